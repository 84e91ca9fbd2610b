// Installation parameters as unknowns (gnss.estimate_lever_arm, gnss.estimate_time_offset;
// factors/gnss_installation.h; the IMU scale factors with filter.scale_factors) on a
// simulated flight whose receiver reports the antenna 0.15 s late, whose antenna sits 0.3 m
// from the IMU on each axis and whose gyros and accelerometers have 2000 ppm scale-factor
// errors, while the configuration starts from none of them: the batch recovers each within
// 3 sigma with a sigma that means something, the filter too (looser), the normalized errors
// over seeds have an RMS near 1, a record without the motion that observes a parameter
// leaves its sigma at the prior, and with the estimation off nothing is added.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "core/config/yaml_config.h"
#include "core/sim/scenario.h"
#include "core/units.h"
#include "problems/gnss_ins/batch.h"
#include "problems/gnss_ins/filter.h"
#include "problems/gnss_ins/initial_state.h"
#include "problems/gnss_ins/run.h"
#include "problems/gnss_ins/sim_config.h"
#include "problems/ins/nav_error.h"
#include "tests/problems/gnss_ins/sim_record.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_installation_test {

// A 120 s flight: a turn, an acceleration, wing rock (roll and pitch), S-turns, a
// deceleration and a turn back: rotations about every body axis (the lever arm) and
// changes of speed and course (the time offset). 100 Hz IMU whose errors the 21-state model
// covers (constant biases and scale factors, white noise), 5 Hz GNSS 1 m / 2 m, 0.05 m/s.
constexpr const char* kScenario = R"(name: installation-flight
description: GNSS lever arm and latency as unknowns
start: {lat_deg: 37.45, lon_deg: 126.65, h_m: 300}
trajectory:
  initial: {speed_mps: 20, heading_deg: 30}
  segments:
    - {kind: cruise, duration_s: 10}
    - {kind: turn, duration_s: 15, heading_change_deg: 90}
    - {kind: accelerate, duration_s: 10, speed_mps: 30}
    - {kind: wing_rock, duration_s: 20, roll_amplitude_deg: 15, roll_frequency_hz: 0.25, pitch_amplitude_deg: 5, pitch_frequency_hz: 0.2}
    - {kind: s_turns, duration_s: 30, heading_amplitude_deg: 30, period_s: 15}
    - {kind: decelerate, duration_s: 10, speed_mps: 20}
    - {kind: turn, duration_s: 15, heading_change_deg: -90}
    - {kind: cruise, duration_s: 10}
imu:
  rate_hz: 100
  errors:
    gyro: {bias_deg_h: 10, arw_deg_sqrt_h: 0.3, scale_factor_fixed_ppm: [2000, -2000, 2000]}
    accel: {bias_ug: 1000, vrw_m_s_sqrt_h: 0.1, scale_factor_fixed_ppm: [-2000, 2000, 2000]}
gnss: {rate_hz: 5, position_sigma_m: [1.0, 2.0], velocity_sigma_mps: 0.05, lever_arm_b_m: [0.3, -0.3, -0.3], latency_s: 0.15}
)";

/// The unknowns: the four GNSS installation parameters (the GNSS source's auxiliary states):
/// lever arm x, y, z (m), time offset (s); then the IMU scale factors (dimensionless).
constexpr int kInstallation = 4;
constexpr int kUnknowns = 10;
const char* const kNames[kUnknowns] = {"gnss_lever_arm_x_m", "gnss_lever_arm_y_m", "gnss_lever_arm_z_m",
                                       "gnss_time_offset_s", "gyro_scale_x",       "gyro_scale_y",
                                       "gyro_scale_z",       "accel_scale_x",      "accel_scale_y",
                                       "accel_scale_z"};
using Vector10d = Eigen::Matrix<double, kUnknowns, 1>;

/// The simulated truth of the unknowns (errors.yaml).
Vector10d Truth(const test_records::SimRecord& r) {
  Vector10d x;
  x.head<3>() = test_records::Vec3(r.errors["gnss"]["lever_arm_b_m"]);
  x[3] = r.errors["gnss"]["latency_s"].as<double>();
  const YAML::Node imu = r.errors["imu"]["errors"];
  x.segment<3>(4) = test_records::Vec3(imu["gyro"]["scale_factor_ppm"]) * kPpm;
  x.segment<3>(7) = test_records::Vec3(imu["accel"]["scale_factor_ppm"]) * kPpm;
  return x;
}

/// The prior std of the scale factors: 5000 ppm, a MEMS datasheet's initial tolerance.
constexpr double kScalePriorStd = 5000.0 * kPpm;

/// The scenario's sensors as a user would describe them, who knows neither the lever arm nor
/// the latency: both estimated from 0 with the default priors (0.5 m, 0.2 s).
GnssInsConfig Config(const test_records::SimRecord& r) {
  GnssInsConfig c;
  c.imu_noise.gyro_arw_rad_per_sqrt_s = 0.3 * kDegPerSqrtHour_radpsqrts;
  c.imu_noise.accel_vrw_mps_per_sqrt_s = 0.1 * kMpsPerSqrtHour_mpspsqrts;
  c.imu_noise.gyro_bias_std_radps = 10.0 * kDegPerHour_radps;
  c.imu_noise.accel_bias_std_mps2 = 1000.0 * kMicroG_mps2;
  c.imu_noise.correlation_time_s = std::numeric_limits<double>::infinity();
  c.imu_noise.gyro_scale_std = kScalePriorStd;
  c.imu_noise.accel_scale_std = kScalePriorStd;
  c.filter.scale_factors = true;
  c.init.source = InitConfig::Source::kGiven;
  c.init.state = InsState{r.init, ImuErrors{}};
  c.init.std.pos_ned_m = Eigen::Vector3d(2.0, 2.0, 3.0);
  c.init.std.vel_ned_mps.setConstant(0.2);
  c.init.std.att_rad = Eigen::Vector3d(1.0, 1.0, 3.0) * kDegToRad;
  c.gnss.estimate_lever_arm = true;
  c.gnss.estimate_time_offset = true;
  return c;
}

struct Estimate {
  Vector10d value = Vector10d::Constant(std::nan(""));
  Vector10d std = Vector10d::Constant(std::nan(""));
};

/// The unknowns at the end of a solution, the auxiliary ones found by name.
Estimate AtEnd(const Solution& s) {
  Estimate e;
  const NavEpoch& last = s.epochs.back();
  if (last.std.size() == ins::err::kSize21) {
    e.value.segment<3>(4) = last.state.imu.sg;
    e.value.segment<3>(7) = last.state.imu.sa;
    e.std.segment<3>(4) = last.std.segment<3>(ins::err::kSg);
    e.std.segment<3>(7) = last.std.segment<3>(ins::err::kSa);
  }
  for (int k = 0; k < kInstallation; ++k) {
    for (std::size_t i = 0; i < s.aux_states.size(); ++i) {
      if (s.aux_states[i].name != kNames[k]) continue;
      e.value[k] = last.aux[static_cast<Eigen::Index>(i)];
      e.std[k] = last.aux_std[static_cast<Eigen::Index>(i)];
    }
  }
  return e;
}

struct SeedResult {
  Vector10d truth;
  Estimate filter, batch;
};

/// Filter and batch on `scenario` simulated with `seed` (perfect: no sensor errors; the
/// lever arm and the latency stay).
SeedResult RunSeed(const sim::Scenario& scenario, std::uint64_t seed, bool perfect = false,
                   bool variance_components = true) {
  const test_records::SimRecord r = test_records::SimulateRecord(scenario, seed, perfect);
  GnssInsConfig c = Config(r);
  c.batch.variance_components = variance_components;
  const FilterResult f = RunFilter(r.inputs, c, false, {}, nullptr);
  const Solution b = RunBatch(r.inputs, c, f.filter, nullptr);
  return {Truth(r), AtEnd(f.filter), AtEnd(b)};
}

void Print(const char* what, const Estimate& e, const Vector10d& truth) {
  for (int k = 0; k < kUnknowns; ++k) {
    std::printf("%s %s: %.6g +- %.3g (true %.6g, normalized error %.2f)\n", what, kNames[k], e.value[k], e.std[k],
                truth[k], (e.value[k] - truth[k]) / e.std[k]);
  }
}

/// Seed 1, kept for the suite.
class Installation : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scenario_ = new sim::Scenario(sim::ParseScenario(ParseYaml(kScenario, "installation scenario")));
    result_ = new SeedResult(RunSeed(*scenario_, 1));
  }
  static void TearDownTestSuite() {
    delete result_;
    delete scenario_;
  }
  static sim::Scenario* scenario_;
  static SeedResult* result_;
};
sim::Scenario* Installation::scenario_ = nullptr;
SeedResult* Installation::result_ = nullptr;

// The batch's estimate of the installation is within 3 sigma of the truth, and its sigma is
// below a third of the true value (0.3 m, 0.15 s): the estimate then tells the parameter
// from zero at 3 sigma, which is what makes the number mean something. Measured: sigma
// 0.06 m on x (seen through pitch changes and turns only, and along the track tied to tau
// v), 0.01 m on y and z, 2.2 ms on tau.
// The scale factors are weakly observable in two minutes: 2000 ppm of a 90 degree turn is
// 0.18 degree of heading, of a 1 m/s^2 acceleration 2 mm/s^2. Each sigma must be below half
// the prior's (the record observes it), the gyro x one (wing rock, +-15 degree of roll)
// below a third of the true value. Measured sigma: gyro 300 / 1080 / 910 ppm, accelerometer
// 1720 / 2060 / 680 ppm (prior 5000). Their recovery within 3 sigma is checked over the
// seeds below (seed 1 has gyro z at 3.1 sigma, one of ten parameters; over 20 seeds its
// normalized error has RMS 1.17).
TEST_F(Installation, BatchRecoversLeverArmAndTimeOffsetWithAMeaningfulSigma) {
  const SeedResult& r = *result_;
  Print("batch", r.batch, r.truth);
  for (int k = 0; k < kUnknowns; ++k) {
    SCOPED_TRACE(kNames[k]);
    ASSERT_TRUE(std::isfinite(r.batch.value[k]) && r.batch.std[k] > 0.0);
    if (k < kInstallation) {
      EXPECT_LT(std::abs(r.batch.value[k] - r.truth[k]), 3.0 * r.batch.std[k]);
      EXPECT_LT(r.batch.std[k], std::abs(r.truth[k]) / 3.0);
    } else {
      EXPECT_LT(r.batch.std[k], 0.5 * kScalePriorStd);
    }
  }
  EXPECT_LT(r.batch.std[4], std::abs(r.truth[4]) / 3.0) << kNames[4];
}

// The filter's estimate at the end of the record: it linearized each fix once, at the
// estimate of the moment (at first far from the truth), so it is held to a looser bound:
// within 4 sigma, sigma below half the true value; the scale factors' sigma as the batch's.
// (Measured: as close as the batch's, the parameters being constants that every fix
// updates.)
TEST_F(Installation, FilterEstimatesThemToo) {
  const SeedResult& r = *result_;
  Print("filter", r.filter, r.truth);
  for (int k = 0; k < kUnknowns; ++k) {
    SCOPED_TRACE(kNames[k]);
    ASSERT_TRUE(std::isfinite(r.filter.value[k]) && r.filter.std[k] > 0.0);
    EXPECT_LT(std::abs(r.filter.value[k] - r.truth[k]), 4.0 * r.filter.std[k]);
    if (k < kInstallation) {
      EXPECT_LT(r.filter.std[k], std::abs(r.truth[k]) / 2.0);
    } else {
      EXPECT_LT(r.filter.std[k], 0.5 * kScalePriorStd);
    }
  }
}

// Without sensor errors what is left is the models' own error (the Taylor series in tau cut
// off, the motion inputs taken from a window of IMU samples): it must bias no parameter by
// more than half its sigma (the variance components are off: with noise-free fixes they
// would shrink the sigmas to the model error). Measured 0.2 to 0.33 sigma; without the jerk
// terms (second order in the IMU's velocity) the turns' along-track residual of ~1 mm/s
// moved l_z by 2.9 sigma.
TEST_F(Installation, PerfectSensorsLeaveOnlyASmallModelBias) {
  const SeedResult r = RunSeed(*scenario_, 1, /*perfect=*/true, /*variance_components=*/false);
  Print("perfect batch", r.batch, r.truth);
  for (int k = 0; k < kUnknowns; ++k) {
    SCOPED_TRACE(kNames[k]);
    EXPECT_LT(std::abs(r.batch.value[k] - r.truth[k]), 0.5 * r.batch.std[k]);
    EXPECT_LT(std::abs(r.filter.value[k] - r.truth[k]), 0.5 * r.filter.std[k]);
  }
}

/// Normalized errors (estimate - truth) / sigma of one method over the seeds, per unknown.
struct NormalizedErrors {
  std::vector<double> z[kUnknowns];
  void Add(const Estimate& e, const Vector10d& truth) {
    for (int k = 0; k < kUnknowns; ++k) z[k].push_back((e.value[k] - truth[k]) / e.std[k]);
  }
  double Mean(int k) const {
    double sum = 0.0;
    for (const double x : z[k]) sum += x;
    return sum / static_cast<double>(z[k].size());
  }
  double Rms(int k) const {
    double sum = 0.0;
    for (const double x : z[k]) sum += x * x;
    return std::sqrt(sum / static_cast<double>(z[k].size()));
  }
  /// The fraction of all normalized errors (every parameter, every seed) within 3.
  double WithinThree() const {
    std::size_t in = 0, all = 0;
    for (int k = 0; k < kUnknowns; ++k) {
      for (const double x : z[k]) in += std::abs(x) < 3.0 ? 1 : 0;
      all += z[k].size();
    }
    return static_cast<double>(in) / static_cast<double>(all);
  }
  double PooledRms() const {
    double sum = 0.0;
    for (int k = 0; k < kUnknowns; ++k) sum += Rms(k) * Rms(k);
    return std::sqrt(sum / kUnknowns);
  }
  void Print(const char* method) const {
    for (int k = 0; k < kUnknowns; ++k) {
      std::printf("%s %s: normalized error mean %+.2f RMS %.2f over %zu seeds\n", method, kNames[k], Mean(k), Rms(k),
                  z[k].size());
    }
    std::printf("%s: pooled RMS %.2f, %.1f %% within 3 sigma\n", method, PooledRms(), 100.0 * WithinThree());
  }
};

/// The number of seeds: NAVTWIN_INSTALLATION_SEEDS when set (docs/gnss-ins.md reports 50),
/// else 20 (1.3 s each).
int Seeds() {
  constexpr int kSeeds = 20;
  const char* env = std::getenv("NAVTWIN_INSTALLATION_SEEDS");
  return env != nullptr && std::atoi(env) > 0 ? std::atoi(env) : kSeeds;
}

// Over the seeds (noise, IMU biases drawn anew; the same installation and scale factors),
// the normalized errors of an honest sigma have an RMS of 1. With 20 seeds and 10 parameters
// (correlated: x with tau, the scale factors with the attitude) a single parameter's RMS
// scatters by about 0.16, the pooled one by less; the bands (0.7-1.4 pooled, 0.5-1.6 each,
// filter pooled 0.7-1.5) catch a sigma wrong by 40 % and a bias of about a sigma. Measured
// over 50 seeds: pooled 1.06 (batch and filter), 99.2 % within 3 sigma, each parameter's
// RMS 0.91-1.25; means -0.25 (x), +0.29 (y), +0.61 (z), -0.29 (tau), the models' bias of
// the perfect-sensor test, and -0.40..+0.33 for the scale factors.
TEST_F(Installation, NormalizedErrorsOverSeedsHaveAnRmsNearOne) {
  const int seeds = Seeds();
  NormalizedErrors batch, filter;
  for (int seed = 1; seed <= seeds; ++seed) {
    const SeedResult r = seed == 1 ? *result_ : RunSeed(*scenario_, static_cast<std::uint64_t>(seed));
    batch.Add(r.batch, r.truth);
    filter.Add(r.filter, r.truth);
  }
  batch.Print("batch");
  filter.Print("filter");
  EXPECT_GT(batch.PooledRms(), 0.7);
  EXPECT_LT(batch.PooledRms(), 1.4);
  for (int k = 0; k < kUnknowns; ++k) {
    EXPECT_GT(batch.Rms(k), 0.5) << kNames[k];
    EXPECT_LT(batch.Rms(k), 1.6) << kNames[k];
  }
  EXPECT_GT(filter.PooledRms(), 0.7);
  EXPECT_LT(filter.PooledRms(), 1.5);
  // Within 3 sigma: 99.7 % for an honest Gaussian sigma; 95 % fails a sigma 40 % too small
  // (then 7 % fall outside).
  EXPECT_GE(batch.WithinThree(), 0.95);
  EXPECT_GE(filter.WithinThree(), 0.95);
}

/// RMS of the 3-D position error of a solution's epochs against the truth.
double PositionRms(const Solution& s, const std::vector<NavState>& truth) {
  NavErrorStats stats;
  for (const NavEpoch& e : s.epochs) stats.Add(CompareNav(e.state.nav, test_records::TruthAt(truth, e.state.nav.t_s)));
  return std::sqrt(stats.Rms(0) * stats.Rms(0) + stats.Rms(1) * stats.Rms(1) + stats.Rms(2) * stats.Rms(2));
}

// With the estimation off nothing is added (no auxiliary state, the models of
// gnss_position.h / gnss_velocity.h); a configured time offset is applied as a known value.
// Ignoring the 0.15 s latency puts the solution v tau = 3 to 4.5 m behind the truth; the
// installation given exactly, or estimated, brings the batch's position error near the
// fixes' 1 m / 2 m noise averaged (measured 3.6 m ignored, 0.12 m known, 0.12 m estimated).
TEST_F(Installation, IgnoringTheLatencyCostsMetresEstimatingItCostsLittle) {
  const test_records::SimRecord r = test_records::SimulateRecord(*scenario_, 1);
  const auto batch_error = [&](const GnssInsConfig& c, std::size_t expected_aux) {
    const FilterResult f = RunFilter(r.inputs, c, false, {}, nullptr);
    const Solution b = RunBatch(r.inputs, c, f.filter, nullptr);
    EXPECT_EQ(f.filter.aux_states.size(), expected_aux);
    EXPECT_EQ(b.aux_states.size(), expected_aux);
    return PositionRms(b, r.truth);
  };
  GnssInsConfig ignored = Config(r);
  ignored.gnss.estimate_lever_arm = false;
  ignored.gnss.estimate_time_offset = false;
  GnssInsConfig known = ignored;
  known.installation.antenna_lever_arm_b_m = Truth(r).head<3>();
  known.gnss.time_offset_s = Truth(r)[3];
  const double e_ignored = batch_error(ignored, 0), e_known = batch_error(known, 0);
  const double e_estimated = batch_error(Config(r), kInstallation);
  std::printf("batch position RMS: installation ignored %.3f m, known %.3f m, estimated %.3f m\n", e_ignored, e_known,
              e_estimated);
  EXPECT_GT(e_ignored, 2.0);
  EXPECT_LT(e_known, 0.5);
  EXPECT_LT(e_estimated, 1.5 * e_known);
}

// The filter's reset to GNSS (after rejections in a row) puts the antenna the models predict
// on the fix, carried forward by the time offset: with a gate that rejects nearly every
// update the filter lives on resets (each puts the position on one fix: RMS about the fixes'
// sqrt(1 + 1 + 4) = 2.4 m); measured 2.3 m, and 4.4 m with tau left out of the reset (the
// position v tau = 3 to 4.5 m behind), which the 3 m bound separates.
TEST_F(Installation, ResetsCarryTheFixForwardByTheTimeOffset) {
  const test_records::SimRecord r = test_records::SimulateRecord(*scenario_, 1);
  GnssInsConfig c = Config(r);
  c.gnss.estimate_lever_arm = false;
  c.gnss.estimate_time_offset = false;
  c.installation.antenna_lever_arm_b_m = Truth(r).head<3>();
  c.gnss.time_offset_s = Truth(r)[3];
  c.filter.gate_probability = 1e-6;
  const FilterResult f = RunFilter(r.inputs, c, false, {}, nullptr);
  const double rms = PositionRms(f.filter, r.truth);
  std::printf("filter living on resets: %zu resets, position RMS %.3f m\n", f.filter.counts.at("gnss_reset").used, rms);
  EXPECT_GT(f.filter.counts.at("gnss_reset").used, 10u);
  EXPECT_LT(rms, 3.0);
}

// A straight, level, steady flight observes neither the lever arm (no rotation: R_n_b l_b is
// a constant offset of the position) nor the time offset (tau v likewise), once the initial
// position is not known better than the fixes: the posterior sigma stays at the prior, which
// the run reports as "not observable" (run.cc).
TEST(InstallationObservability, ASteadyFlightLeavesTheParametersAtTheirPrior) {
  const std::string full = kScenario;
  const std::string text = full.substr(0, full.find("  segments:")) +
                           "  segments:\n    - {kind: cruise, duration_s: 60}\n" + full.substr(full.find("imu:"));
  const sim::Scenario scenario = sim::ParseScenario(ParseYaml(text, "steady flight"));
  const test_records::SimRecord r = test_records::SimulateRecord(scenario, 1);
  GnssInsConfig c = Config(r);
  c.init.std.pos_ned_m.setConstant(100.0);
  const FilterResult f = RunFilter(r.inputs, c, false, {}, nullptr);
  const Solution b = RunBatch(r.inputs, c, f.filter, nullptr);
  const Eigen::Vector4d prior(0.5, 0.5, 0.5, 0.2);
  const Estimate eb = AtEnd(b), ef = AtEnd(f.filter);
  Print("steady batch", eb, Truth(r));
  Print("steady filter", ef, Truth(r));
  for (int k = 0; k < kInstallation; ++k) {
    SCOPED_TRACE(kNames[k]);
    EXPECT_GE(eb.std[k], 0.9 * prior[k]);
    EXPECT_GE(ef.std[k], 0.9 * prior[k]);
  }
  GnssInsRun run;
  run.prior_std = InitialStdVector(c, ins::err::kSize21);
  run.methods.push_back({"filter", f.filter, std::nullopt, ""});
  run.methods.push_back({"batch", b, std::nullopt, ""});
  RunOptions options;
  const std::string table = RunTable(options, run);
  std::printf("%s", table.c_str());
  EXPECT_NE(table.find("gnss_lever_arm_z_m at the end: filter not observable batch not observable"),
            std::string::npos);
  EXPECT_NE(table.find("it needs rotation about the body x and y axes (roll and pitch changes)"), std::string::npos);
  // The scale factors: straight and level, no rotation but the Earth's.
  EXPECT_NE(table.find("gyro_scale_z at the end: filter not observable batch not observable"), std::string::npos);
  EXPECT_NE(table.find("not observable from this record: posterior sigma >= 0.9 x prior sigma 5000 ppm; it needs "
                       "rotation about the body z axis (turns)"),
            std::string::npos);
  std::ostringstream json;
  JsonWriter w(json);
  WriteRunSummary(w, options, run);
  EXPECT_NE(json.str().find("\"gnss_time_offset_s\":{\"value\""), std::string::npos) << json.str();
  EXPECT_NE(json.str().find("\"imu_scale_factors\":{\"gyro_scale_x\":{\"value\""), std::string::npos);
  // Every installation parameter is unobservable (the accelerometer z scale factor is not:
  // gravity on a z bias known to 1000 ug observes it to 980 ppm).
  const std::string summary = json.str();
  for (std::size_t at = summary.find("\"aux\":{"); at != std::string::npos; at = summary.find("\"aux\":{", at + 1)) {
    const std::string aux = summary.substr(at, summary.find("\"imu_scale_factors\"", at) - at);
    EXPECT_NE(aux.find("\"observable\":false"), std::string::npos) << aux;
    EXPECT_EQ(aux.find("\"observable\":true"), std::string::npos) << aux;
  }
}

// The demo's configuration (navtwin smooth --demo) gives a simulated latency as the known
// time offset, as it gives the lever arm; without a latency it writes no gnss section.
TEST(InstallationDemoConfig, CarriesTheSimulatedLatency) {
  const sim::Scenario with = sim::ParseScenario(ParseYaml(kScenario, "installation scenario"));
  const std::string yaml = ConfigYamlForSimulation(with, "", 1, "off");
  EXPECT_NE(yaml.find("gnss:\n  time_offset_s: 0.15"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("antenna_lever_arm_b_m: [0.3, -0.3, -0.3]"), std::string::npos) << yaml;
  std::string text = kScenario;
  text.replace(text.find(", latency_s: 0.15"), std::string(", latency_s: 0.15").size(), "");
  const sim::Scenario without = sim::ParseScenario(ParseYaml(text, "no latency"));
  EXPECT_EQ(ConfigYamlForSimulation(without, "", 1, "off").find("gnss:"), std::string::npos);
}

}  // namespace gnss_ins_installation_test
}  // namespace navtwin::gnss_ins
