// Consistency of the navigation filter (problems/gnss_ins/filter.h): the normalised
// estimation error squared (NEES) of the 15-state error over 50 Monte Carlo runs of a
// simulated flight must fall within the two-sided 95 % chi-square bounds.
#include <stdlib.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "core/io/open.h"
#include "core/rotation.h"
#include "core/sim/scenario.h"
#include "core/sim/simulator.h"
#include "core/config/yaml_config.h"
#include "core/units.h"
#include "problems/ins/error_dynamics.h"
#include "problems/gnss_ins/filter.h"
#include "problems/ins/nav_error.h"
#include "solvers/eskf.h"
#include "tests/problems/gnss_ins/sim_record.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_nees_test {

// A 150 s flight with turns, a climb and S-turns, and sensors whose errors the 15-state
// model covers exactly: constant biases (drawn per run) and white noise, no scale factors,
// misalignments, anti-alias filter or iron. 100 Hz IMU, 5 Hz GNSS with velocity and a
// lever arm, 10 Hz magnetometer vector.
constexpr const char* kNeesScenario = R"(name: nees-flight
description: NEES Monte Carlo - errors inside the 15-state model
start: {lat_deg: 36.5, lon_deg: 127.4, h_m: 800}
trajectory:
  initial: {speed_mps: 50, heading_deg: 20}
  segments:
    - {kind: cruise, duration_s: 15}
    - {kind: turn, duration_s: 20, heading_change_deg: 90}
    - {kind: climb, duration_s: 15, vertical_speed_mps: 4}
    - {kind: s_turns, duration_s: 40, heading_amplitude_deg: 25, period_s: 20}
    - {kind: turn, duration_s: 20, heading_change_deg: -120}
    - {kind: accelerate, duration_s: 15, speed_mps: 60}
    - {kind: cruise, duration_s: 25}
imu:
  rate_hz: 100
  errors:
    gyro: {bias_deg_h: 20, arw_deg_sqrt_h: 0.5}
    accel: {bias_ug: 2000, vrw_m_s_sqrt_h: 0.1}
gnss: {rate_hz: 5, position_sigma_m: [1.5, 3.0], velocity_sigma_mps: 0.05, lever_arm_b_m: [0.3, 0.0, -0.5]}
mag: {rate_hz: 10, declination_deg: -8.0, noise_uT: 0.3}
)";

constexpr int kRuns = 50;

struct RunNees {
  std::vector<double> filter;  ///< NEES at each check epoch
  std::vector<double> rts;
};

/// One Monte Carlo run: simulate with `seed`, start from the truth perturbed by a draw from
/// the initial covariance, and compute the NEES at the check epochs.
RunNees OneRun(const sim::Scenario& scenario, std::uint64_t seed, const std::vector<double>& check_s) {
  const test_records::SimRecord r = test_records::SimulateRecord(scenario, seed);
  const Inputs& in = r.inputs;
  const std::vector<NavState>& truth = r.truth;
  const YAML::Node& errors = r.errors;

  // The true IMU errors of this run (constant biases).
  ImuErrors true_imu;
  true_imu.bg_radps = test_records::Vec3(errors["imu"]["errors"]["gyro"]["bias_deg_h"]) * kDegPerHour_radps;
  true_imu.ba_mps2 = test_records::Vec3(errors["imu"]["errors"]["accel"]["bias_ug"]) * kMicroG_mps2;

  // The model of the scenario's sensors, taken honestly from its parameters.
  GnssInsConfig c;
  c.imu_noise.gyro_arw_rad_per_sqrt_s = 0.5 * kDegToRad / 60.0;
  c.imu_noise.accel_vrw_mps_per_sqrt_s = 0.1 / 60.0;
  c.imu_noise.gyro_bias_std_radps = 20.0 * kDegPerHour_radps;
  c.imu_noise.accel_bias_std_mps2 = 2000.0 * kMicroG_mps2;
  c.imu_noise.correlation_time_s = std::numeric_limits<double>::infinity();  // constants
  c.installation.antenna_lever_arm_b_m = Eigen::Vector3d(0.3, 0.0, -0.5);
  c.mag.mode = MagConfig::Mode::kVector;
  c.mag.field_ned_uT = test_records::Vec3(errors["mag"]["field_ned_uT"]);
  c.mag.noise_uT = 0.3;
  c.init.std.pos_ned_m = Eigen::Vector3d(3.0, 3.0, 5.0);
  c.init.std.vel_ned_mps.setConstant(0.3);
  c.init.std.att_rad = Eigen::Vector3d(1.0, 1.0, 3.0) * kDegToRad;
  // Initial error drawn from the initial covariance (the biases are drawn by the simulator
  // with the same sigmas), so that the NEES is chi-square from the start.
  const Eigen::VectorXd std0 = InitialStdVector(c, err::kSize15);
  std::mt19937 rng(static_cast<unsigned>(1000 + seed));
  std::normal_distribution<double> normal;
  Eigen::VectorXd dx0(15);
  for (int i = 0; i < 9; ++i) dx0[i] = std0[i] * normal(rng);
  dx0.tail<6>().setZero();  // the estimate starts at zero biases; the truth has the drawn ones
  InsState x0{truth.front(), ImuErrors{}};
  x0 = ApplyCorrection(x0, -dx0);  // error = truth - estimate = dx0
  c.init.state = x0;

  const FilterResult result = RunFilter(in, c, true, {}, nullptr, FilterKnots::kAllWithCovariances);
  RunNees out;
  for (const double t : check_s) {
    const std::vector<NavEpoch>& knots = result.filter.epochs;
    std::size_t k = 0;
    while (k < knots.size() && std::abs(knots[k].state.nav.t_s - t) > 1e-6) ++k;
    if (k == knots.size()) throw std::runtime_error("no knot at a check epoch");
    NavState truth_nav = truth.front();
    for (const NavState& s : truth) {
      if (std::abs(s.t_s - t) < 1e-6) truth_nav = s;
    }
    const InsState x_true{truth_nav, true_imu};
    const Eigen::VectorXd e = StateDifference(x_true, knots[k].state, err::kSize15);
    out.filter.push_back(e.dot(result.filter_covariances[k].ldlt().solve(e)));
    const Eigen::VectorXd es = StateDifference(x_true, result.rts->epochs[k].state, err::kSize15);
    out.rts.push_back(es.dot(result.rts_covariances[k].ldlt().solve(es)));
  }
  return out;
}

TEST(GnssInsFilterNees, FiftyRunsWithinChiSquareBounds) {
  const sim::Scenario scenario = sim::ParseScenario(ParseYaml(kNeesScenario, "nees scenario"));
  // Epochs in the turns, the climb, the S-turns and the cruise (GNSS epochs: knots).
  const std::vector<double> check_s = {10.0, 30.0, 50.0, 80.0, 110.0, 140.0};
  std::vector<double> mean(check_s.size(), 0.0), mean_rts(check_s.size(), 0.0);
  for (int run = 1; run <= kRuns; ++run) {
    const RunNees n = OneRun(scenario, static_cast<std::uint64_t>(run), check_s);
    for (std::size_t i = 0; i < check_s.size(); ++i) {
      mean[i] += n.filter[i] / kRuns;
      mean_rts[i] += n.rts[i] / kRuns;
    }
  }
  // The sum over runs of a consistent filter's NEES is chi-square with 50 x 15 dof: the
  // average lies within [q(0.025), q(0.975)] / 50 with 95 % probability at each epoch.
  // Checking six epochs against those bounds would fail a perfectly consistent filter one
  // time in four (1 - 0.95^6); the assertion uses the Bonferroni bounds instead
  // (two-sided 1 - 0.05 / 6 per epoch, 95 % for the six together), and the figures show
  // the per-epoch 95 % bounds as well.
  const int dof = kRuns * err::kSize15;
  const double lo = ChiSquareQuantile(0.025, dof) / kRuns;
  const double hi = ChiSquareQuantile(0.975, dof) / kRuns;
  const double tail = 0.025 / static_cast<double>(check_s.size());
  const double lo_family = ChiSquareQuantile(tail, dof) / kRuns;
  const double hi_family = ChiSquareQuantile(1.0 - tail, dof) / kRuns;
  std::printf("[ figures  ] average NEES over %d runs, 15 states (95 %% bounds per epoch %.2f .. %.2f, "
              "for the %zu epochs together %.2f .. %.2f):\n",
              kRuns, lo, hi, check_s.size(), lo_family, hi_family);
  for (std::size_t i = 0; i < check_s.size(); ++i) {
    std::printf("             t = %5.1f s: filter %.2f, rts %.2f\n", check_s[i], mean[i], mean_rts[i]);
    EXPECT_GT(mean[i], lo_family) << "t = " << check_s[i];
    EXPECT_LT(mean[i], hi_family) << "t = " << check_s[i];
  }
}

}  // namespace gnss_ins_nees_test
}  // namespace navtwin::gnss_ins
