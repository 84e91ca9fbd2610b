// Aiding and reference streams: epochs, interpolation of the truth, GNSS geometry and error
// statistics, magnetometer field and iron, barometer and ISA, master INS delay and errors,
// configuration parsing. Random tests use fixed seeds.
#include "core/sim/aiding.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/io/input_error.h"
#include "core/rotation.h"

namespace navtwin::sim {
namespace sim_aiding_test {

const wgs84::Geodetic kStart{37.5 * kDegToRad, 127.0 * kDegToRad, 300.0};

/// Fast manoeuvres: roll +-29 deg at 1 Hz, pitch +-17 deg at 0.7 Hz, yaw +-23 deg at
/// 0.5 Hz (angular rates to 3 rad/s, angular accelerations to 20 rad/s^2), 50 m/s.
class Wobble : public AnalyticTrajectory {
 public:
  Eigen::Vector3d Euler_rad(double t) const override {
    return {0.5 * std::sin(kW1 * t), 0.3 * std::sin(kW2 * t), 1.0 + 0.4 * std::sin(kW3 * t)};
  }
  Eigen::Vector3d EulerRate_radps(double t) const override {
    return {0.5 * kW1 * std::cos(kW1 * t), 0.3 * kW2 * std::cos(kW2 * t),
            0.4 * kW3 * std::cos(kW3 * t)};
  }
  Eigen::Vector3d Velocity_n_mps(double t) const override {
    return {50.0 + 5.0 * std::sin(kW3 * t), 10.0 * std::cos(kW2 * t), 2.0 * std::sin(kW1 * t)};
  }
  Eigen::Vector3d Acceleration_n_mps2(double t) const override {
    return {5.0 * kW3 * std::cos(kW3 * t), -10.0 * kW2 * std::sin(kW2 * t),
            2.0 * kW1 * std::cos(kW1 * t)};
  }

 private:
  static constexpr double kW1 = 2.0 * M_PI * 1.0;
  static constexpr double kW2 = 2.0 * M_PI * 0.7;
  static constexpr double kW3 = 2.0 * M_PI * 0.5;
};

std::vector<TruthSample> TruthStream(const AnalyticTrajectory& trajectory, double rate_hz,
                                     double duration_s) {
  TruthGenerator generator(trajectory, kStart, rate_hz);
  std::vector<TruthSample> out{generator.current()};
  const long n = std::lround(duration_s * rate_hz);
  for (long k = 0; k < n; ++k) out.push_back(generator.Next());
  return out;
}

/// A vehicle at rest at kStart with attitude (roll, pitch, yaw), sampled at rate_hz.
std::vector<TruthSample> StaticStream(double rate_hz, long count,
                                      const Eigen::Vector3d& euler = Eigen::Vector3d::Zero()) {
  std::vector<TruthSample> out(static_cast<std::size_t>(count));
  for (long k = 0; k < count; ++k) {
    TruthSample& s = out[static_cast<std::size_t>(k)];
    s.t_s = k / rate_hz;
    s.state.t_s = s.t_s;
    s.state.lat_rad = kStart.lat_rad;
    s.state.lon_rad = kStart.lon_rad;
    s.state.h_m = kStart.h_m;
    s.state.q_n_b = QuatFromEuler(euler.x(), euler.y(), euler.z());
    s.omega_ib_b_radps = s.state.q_n_b.conjugate() * wgs84::EarthRateNed(kStart.lat_rad);
  }
  return out;
}

Eigen::Vector3d OffsetNed(const GnssSample& g, const GnssSample& reference) {
  return wgs84::GeodeticToNed({g.lat_rad, g.lon_rad, g.h_m},
                              {reference.lat_rad, reference.lon_rad, reference.h_m});
}

template <typename Sample, typename Model>
std::vector<Sample> Feed(Model& model, const std::vector<TruthSample>& truth) {
  std::vector<Sample> out;
  for (const TruthSample& t : truth) {
    if (auto s = model.Push(t)) out.push_back(*s);
  }
  return out;
}

/// Sample standard deviation of each column.
Eigen::Vector3d StdDev(const std::vector<Eigen::Vector3d>& v) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), sq = Eigen::Vector3d::Zero();
  for (const auto& x : v) mean += x;
  mean /= static_cast<double>(v.size());
  for (const auto& x : v) sq += (x - mean).cwiseAbs2();
  return (sq / static_cast<double>(v.size() - 1)).cwiseSqrt();
}

ConfigNode Yaml(const std::string& text) { return ParseYaml(text, "aiding.yaml"); }

template <typename F>
void ExpectConfigError(F f, const std::string& part) {
  try {
    f();
    ADD_FAILURE() << "no InputError for " << part;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

// -------------------------------------------------------------------- interpolation

TEST(AidingTest, InterpolatedTruthMatchesTheTruthBetweenSamples) {
  // Truth at 1 kHz; interpolate between every 10th sample (100 Hz, the slowest internal
  // rate) and compare at the nine samples in between.
  Wobble wobble;
  const std::vector<TruthSample> fine = TruthStream(wobble, 1000.0, 20.0);
  double pos_m = 0, vel_mps = 0, att_rad = 0, omega_radps = 0;
  for (std::size_t k = 0; k + 10 < fine.size(); k += 10) {
    for (std::size_t j = 1; j < 10; ++j) {
      const TruthSample& f = fine[k + j];
      const TruthSample x = InterpolateTruth(fine[k], fine[k + 10], f.t_s);
      pos_m = std::max(pos_m, wgs84::GeodeticToNed({x.state.lat_rad, x.state.lon_rad, x.state.h_m},
                                                   {f.state.lat_rad, f.state.lon_rad, f.state.h_m})
                                  .norm());
      vel_mps = std::max(vel_mps, (x.state.v_n_mps - f.state.v_n_mps).norm());
      att_rad = std::max(att_rad, AttitudeError(f.state.q_n_b, x.state.q_n_b).norm());
      omega_radps = std::max(omega_radps, (x.omega_ib_b_radps - f.omega_ib_b_radps).norm());
    }
  }
  // Cubic Hermite over h = 10 ms: error ~ h^4/384 |y^(4)| (|d3 v/dt3| ~ 2 (2 pi)^3 gives
  // 1e-8 m; |d4 v/dt4| ~ 2 (2 pi)^4 gives 1e-7 m/s). Measured 3.0e-8 m, 1.3e-7 m/s,
  // 2.5e-8 rad, 9.9e-6 rad/s (omega's slope is the truth's finite-difference alpha);
  // bounds with 3-8x margin, far below the 3e-5 rad of a plain slerp (h^2 |alpha| / 8).
  EXPECT_LT(pos_m, 1e-7);
  EXPECT_LT(vel_mps, 1e-6);
  EXPECT_LT(att_rad, 1e-7);
  EXPECT_LT(omega_radps, 5e-5);
}

TEST(AidingTest, InterpolationEndsAreTheSamplesAndBadTimesThrow) {
  Wobble wobble;
  const std::vector<TruthSample> t = TruthStream(wobble, 100.0, 0.02);
  EXPECT_EQ(InterpolateTruth(t[0], t[1], t[0].t_s).state.q_n_b.coeffs(), t[0].state.q_n_b.coeffs());
  EXPECT_EQ(InterpolateTruth(t[0], t[1], t[1].t_s).state.h_m, t[1].state.h_m);
  EXPECT_THROW(InterpolateTruth(t[0], t[1], t[1].t_s + 1e-3), std::invalid_argument);
  EXPECT_THROW(InterpolateTruth(t[1], t[0], t[0].t_s), std::invalid_argument);
}

// --------------------------------------------------------------------------- GNSS

TEST(AidingTest, GnssEpochsFollowRateOffsetAndStart) {
  GnssSimConfig c;
  c.rate_hz = 5.0;
  c.time_offset_s = 0.013;  // between truth samples: interpolated
  c.start_s = 2.0;
  GnssSimulator gnss(c, Rng(1), false);
  const std::vector<GnssSample> out = Feed<GnssSample>(gnss, StaticStream(100.0, 1001));
  // Epochs k/5 + 0.013 in [2, 10]: k = 10 ... 49.
  ASSERT_EQ(out.size(), 40u);
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(out[i].t_s, static_cast<double>(i + 10) / 5.0 + 0.013);
    EXPECT_EQ(out[i].quality, 1);
    EXPECT_EQ(out[i].num_sats, 10);
    EXPECT_TRUE(out[i].has_velocity);
  }
}

TEST(AidingTest, EpochSamplerRejectsRatesAboveTheTruthRate) {
  EpochSampler sampler(200.0, 0.0, 0.0);
  const std::vector<TruthSample> truth = StaticStream(100.0, 3);
  EXPECT_TRUE(sampler.Push(truth[0]).has_value());
  EXPECT_THROW(sampler.Push(truth[1]), std::invalid_argument);
}

TEST(AidingTest, LeverArmMovesTheAntennaExactly) {
  const Eigen::Vector3d arm(1.0, 0.0, 0.0);
  // Yaw 90 deg: the antenna 1 m ahead of the IMU is 1 m east; pitch 90 deg: 1 m up.
  // Through ECEF and back (EcefToGeodetic converges to ~1e-9 m here): 1e-8 m.
  const TruthSample east = StaticStream(1.0, 1, {0.0, 0.0, M_PI / 2})[0];
  const GnssSample imu = AntennaTruth(east, Eigen::Vector3d::Zero());
  EXPECT_LT((OffsetNed(AntennaTruth(east, arm), imu) - Eigen::Vector3d(0, 1, 0)).norm(), 1e-8);
  const TruthSample up = StaticStream(1.0, 1, {0.0, M_PI / 2, 0.0})[0];
  EXPECT_LT((OffsetNed(AntennaTruth(up, arm), imu) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-8);
  // At rest the antenna does not move (the Earth rate in omega_ib cancels).
  EXPECT_LT(AntennaTruth(east, arm).v_n_mps.norm(), 1e-15);
  // Turning at 0.5 rad/s about the vertical at yaw 0: the antenna 1 m ahead (north) moves
  // east at 0.5 m/s. Its NED differs from the IMU's by a rotation about east, which leaves
  // an east velocity unchanged: exact to rounding.
  TruthSample turning = StaticStream(1.0, 1)[0];
  turning.omega_ib_b_radps += Eigen::Vector3d(0.0, 0.0, 0.5);
  EXPECT_LT((AntennaTruth(turning, arm).v_n_mps - Eigen::Vector3d(0, 0.5, 0)).norm(), 1e-12);
}

TEST(AidingTest, PerfectGnssIsTheAntennaTruthAndReportsTheConfiguredSigma) {
  Wobble wobble;
  const std::vector<TruthSample> truth = TruthStream(wobble, 200.0, 10.0);
  GnssSimConfig c;
  c.rate_hz = 10.0;
  c.position_sigma_ned_m = Eigen::Vector3d(1.5, 1.5, 3.0);
  c.lever_arm_b_m = Eigen::Vector3d(0.5, -0.2, -1.0);
  c.outlier_probability = 0.5;
  c.outlier_size_m = 50.0;
  GnssSimulator gnss(c, Rng(7), true);
  const std::vector<GnssSample> out = Feed<GnssSample>(gnss, truth);
  ASSERT_EQ(out.size(), 101u);
  for (const GnssSample& g : out) {
    const std::size_t k = static_cast<std::size_t>(std::lround(g.t_s * 200.0));
    const GnssSample ref = AntennaTruth(truth[k], c.lever_arm_b_m);
    EXPECT_EQ(g.lat_rad, ref.lat_rad);
    EXPECT_EQ(g.h_m, ref.h_m);
    EXPECT_EQ(g.v_n_mps, ref.v_n_mps);
    EXPECT_EQ(g.pos_std_ned_m, c.position_sigma_ned_m);
    EXPECT_EQ(g.vel_std_ned_mps, Eigen::Vector3d::Constant(1e-3));  // 0 configured: the floor
  }
  EXPECT_TRUE(gnss.outliers().empty());
}

TEST(AidingTest, GnssLatencyReportsTheAntennaOfTheEarlierTime) {
  Wobble wobble;
  const std::vector<TruthSample> truth = TruthStream(wobble, 200.0, 10.0);
  GnssSimConfig c;
  c.rate_hz = 10.0;
  c.lever_arm_b_m = Eigen::Vector3d(0.5, -0.2, -1.0);
  c.latency_s = 0.15;  // 30 truth samples
  GnssSimulator gnss(c, Rng(7), true);
  const std::vector<GnssSample> out = Feed<GnssSample>(gnss, truth);
  // Tags k / 10 whose data time t - 0.15 lies in the truth [0, 10]: 0.2 ... 10.
  ASSERT_EQ(out.size(), 99u);
  EXPECT_NEAR(out.front().t_s, 0.2, 1e-12);
  for (const GnssSample& g : out) {
    const std::size_t k = static_cast<std::size_t>(std::lround((g.t_s - c.latency_s) * 200.0));
    const GnssSample ref = AntennaTruth(truth[k], c.lever_arm_b_m);
    EXPECT_EQ(g.lat_rad, ref.lat_rad);
    EXPECT_EQ(g.h_m, ref.h_m);
    EXPECT_EQ(g.v_n_mps, ref.v_n_mps);
  }
  YAML::Emitter e;
  gnss.EmitDrawn(e);
  EXPECT_EQ(YAML::Load(e.c_str())["latency_s"].as<double>(), 0.15);
}

struct GnssErrors {
  std::vector<Eigen::Vector3d> position, velocity;
  std::vector<GnssSample> samples;
};

GnssErrors RunStaticGnss(const GnssSimConfig& c, std::uint64_t seed, long truth_samples) {
  const std::vector<TruthSample> truth = StaticStream(100.0, truth_samples);
  const GnssSample ref = AntennaTruth(truth[0], Eigen::Vector3d::Zero());
  GnssSimulator gnss(c, Rng(seed), false);
  GnssErrors e;
  e.samples = Feed<GnssSample>(gnss, truth);
  for (const GnssSample& g : e.samples) {
    e.position.push_back(OffsetNed(g, ref));
    e.velocity.push_back(g.v_n_mps);
  }
  return e;
}

TEST(AidingTest, GnssNoiseHasTheConfiguredSigma) {
  GnssSimConfig c;
  c.rate_hz = 100.0;
  c.position_sigma_ned_m = Eigen::Vector3d(1.5, 1.5, 3.0);
  c.velocity_sigma_ned_mps = Eigen::Vector3d(0.05, 0.05, 0.1);
  const GnssErrors e = RunStaticGnss(c, 11, 20000);
  ASSERT_EQ(e.samples.size(), 20000u);
  // N = 20000: the relative standard error of a sample sigma is 1/sqrt(2N) = 0.5 %; 3 %
  // is 6 standard errors.
  const Eigen::Vector3d sp = StdDev(e.position), sv = StdDev(e.velocity);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(sp[i] / c.position_sigma_ned_m[i], 1.0, 0.03) << i;
    EXPECT_NEAR(sv[i] / c.velocity_sigma_ned_mps[i], 1.0, 0.03) << i;
  }
  EXPECT_EQ(e.samples[0].pos_std_ned_m, c.position_sigma_ned_m);
  EXPECT_EQ(e.samples[0].vel_std_ned_mps, c.velocity_sigma_ned_mps);
}

TEST(AidingTest, GnssOutliersComeAtTheConfiguredProbabilityAndSize) {
  GnssSimConfig c;
  c.rate_hz = 100.0;
  c.position_sigma_ned_m = Eigen::Vector3d::Constant(1.0);
  c.outlier_probability = 0.05;
  c.outlier_size_m = 100.0;
  GnssSimulator gnss(c, Rng(5), false);
  const std::vector<TruthSample> truth = StaticStream(100.0, 20000);
  const GnssSample ref = AntennaTruth(truth[0], Eigen::Vector3d::Zero());
  int outliers = 0;
  for (const GnssSample& g : Feed<GnssSample>(gnss, truth)) {
    const double err = OffsetNed(g, ref).norm();
    if (err > 50.0) {
      ++outliers;
      // The outlier's length plus noise (sigma 1 m along it): within 5 sigma.
      EXPECT_NEAR(err, 100.0, 5.0);
    }
  }
  // Binomial(20000, 0.05): mean 1000, sd 30.8; 5 sd.
  EXPECT_NEAR(outliers, 1000, 154);
  EXPECT_EQ(gnss.outliers().size(), static_cast<std::size_t>(outliers));
}

TEST(AidingTest, GnssOutagesGiveNoSampleAndDoNotShiftLaterNoise) {
  GnssSimConfig c;
  c.rate_hz = 10.0;
  c.position_sigma_ned_m = Eigen::Vector3d::Constant(2.0);
  const GnssErrors all = RunStaticGnss(c, 3, 1000);
  c.outages_s = {Eigen::Vector2d(2.0, 3.5), Eigen::Vector2d(8.0, 20.0)};
  const GnssErrors gaps = RunStaticGnss(c, 3, 1000);
  ASSERT_EQ(all.samples.size(), 100u);  // 0.0 ... 9.9 s
  ASSERT_EQ(gaps.samples.size(), 100u - 15u - 20u);
  std::size_t j = 0;
  for (std::size_t i = 0; i < all.samples.size(); ++i) {
    const double t = all.samples[i].t_s;
    if ((t >= 2.0 && t < 3.5) || t >= 8.0) continue;
    ASSERT_EQ(gaps.samples[j].t_s, t);
    EXPECT_EQ(gaps.position[j], all.position[i]);  // same draws
    ++j;
  }
}

TEST(AidingTest, GnssSameSeedSameSamplesOtherSeedOtherSamples) {
  GnssSimConfig c;
  c.position_sigma_ned_m = Eigen::Vector3d::Constant(2.0);
  const GnssErrors a = RunStaticGnss(c, 42, 1000), b = RunStaticGnss(c, 42, 1000);
  const GnssErrors other = RunStaticGnss(c, 43, 1000);
  EXPECT_EQ(a.position, b.position);
  EXPECT_NE(a.position, other.position);
}

// ------------------------------------------------------------------- magnetometer

TEST(AidingTest, PerfectMagnetometerGivesIntensityAndHeadingAtLevel) {
  MagSimConfig c;
  c.rate_hz = 100.0;
  c.declination_rad = -8.5 * kDegToRad;
  c.inclination_rad = 53.0 * kDegToRad;
  c.intensity_uT = 50.0;
  c.noise_uT = 1.0;  // off in perfect mode
  for (const double yaw_deg : {0.0, 37.0, 135.0, -100.0}) {
    MagSimulator mag(c, kStart.lat_rad, Rng(2), true);
    const auto out = Feed<MagSample>(mag, StaticStream(100.0, 3, {0.0, 0.0, yaw_deg * kDegToRad}));
    ASSERT_EQ(out.size(), 3u);
    const Eigen::Vector3d m = out[0].m_b_uT;
    EXPECT_NEAR(m.norm(), 50.0, 1e-12);
    // FRD at level: magnetic heading atan2(-m_y, m_x); true heading = magnetic + declination.
    const double heading = std::atan2(-m.y(), m.x()) + *c.declination_rad;
    EXPECT_NEAR(WrapPi(heading - yaw_deg * kDegToRad), 0.0, 1e-12) << yaw_deg;
    EXPECT_NEAR(std::atan2(m.z(), m.head<2>().norm()), *c.inclination_rad, 1e-12);
  }
}

TEST(AidingTest, MagnetometerFieldDefaultsComeFromTheDipole) {
  MagSimulator mag(MagSimConfig{}, 37.5 * kDegToRad, Rng(1), true);
  const Eigen::Vector3d f = mag.field_ned_uT();
  // tan I = 2 tan(37.5 deg): I = 56.91 deg (the seed's 57 deg); B = 29.4048 sqrt(1 + 3 sin^2).
  EXPECT_NEAR(std::atan2(f.z(), f.x()) * kRadToDeg, 56.91, 0.01);
  EXPECT_NEAR(f.norm(), 29.4048 * std::sqrt(1.0 + 3.0 * std::pow(std::sin(37.5 * kDegToRad), 2)),
              1e-12);
  EXPECT_EQ(f.y(), 0.0);  // declination 0
}

TEST(AidingTest, MagnetometerAppliesHardAndSoftIron) {
  MagSimConfig c;
  c.rate_hz = 50.0;
  c.intensity_uT = 48.0;
  c.hard_iron_fixed_uT = Eigen::Vector3d(12.0, -7.5, 3.0);
  Eigen::Matrix3d soft;
  soft << 0.05, 0.01, -0.02, 0.0, -0.03, 0.015, 0.02, 0.0, 0.08;
  c.soft_iron_fixed = soft;
  MagSimulator mag(c, kStart.lat_rad, Rng(4), false);
  const Eigen::Vector3d euler(0.3, -0.2, 2.0);
  const std::vector<TruthSample> truth = StaticStream(100.0, 10, euler);
  const auto out = Feed<MagSample>(mag, truth);
  ASSERT_EQ(out.size(), 5u);
  const Eigen::Vector3d expected = (Eigen::Matrix3d::Identity() + soft) *
                                       (truth[0].state.q_n_b.conjugate() * mag.field_ned_uT()) +
                                   *c.hard_iron_fixed_uT;
  EXPECT_LT((out[0].m_b_uT - expected).norm(), 1e-12);
  EXPECT_EQ(mag.hard_iron_uT(), *c.hard_iron_fixed_uT);
}

TEST(AidingTest, MagnetometerDrawsIronNoiseAndTwoAxisMode) {
  MagSimConfig c;
  c.rate_hz = 100.0;
  c.hard_iron_sigma_uT = 10.0;
  c.soft_iron_sigma = 0.05;
  c.soft_iron_symmetric = true;
  c.noise_uT = 0.4;
  MagSimulator mag(c, kStart.lat_rad, Rng(8), false);
  EXPECT_GT(mag.hard_iron_uT().norm(), 0.0);
  EXPECT_GT(mag.soft_iron().norm(), 0.0);
  EXPECT_EQ(mag.soft_iron(), mag.soft_iron().transpose());
  const std::vector<TruthSample> truth = StaticStream(100.0, 20000);
  const Eigen::Vector3d clean =
      (Eigen::Matrix3d::Identity() + mag.soft_iron()) * mag.field_ned_uT() + mag.hard_iron_uT();
  std::vector<Eigen::Vector3d> noise;
  for (const MagSample& m : Feed<MagSample>(mag, truth)) noise.push_back(m.m_b_uT - clean);
  ASSERT_EQ(noise.size(), 20000u);
  const Eigen::Vector3d sd = StdDev(noise);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(sd[i] / 0.4, 1.0, 0.03) << i;  // 6 standard errors

  c.two_axis = true;
  MagSimulator two(c, kStart.lat_rad, Rng(8), false);
  for (const MagSample& m : Feed<MagSample>(two, StaticStream(100.0, 50)))
    EXPECT_EQ(m.m_b_uT.z(), 0.0);
}

// ---------------------------------------------------------------------- barometer

TEST(AidingTest, IsaMatchesTheStandardTable) {
  // U.S. Standard Atmosphere 1976 table values (geopotential altitude H; geometric
  // z = r0 H / (r0 - H)); 0.01 Pa is the table's last digit.
  const auto z = [](double H) { return 6356766.0 * H / (6356766.0 - H); };
  EXPECT_NEAR(IsaPressure_pa(0.0), 101325.0, 1e-9);
  EXPECT_NEAR(IsaTemperature_K(0.0), 288.15, 1e-12);
  EXPECT_NEAR(IsaPressure_pa(z(1000.0)), 89874.57, 0.01);
  EXPECT_NEAR(IsaPressure_pa(z(11000.0)), 22632.06, 0.01);
  EXPECT_NEAR(IsaPressure_pa(z(20000.0)), 5474.89, 0.01);
  EXPECT_NEAR(IsaTemperature_K(z(15000.0)), 216.65, 1e-12);
  EXPECT_THROW(IsaPressure_pa(z(20001.0)), std::out_of_range);
}

TEST(AidingTest, BarometerBiasAndNoise) {
  BaroSimConfig c;
  c.rate_hz = 100.0;
  c.bias_sigma_m = 5.0;
  c.noise_m = 0.5;
  BaroSimulator baro(c, Rng(9), false);
  EXPECT_NE(baro.bias_m(), 0.0);
  std::vector<Eigen::Vector3d> err;
  double mean = 0.0;
  for (const BaroSample& b : Feed<BaroSample>(baro, StaticStream(100.0, 20000))) {
    const double e = b.altitude_m - kStart.h_m - baro.bias_m();
    err.push_back(Eigen::Vector3d::Constant(e));
    mean += e / 20000.0;
    EXPECT_NEAR(b.pressure_pa, IsaPressure_pa(b.altitude_m), 1e-9);
  }
  ASSERT_EQ(err.size(), 20000u);
  EXPECT_NEAR(StdDev(err).x() / 0.5, 1.0, 0.03);           // 6 standard errors
  EXPECT_NEAR(mean, 0.0, 4.0 * 0.5 / std::sqrt(20000.0));  // 4 standard errors

  BaroSimulator perfect(c, Rng(9), true);
  const auto out = Feed<BaroSample>(perfect, StaticStream(100.0, 2));
  EXPECT_EQ(out[0].altitude_m, kStart.h_m);
  EXPECT_NEAR(out[0].temperature_degC, IsaTemperature_K(kStart.h_m) - 273.15, 1e-12);
}

// ----------------------------------------------------------------------- odometer

// The odometer reads the forward speed of its reference point: on the Wobble trajectory
// (body rates to 3 rad/s) the perfect odometer at a lever arm equals [R_b_n v_n + omega x
// l]_x of the interpolated truth, and the scale factor multiplies it exactly.
TEST(AidingTest, OdometerReadsTheForwardSpeedOfItsReferencePoint) {
  const Wobble trajectory;
  const std::vector<TruthSample> truth = TruthStream(trajectory, 200.0, 3.0);
  OdometerSimConfig c;
  c.rate_hz = 10.0;
  c.lever_arm_b_m = Eigen::Vector3d(-1.2, 0.3, 0.4);
  c.scale_factor_fixed = 0.01;
  c.noise_mps = 0.05;
  OdometerSimulator perfect(c, Rng(3), true);
  OdometerSimulator scaled(c, Rng(3), false);
  const std::vector<OdometerSample> p = Feed<OdometerSample>(perfect, truth);
  ASSERT_EQ(p.size(), 31u);  // t = 0, 0.1, ..., 3.0
  for (const OdometerSample& s : p) {
    const auto at = std::find_if(truth.begin(), truth.end(), [&](const TruthSample& t) { return std::abs(t.t_s - s.t_s) < 1e-9; });
    ASSERT_NE(at, truth.end());
    const Eigen::Vector3d v_b =
        at->state.q_n_b.conjugate() * at->state.v_n_mps + at->omega_ib_b_radps.cross(c.lever_arm_b_m);
    EXPECT_NEAR(s.speed_mps, v_b.x(), 1e-9);
  }
  EXPECT_EQ(scaled.scale_factor(), 0.01);
  // Noise: the residual of the scaled reading has the configured sigma (30 samples: loose).
  double sum_sq = 0.0;
  const std::vector<OdometerSample> n = Feed<OdometerSample>(scaled, truth);
  for (std::size_t k = 0; k < n.size(); ++k) sum_sq += std::pow(n[k].speed_mps - 1.01 * p[k].speed_mps, 2);
  EXPECT_NEAR(std::sqrt(sum_sq / n.size()), 0.05, 0.02);
  // Parsed from YAML in people units.
  const OdometerSimConfig y = ParseOdometerSimConfig(
      Yaml("odometer: {rate_hz: 20, scale_factor_ppm: 3000, noise_mps: 0.1, lever_arm_b_m: [1, 0, 0]}")
          .Child("odometer"));
  EXPECT_EQ(y.rate_hz, 20.0);
  EXPECT_NEAR(y.scale_factor_sigma, 3e-3, 1e-15);
  ExpectConfigError([&] { ParseOdometerSimConfig(Yaml("odometer: {noise_mps: -1}").Child("odometer")); },
                    "noise_mps");
}

// --------------------------------------------------------------------- master INS

TEST(AidingTest, PerfectMasterRecordTaggedTIsTheTruthAtTMinusDelay) {
  Wobble wobble;
  const std::vector<TruthSample> truth = TruthStream(wobble, 200.0, 5.0);
  MasterSimConfig c;
  c.rate_hz = 50.0;
  c.transfer_delay_s = 0.3;
  c.attitude_error_sigma_rad = 1e-3;  // off in perfect mode
  MasterSimulator master(c, Rng(1), true);
  const std::vector<NavState> out = Feed<NavState>(master, truth);
  ASSERT_EQ(out.size(), 236u);  // tags 0.30 ... 5.00 s
  EXPECT_NEAR(out.front().t_s, 0.3, 1e-15);
  for (const NavState& m : out) {
    const TruthSample& t = truth[static_cast<std::size_t>(std::lround((m.t_s - 0.3) * 200.0))];
    EXPECT_EQ(m.lat_rad, t.state.lat_rad);
    EXPECT_EQ(m.h_m, t.state.h_m);
    EXPECT_EQ(m.v_n_mps, t.state.v_n_mps);
    EXPECT_EQ(m.q_n_b.coeffs(), t.state.q_n_b.coeffs());
  }
}

TEST(AidingTest, MasterDelayOffTheTruthGridIsInterpolated) {
  Wobble wobble;
  const std::vector<TruthSample> fine = TruthStream(wobble, 1000.0, 3.0);
  std::vector<TruthSample> coarse;
  for (std::size_t k = 0; k < fine.size(); k += 10) coarse.push_back(fine[k]);
  MasterSimConfig c;
  c.rate_hz = 100.0;
  c.transfer_delay_s = 0.303;  // data times on the 1 kHz grid, between 100 Hz samples
  MasterSimulator master(c, Rng(1), true);
  double att_rad = 0.0, vel_mps = 0.0;
  for (const NavState& m : Feed<NavState>(master, coarse)) {
    const TruthSample& t = fine[static_cast<std::size_t>(std::lround((m.t_s - 0.303) * 1000.0))];
    att_rad = std::max(att_rad, AttitudeError(t.state.q_n_b, m.q_n_b).norm());
    vel_mps = std::max(vel_mps, (t.state.v_n_mps - m.v_n_mps).norm());
  }
  // As InterpolatedTruthMatchesTheTruthBetweenSamples; measured 1.6e-8 rad, 8.9e-8 m/s.
  EXPECT_LT(att_rad, 1e-7);
  EXPECT_LT(vel_mps, 1e-6);
}

TEST(AidingTest, MasterAttitudeErrorAndVelocityNoise) {
  MasterSimConfig c;
  c.rate_hz = 100.0;
  c.transfer_delay_s = 0.1;
  c.attitude_error_sigma_rad = 2e-3;
  c.velocity_noise_mps = 0.02;
  MasterSimulator master(c, Rng(6), false);
  EXPECT_GT(master.attitude_error_rad().norm(), 0.0);
  const std::vector<TruthSample> truth = StaticStream(100.0, 20010);
  std::vector<Eigen::Vector3d> dv;
  for (const NavState& m : Feed<NavState>(master, truth)) {
    // R_true = Exp(phi) R_master with phi the drawn constant (no random walk configured).
    EXPECT_LT((AttitudeError(truth[0].state.q_n_b, m.q_n_b) - master.attitude_error_rad()).norm(),
              1e-15);
    dv.push_back(m.v_n_mps);
  }
  ASSERT_EQ(dv.size(), 20000u);
  const Eigen::Vector3d sd = StdDev(dv);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(sd[i] / 0.02, 1.0, 0.03) << i;  // 6 standard errors
}

TEST(AidingTest, MasterAttitudeRandomWalkGrowsLikeSqrtTime) {
  // 400 independent runs of 100 s at 10 Hz: the random walk after 100 s has sigma
  // q sqrt(100 s); the sample sigma of 1200 values (3 axes) is within 4 standard errors
  // (1/sqrt(2400) = 2 %) of it.
  MasterSimConfig c;
  c.rate_hz = 10.0;
  c.attitude_random_walk_rad_sqrt_s = 1e-4;
  const std::vector<TruthSample> truth = StaticStream(10.0, 1001);
  std::vector<Eigen::Vector3d> end;
  for (std::uint64_t seed = 0; seed < 400; ++seed) {
    MasterSimulator master(c, Rng(seed), false);
    const std::vector<NavState> out = Feed<NavState>(master, truth);
    end.push_back(AttitudeError(truth[0].state.q_n_b, out.back().q_n_b));
  }
  double sq = 0.0;
  for (const auto& e : end) sq += e.squaredNorm();
  // The last record (tag 100 s) carries 1000 steps of N(0, q^2 / 10 Hz).
  EXPECT_NEAR(std::sqrt(sq / 1200.0) / (1e-4 * std::sqrt(100.0)), 1.0, 0.08);
}

// ------------------------------------------------------------------------ parsing

TEST(AidingTest, ParsesEverySection) {
  const ConfigNode root = Yaml(R"(
gnss: {rate_hz: 5, position_sigma_m: [1.5, 3], velocity_sigma_mps: 0.05,
       lever_arm_b_m: [0.5, 0, -1], time_offset_s: 0.1, latency_s: 0.12, outages: [[10, 20], [30, 31]],
       outlier_probability: 0.01, outlier_size_m: 30, start_s: 1}
mag: {rate_hz: 20, declination_deg: -8, inclination_deg: 53, intensity_uT: 50,
      hard_iron_fixed_uT: [1, 2, 3], soft_iron: 0.02, soft_iron_symmetric: true,
      noise_uT: 0.3, two_axis: true}
baro: {rate_hz: 25, bias_m: 3, noise_m: 0.4, pressure: false}
master: {rate_hz: 100, transfer_delay_s: 0.3, attitude_error_sigma_mrad: 1,
         attitude_random_walk_mrad_sqrt_h: 0.6, velocity_noise_mps: 0.01}
)");
  const GnssSimConfig g = ParseGnssSimConfig(root.Child("gnss"));
  EXPECT_EQ(g.rate_hz, 5.0);
  EXPECT_EQ(g.position_sigma_ned_m, Eigen::Vector3d(1.5, 1.5, 3.0));
  EXPECT_EQ(g.velocity_sigma_ned_mps, Eigen::Vector3d::Constant(0.05));
  EXPECT_EQ(g.lever_arm_b_m, Eigen::Vector3d(0.5, 0.0, -1.0));
  EXPECT_EQ(g.latency_s, 0.12);
  ASSERT_EQ(g.outages_s.size(), 2u);
  EXPECT_EQ(g.outages_s[1], Eigen::Vector2d(30.0, 31.0));
  EXPECT_EQ(g.outlier_size_m, 30.0);
  EXPECT_EQ(g.start_s, 1.0);
  const MagSimConfig m = ParseMagSimConfig(root.Child("mag"));
  EXPECT_NEAR(*m.declination_rad, -8.0 * kDegToRad, 1e-15);
  EXPECT_EQ(*m.hard_iron_fixed_uT, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(m.soft_iron_sigma, 0.02);
  EXPECT_TRUE(m.two_axis && m.soft_iron_symmetric);
  const BaroSimConfig b = ParseBaroSimConfig(root.Child("baro"));
  EXPECT_EQ(b.bias_sigma_m, 3.0);
  EXPECT_FALSE(b.pressure);
  const MasterSimConfig ms = ParseMasterSimConfig(root.Child("master"));
  EXPECT_EQ(ms.transfer_delay_s, 0.3);
  EXPECT_NEAR(ms.attitude_error_sigma_rad, 1e-3, 1e-18);
  EXPECT_NEAR(ms.attitude_random_walk_rad_sqrt_s, 1e-5, 1e-20);  // 0.6 mrad/sqrt(h)
}

TEST(AidingTest, BadConfigurationsNameTheKey) {
  const auto gnss = [](const std::string& text) { ParseGnssSimConfig(Yaml(text).Child("gnss")); };
  ExpectConfigError([&] { gnss("gnss: {rate_hz: 200}"); }, "gnss.rate_hz");
  ExpectConfigError([&] { gnss("gnss: {rate: 5}"); }, "unknown key");
  ExpectConfigError([&] { gnss("gnss: {position_sigma_m: -1}"); }, "must be >= 0");
  ExpectConfigError([&] { gnss("gnss: {position_sigma_m: [1, 2, 3, 4]}"); }, "[N, E, D]");
  ExpectConfigError([&] { gnss("gnss:\n  outages: [[5, 2]]"); }, "gnss.outages[0]");
  ExpectConfigError([&] { gnss("gnss: {outlier_probability: 0.1}"); }, "gnss.outlier_size_m");
  ExpectConfigError(
      [&] {
        ParseMagSimConfig(
            Yaml("mag: {hard_iron_uT: 1, hard_iron_fixed_uT: [1, 2, 3]}").Child("mag"));
      },
      "not both");
  ExpectConfigError(
      [&] { ParseMagSimConfig(Yaml("mag: {soft_iron_fixed: [[1, 0], [0, 1]]}").Child("mag")); },
      "mag.soft_iron_fixed");
  ExpectConfigError([&] { ParseMagSimConfig(Yaml("mag: {intensity_uT: 0}").Child("mag")); },
                    "must be > 0");
  ExpectConfigError([&] { ParseBaroSimConfig(Yaml("baro: {noise_m: -0.1}").Child("baro")); },
                    "baro.noise_m");
  ExpectConfigError(
      [&] { ParseMasterSimConfig(Yaml("master: {transfer_delay_s: -0.3}").Child("master")); },
      "master.transfer_delay_s");
}

TEST(AidingTest, EmitDrawnWritesTheDrawnValuesWithUnits) {
  GnssSimConfig gc;
  gc.rate_hz = 100.0;
  gc.outlier_probability = 0.5;
  gc.outlier_size_m = 10.0;
  GnssSimulator gnss(gc, Rng(1), false);
  Feed<GnssSample>(gnss, StaticStream(100.0, 20));
  MagSimConfig mc;
  mc.hard_iron_sigma_uT = 5.0;
  MagSimulator mag(mc, kStart.lat_rad, Rng(1), false);
  MasterSimConfig msc;
  msc.attitude_error_sigma_rad = 1e-3;
  MasterSimulator master(msc, Rng(1), false);
  BaroSimulator baro(BaroSimConfig{}, Rng(1), false);

  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "gnss" << YAML::Value;
  gnss.EmitDrawn(out);
  out << YAML::Key << "mag" << YAML::Value;
  mag.EmitDrawn(out);
  out << YAML::Key << "baro" << YAML::Value;
  baro.EmitDrawn(out);
  out << YAML::Key << "master" << YAML::Value;
  master.EmitDrawn(out);
  out << YAML::EndMap;
  ASSERT_TRUE(out.good()) << out.GetLastError();
  const YAML::Node y = YAML::Load(out.c_str());
  EXPECT_EQ(y["gnss"]["outliers"].size(), gnss.outliers().size());
  EXPECT_GT(gnss.outliers().size(), 0u);
  EXPECT_DOUBLE_EQ(y["mag"]["hard_iron_uT"][1].as<double>(), mag.hard_iron_uT().y());
  EXPECT_DOUBLE_EQ(y["master"]["attitude_error_mrad"][2].as<double>(),
                   master.attitude_error_rad().z() / 1e-3);
  EXPECT_EQ(y["baro"]["bias_m"].as<double>(), 0.0);
}

}  // namespace sim_aiding_test
}  // namespace navtwin::sim
