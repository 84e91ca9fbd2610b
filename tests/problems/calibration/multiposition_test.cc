// Multi-position IMU calibration (problems/calibration/multiposition.h) on simulated tables
// with known errors: the IMU increments come from sim::MultiPositionRig + sim::SynthesizeImu
// (exact, once per table) and sim::InertialErrorModel (per run), all in memory.
#include "problems/calibration/multiposition.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/csv_imu.h"
#include "core/io/input_error.h"
#include "core/rotation.h"
#include "core/sim/analytic_trajectory.h"
#include "core/sim/inertial_errors.h"
#include "core/sim/random.h"
#include "core/units.h"

namespace navtwin::calibration {
namespace calibration_multiposition_test {

constexpr double kLat_rad = 45.0 * kDegToRad;
constexpr double kHeight_m = 100.0;
constexpr double kRate_hz = 100.0;

/// A table with the given positions (deg), each held dwell_s after a move of rotation_s.
sim::MultiPositionConfig Table(const std::vector<Eigen::Vector3d>& euler_deg, double dwell_s, double rotation_s) {
  sim::MultiPositionConfig c;
  c.rotation_s = rotation_s;
  for (const Eigen::Vector3d& e : euler_deg) {
    sim::TableStep s;
    s.euler_rad = e * kDegToRad;
    s.dwell_s = dwell_s;
    c.steps.push_back(s);
  }
  return c;
}

/// Six faces down (z down, z up, x down, x up, y down, y up) at four headings: 24 positions.
std::vector<Eigen::Vector3d> TwentyFourPositions() {
  const std::vector<Eigen::Vector2d> faces = {{0, 0}, {180, 0}, {0, 90}, {0, -90}, {90, 0}, {-90, 0}};
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector2d& f : faces)
    for (double yaw : {0.0, 90.0, 180.0, 270.0}) out.emplace_back(f.x(), f.y(), yaw);
  return out;
}

/// The exact increments of a table (first emitted sample, dt = 0, dropped).
std::vector<ImuSample> Truth(const sim::MultiPositionConfig& table) {
  const sim::MultiPositionRig rig(table);
  std::vector<ImuSample> out;
  sim::SynthesizeImu(rig, wgs84::Geodetic{kLat_rad, 0.0, kHeight_m}, kRate_hz, rig.duration_s() + 1.0,
                     [&out](const ImuSample& s, const NavState&) {
                       if (s.dt_s > 0.0) out.push_back(s);
                     });
  return out;
}

/// Measured increments: truth through the error model of `config`, drawn with `seed`.
std::vector<ImuSample> Measure(const std::vector<ImuSample>& truth, const sim::InertialErrorConfig& config,
                               std::uint64_t seed, sim::InertialErrorModel** model_out = nullptr) {
  static thread_local std::unique_ptr<sim::InertialErrorModel> model;
  model = std::make_unique<sim::InertialErrorModel>(config, sim::Rng(seed).Stream("imu"), false);
  std::vector<ImuSample> out = truth;
  for (ImuSample& s : out) model->Apply(s.t_s, s.dt_s, 25.0, s.dtheta_b_rad, s.dv_b_mps, &s.dtheta_b_rad, &s.dv_b_mps);
  if (model_out != nullptr) *model_out = model.get();
  return out;
}

MultiPositionData Data(const sim::MultiPositionConfig& table, std::vector<ImuSample> imu) {
  MultiPositionData d;
  d.imu = std::move(imu);
  d.schedule = table;
  d.latitude_rad = kLat_rad;
  d.height_m = kHeight_m;
  return d;
}

/// The true parameter vector of a drawn model, in the blocks of core/imu_error_model.h.
struct TrueParameters {
  Eigen::Matrix<double, 12, 1> accel, gyro;
  Eigen::Matrix<double, 9, 1> g9;
};
Eigen::Matrix<double, 12, 1> TriadVector(const sim::DrawnTriadErrors& d) {
  Eigen::Matrix<double, 12, 1> v;
  for (int r = 0; r < 3; ++r) {
    v(r) = d.scale_factor(r);
    v(9 + r) = d.bias(r);
    for (int c = 0; c < 3; ++c)
      if (c != r) v(MisalignmentIndex(r, c)) = d.misalignment(r, c);
  }
  return v;
}
TrueParameters Truth(const sim::InertialErrorModel& m) {
  TrueParameters t;
  t.accel = TriadVector(m.accel().drawn());
  t.gyro = TriadVector(m.gyro().drawn());
  for (int i = 0; i < 9; ++i) t.g9(i) = m.g_sensitivity()(i / 3, i % 3);
  return t;
}

/// Realistic tactical-grade errors (constants drawn per run, white noise).
sim::InertialErrorConfig Tactical() {
  sim::InertialErrorConfig c;
  c.gyro.bias.sigma = 1.0 * kDegToRad / 3600.0;        // 1 deg/h
  c.gyro.white_noise = 0.05 * kDegToRad / 60.0;        // 0.05 deg/sqrt(h)
  c.gyro.scale_factor.sigma = 300e-6;
  c.gyro.misalignment.sigma = 0.5e-3;
  c.accel.bias.sigma = kMilliG_mps2;                 // 1 mg
  c.accel.white_noise = 0.05 / 60.0;                   // 0.05 m/s/sqrt(h)
  c.accel.scale_factor.sigma = 300e-6;
  c.accel.misalignment.sigma = 0.5e-3;
  c.g_sensitivity.sigma = kDegPerHour_radps / kStandardGravity_mps2;  // 1 deg/h/g
  return c;
}

/// Fixed errors, no noise (for the exact-recovery test).
sim::InertialErrorConfig Fixed() {
  sim::InertialErrorConfig c;
  Eigen::Matrix3d Mg, Ma, G;
  Mg << 0, 4e-4, -3e-4, 2e-4, 0, 5e-4, -6e-4, 1e-4, 0;
  Ma << 0, -2e-4, 3e-4, 5e-4, 0, -4e-4, 1e-4, 6e-4, 0;
  G << 2e-6, -1e-6, 3e-6, 1e-6, -2e-6, 1e-6, -3e-6, 2e-6, 1e-6;
  c.gyro.bias.fixed = Eigen::Vector3d(3e-5, -2e-5, 1e-5);
  c.gyro.scale_factor.fixed = Eigen::Vector3d(500e-6, -300e-6, 200e-6);
  c.gyro.misalignment.fixed = Mg;
  c.accel.bias.fixed = Eigen::Vector3d(0.02, -0.01, 0.015);
  c.accel.scale_factor.fixed = Eigen::Vector3d(-400e-6, 250e-6, 600e-6);
  c.accel.misalignment.fixed = Ma;
  c.g_sensitivity.fixed = G;
  return c;
}

Eigen::Matrix<double, 33, 1> Stack(const ImuCalibration& c) {
  Eigen::Matrix<double, 33, 1> v;
  v << c.accel, c.gyro, c.g_sensitivity;
  return v;
}
Eigen::Matrix<double, 33, 1> SigmaStack(const ImuCalibration& c) {
  Eigen::Matrix<double, 33, 1> v;
  v << *c.accel_sigma, *c.gyro_sigma, *c.g_sensitivity_sigma;
  return v;
}
Eigen::Matrix<double, 33, 1> Stack(const TrueParameters& t) {
  Eigen::Matrix<double, 33, 1> v;
  v << t.accel, t.gyro, t.g9;
  return v;
}

TEST(MultiPositionTest, RecoversFixedErrorsExactlyWithoutNoise) {
  const sim::MultiPositionConfig table = Table(TwentyFourPositions(), 5.0, 3.0);
  sim::InertialErrorModel* model = nullptr;
  const std::vector<ImuSample> imu = Measure(Truth(table), Fixed(), 1, &model);
  const Eigen::Matrix<double, 33, 1> truth = Stack(Truth(*model));
  const ImuCalibrationResult r = CalibrateMultiPosition(Data(table, imu));
  EXPECT_TRUE(r.unobservable.empty()) << r.unobservable.front();
  EXPECT_EQ(r.positions, 24);
  EXPECT_EQ(r.estimated.size(), 33u);
  const Eigen::Matrix<double, 33, 1> err = Stack(r.calibration) - truth;
  // Noise-free: the accelerometer is exact to rounding; the gyro keeps the truncation error
  // of the two-sample coning correction in the 3 s moves (up to 3 rad/s at 100 Hz), which
  // scales with the cube of the rate (measured: 3.1e-7, 4.1e-8, 5.6e-9 for 3, 6, 12 s moves).
  EXPECT_LT(err.head<9>().cwiseAbs().maxCoeff(), 1e-12);         // accel scale, misalignment
  EXPECT_LT(err.segment<3>(9).cwiseAbs().maxCoeff(), 1e-12);     // accel bias, m/s^2
  EXPECT_LT(err.segment<9>(12).cwiseAbs().maxCoeff(), 5e-7);     // gyro scale, misalignment (3.1e-7)
  EXPECT_LT(err.segment<3>(21).cwiseAbs().maxCoeff(), 3e-9);     // gyro bias, rad/s (1.3e-9)
  EXPECT_LT(err.tail<9>().cwiseAbs().maxCoeff(), 1e-8);          // (rad/s)/(m/s^2) (5.8e-9)
  EXPECT_LT(r.accel_residual_rms_mps2, 1e-8);
  // The residuals before and after per position: before, the raw sensor's errors (its
  // biases alone are mg and hundreds of deg/h); after, rounding and the coning truncation.
  ASSERT_EQ(r.residuals.size(), 24u);
  ASSERT_EQ(r.static_positions.size(), 24u);
  for (const CalibrationResidual& res : r.residuals) {
    EXPECT_GT(res.accel_before_mps2.norm(), 1e-4);
    EXPECT_LT(res.accel_after_mps2.norm(), 1e-8);
    EXPECT_LT(res.t0_s, res.t1_s);
    EXPECT_FALSE(res.rms);
  }
}

// The residual rows are the fit's own: their RMS after calibration over every axis of
// every position is the reported residual RMS (same formula, to rounding), with noise.
TEST(MultiPositionTest, ResidualRowsAgreeWithTheReportedRms) {
  const sim::MultiPositionConfig table = Table(TwentyFourPositions(), 5.0, 3.0);
  sim::InertialErrorModel* model = nullptr;
  const ImuCalibrationResult r = CalibrateMultiPosition(Data(table, Measure(Truth(table), Tactical(), 7, &model)));
  ASSERT_EQ(r.residuals.size(), 24u);
  double ss_a = 0.0, ss_g = 0.0, before_a = 0.0;
  for (const CalibrationResidual& res : r.residuals) {
    ss_a += res.accel_after_mps2.squaredNorm();
    ss_g += res.gyro_after_radps.squaredNorm();
    before_a += res.accel_before_mps2.squaredNorm();
  }
  EXPECT_NEAR(std::sqrt(ss_a / 72.0) / r.accel_residual_rms_mps2, 1.0, 1e-9);
  EXPECT_NEAR(std::sqrt(ss_g / 72.0) / r.gyro_residual_rms_rad_per_s, 1.0, 1e-9);
  EXPECT_GT(before_a, 100.0 * ss_a);  // the calibration removes the tactical IMU's errors
}

TEST(MultiPositionTest, MonteCarloSigmaIsHonest) {
  // 12 positions (two faces per axis direction at two headings) keep 100 runs to seconds.
  std::vector<Eigen::Vector3d> positions;
  const std::vector<Eigen::Vector3d> all = TwentyFourPositions();
  for (std::size_t i = 0; i < all.size(); i += 2) positions.push_back(all[i]);
  const sim::MultiPositionConfig table = Table(positions, 8.0, 3.0);
  const std::vector<ImuSample> truth = Truth(table);
  int within = 0, total = 0, runs = 0;
  for (std::uint64_t seed = 1000; seed < 1100; ++seed) {
    sim::InertialErrorModel* model = nullptr;
    const std::vector<ImuSample> imu = Measure(truth, Tactical(), seed, &model);
    const Eigen::Matrix<double, 33, 1> t = Stack(Truth(*model));
    const ImuCalibrationResult r = CalibrateMultiPosition(Data(table, imu));
    ASSERT_TRUE(r.unobservable.empty()) << r.unobservable.front();
    const Eigen::Matrix<double, 33, 1> e = Stack(r.calibration) - t, s = SigmaStack(r.calibration);
    for (int i = 0; i < 33; ++i) {
      ASSERT_TRUE(std::isfinite(s(i)) && s(i) > 0.0);
      within += std::abs(e(i)) <= 3.0 * s(i) ? 1 : 0;
      ++total;
    }
    ++runs;
  }
  const double fraction = static_cast<double>(within) / total;
  RecordProperty("fraction_within_3_sigma", std::to_string(fraction));
  std::printf("Monte Carlo: %d runs, %d of %d (run, parameter) within 3 sigma: %.4f\n", runs, within, total, fraction);
  // Gaussian errors with honest sigma: 99.7 % within 3 sigma; the issue asks >= 95 %.
  EXPECT_GE(fraction, 0.95);
}

TEST(MultiPositionTest, RecursiveAgreesWithBatchAfterLastPosition) {
  const sim::MultiPositionConfig table = Table(TwentyFourPositions(), 8.0, 3.0);
  const MultiPositionData data = Data(table, Measure(Truth(table), Tactical(), 7));
  const ImuCalibrationResult batch = CalibrateMultiPosition(data);
  RecursiveMultiPosition filter(data);
  int steps = 0;
  while (filter.Step()) ++steps;
  EXPECT_EQ(steps, 24);
  EXPECT_EQ(filter.positions_done(), 24);
  const ImuCalibrationResult rec = filter.Current();
  ASSERT_TRUE(rec.unobservable.empty()) << rec.unobservable.front();
  const Eigen::Matrix<double, 33, 1> d = Stack(rec.calibration) - Stack(batch.calibration);
  const Eigen::Matrix<double, 33, 1> sb = SigmaStack(batch.calibration), sr = SigmaStack(rec.calibration);
  double worst = 0.0, worst_sigma_ratio = 0.0;
  for (int i = 0; i < 33; ++i) {
    worst = std::max(worst, std::abs(d(i)) / sb(i));
    worst_sigma_ratio = std::max(worst_sigma_ratio, std::abs(sr(i) / sb(i) - 1.0));
  }
  std::printf("recursive - batch: worst %.3g sigma; sigma ratio off by %.3g\n", worst, worst_sigma_ratio);
  // Both solve the same equations (the filter re-linearises the moves at each position);
  // left: the filter's prior (information 1e-8 of the data's) and the batch's stopping
  // tolerance. Measured: 4.1e-6 sigma and 1.8e-8.
  EXPECT_LT(worst, 1e-3);
  EXPECT_LT(worst_sigma_ratio, 1e-5);
}

TEST(MultiPositionTest, RecursiveRefinesAsPositionsArrive) {
  const sim::MultiPositionConfig table = Table(TwentyFourPositions(), 8.0, 3.0);
  RecursiveMultiPosition filter(Data(table, Measure(Truth(table), Tactical(), 8)));
  for (int k = 0; k < 6; ++k) ASSERT_TRUE(filter.Step());
  const ImuCalibrationResult early = filter.Current();
  while (filter.Step()) {
  }
  const ImuCalibrationResult late = filter.Current();
  EXPECT_EQ(early.positions, 6);
  EXPECT_GE(early.unobservable.size(), late.unobservable.size());
  // More positions: the accel bias sigma shrinks.
  EXPECT_LT((*late.calibration.accel_sigma)(9), (*early.calibration.accel_sigma)(9));
}

TEST(MultiPositionTest, PositionsInOnePlaneReportUnobservableParameters) {
  // Roll only: gravity always in the body y-z plane, rotations only about x.
  std::vector<Eigen::Vector3d> positions;
  for (int k = 0; k < 8; ++k) positions.emplace_back(45.0 * k, 0.0, 0.0);
  const sim::MultiPositionConfig table = Table(positions, 8.0, 3.0);
  const ImuCalibrationResult r = CalibrateMultiPosition(Data(table, Measure(Truth(table), Tactical(), 3)));
  const auto listed = [&r](const std::string& name) {
    for (const std::string& u : r.unobservable)
      if (u.rfind(name + ":", 0) == 0) return true;
    return false;
  };
  for (const char* name : {"accel.scale_factor.x", "accel.misalignment.yx", "accel.misalignment.zx",
                           "g_sensitivity.xx", "g_sensitivity.yx", "g_sensitivity.zx"}) {
    EXPECT_TRUE(listed(name)) << name;
  }
  EXPECT_FALSE(listed("accel.bias.x"));
  EXPECT_FALSE(listed("gyro.scale_factor.x"));  // the roll moves excite it
  // Everything listed is 0 with sigma NaN, everything else finite.
  const Eigen::Matrix<double, 33, 1> v = Stack(r.calibration), s = SigmaStack(r.calibration);
  std::vector<std::string> names;
  for (int i = 0; i < 12; ++i) names.push_back(TriadParameterName("accel", i));
  for (int i = 0; i < 12; ++i) names.push_back(TriadParameterName("gyro", i));
  for (int i = 0; i < 9; ++i) names.push_back(GSensitivityParameterName(i));
  for (int i = 0; i < 33; ++i) {
    ASSERT_TRUE(std::isfinite(v(i))) << names[i];
    if (listed(names[i])) {
      EXPECT_EQ(v(i), 0.0) << names[i];
      EXPECT_TRUE(std::isnan(s(i))) << names[i];
    } else {
      EXPECT_TRUE(std::isfinite(s(i))) << names[i];
    }
  }
  EXPECT_EQ(r.estimated.size() + r.unobservable.size(), 33u);
  std::printf("one plane: %zu unobservable:\n", r.unobservable.size());
  for (const std::string& u : r.unobservable) std::printf("  %s\n", u.c_str());
}

TEST(MultiPositionTest, FewerThanSixPositionsIsAnError) {
  const std::vector<Eigen::Vector3d> all = TwentyFourPositions();
  const std::vector<Eigen::Vector3d> positions(all.begin(), all.begin() + 5);
  const sim::MultiPositionConfig table = Table(positions, 5.0, 3.0);
  try {
    CalibrateMultiPosition(Data(table, Truth(table)));
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("5 static positions"), std::string::npos) << e.what();
  }
}

TEST(MultiPositionTest, SaturatedSamplesAreLeftOutWithANote) {
  const sim::MultiPositionConfig table = Table(TwentyFourPositions(), 5.0, 3.0);
  const std::vector<ImuSample> clean = Measure(Truth(table), Fixed(), 1);
  std::vector<ImuSample> spiky = clean;
  const sim::MultiPositionRig rig(table);
  const double t_mid = 0.5 * (rig.static_intervals()[2].start_s + rig.static_intervals()[2].end_s);
  int spiked = 0;
  for (ImuSample& s : spiky) {
    if (std::abs(s.t_s - t_mid) < 0.025) {  // 5 samples at 100 Hz
      s.dv_b_mps.x() = 100.0 * s.dt_s;      // 100 m/s^2, above the 50 m/s^2 range below
      ++spiked;
    }
  }
  MultiPositionOptions options;
  options.accel_saturation_mps2 = 50.0;
  const ImuCalibrationResult a = CalibrateMultiPosition(Data(table, clean), options);
  const ImuCalibrationResult b = CalibrateMultiPosition(Data(table, spiky), options);
  ASSERT_FALSE(b.notes.empty());
  EXPECT_NE(b.notes.front().find(std::to_string(spiked) + " saturated samples"), std::string::npos) << b.notes.front();
  // Noise-free data: leaving 5 of 300 samples out of one mean changes nothing measurable.
  EXPECT_LT((Stack(a.calibration) - Stack(b.calibration)).cwiseAbs().maxCoeff(), 1e-9);
}

std::string WriteFile(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

void ExpectInputError(const std::string& record, const std::string& field) {
  try {
    CalibrateMultiPositionRecord(record);
    FAIL() << "no error for " << record;
  } catch (const InputError& e) {
    EXPECT_NE(e.field().find(field), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), record);
  }
}

// ------------------------------------------------------------- rate-table rotations

sim::TableStep Position(double roll_deg, double pitch_deg, double yaw_deg, double dwell_s) {
  sim::TableStep s;
  s.euler_rad = Eigen::Vector3d(roll_deg, pitch_deg, yaw_deg) * kDegToRad;
  s.dwell_s = dwell_s;
  return s;
}
/// A rate-table rotation of one gimbal (0 roll, 1 pitch, 2 yaw), turning rate (ramp + duration).
sim::TableStep Spin(int axis, double rate_deg_s, double duration_s, double ramp_s, double dwell_s) {
  sim::TableStep s;
  s.kind = sim::TableStep::Kind::kRotation;
  s.axis = axis;
  s.rate_radps = rate_deg_s * kDegToRad;
  s.duration_s = duration_s;
  s.ramp_s = ramp_s;
  s.dwell_s = dwell_s;
  return s;
}

/// Seven positions (z down at two headings, z up, x up, x down, y down, y up), held 10 s,
/// moves of 4 s; with `spins`, full turns of the inner gimbal (roll, 60 deg/s) at the first
/// position, of the outer (yaw, -100 deg/s) and the middle (pitch, 30 deg/s) at the fourth:
/// there they turn the IMU about its x, z and y axes. The angles stay on the branch the
/// turns leave them on (the same seven attitudes either way).
sim::MultiPositionConfig SpinTable(bool spins, double rotation_s = 4.0) {
  constexpr double kDwell_s = 10.0;
  sim::MultiPositionConfig c;
  c.rotation_s = rotation_s;
  if (!spins) {
    for (const Eigen::Vector3d& e : std::vector<Eigen::Vector3d>{
             {0, 0, 0}, {180, 0, 0}, {0, 90, 0}, {0, 0, 90}, {0, -90, 90}, {90, 0, 90}, {-90, 0, 90}}) {
      c.steps.push_back(Position(e.x(), e.y(), e.z(), kDwell_s));
    }
    return c;
  }
  c.steps = {Position(0, 0, 0, kDwell_s),        Spin(0, 100.0, 3.0, 0.6, kDwell_s),
             Position(540, 0, 0, kDwell_s),      Position(360, 90, 0, kDwell_s),
             Position(360, 0, 90, kDwell_s),     Spin(2, -100.0, 3.0, 0.6, kDwell_s),
             Spin(1, 30.0, 11.0, 1.0, kDwell_s), Position(360, 270, -270, kDwell_s),
             Position(450, 360, -270, kDwell_s), Position(270, 360, -270, kDwell_s)};
  return c;
}

TEST(MultiPositionTest, RateTableRotationsCalibrateTheGyroScaleAndMisalignment) {
  // Five IMUs (tactical errors and noise), each on the table with and without the turns.
  const std::vector<ImuSample> with = Truth(SpinTable(true)), without = Truth(SpinTable(false));
  Eigen::Matrix<double, 33, 1> ms_with = Eigen::Matrix<double, 33, 1>::Zero(), ms_without = ms_with;
  double worst = 0.0;
  for (std::uint64_t seed = 500; seed < 505; ++seed) {
    sim::InertialErrorModel* model = nullptr;
    const ImuCalibrationResult r = CalibrateMultiPosition(Data(SpinTable(true), Measure(with, Tactical(), seed, &model)));
    const Eigen::Matrix<double, 33, 1> t = Stack(Truth(*model));
    const ImuCalibrationResult r0 = CalibrateMultiPosition(Data(SpinTable(false), Measure(without, Tactical(), seed)));
    ASSERT_TRUE(r.unobservable.empty()) << r.unobservable.front();
    ASSERT_TRUE(r0.unobservable.empty()) << r0.unobservable.front();
    const Eigen::Matrix<double, 33, 1> e = Stack(r.calibration) - t, s = SigmaStack(r.calibration);
    for (int i = 0; i < 33; ++i) {
      // 165 (IMU, parameter) pairs at 4 sigma: a false alarm below 1 % (measured worst 3.1).
      EXPECT_LT(std::abs(e(i)), 4.0 * s(i)) << r.estimated[i] << " seed " << seed;
      worst = std::max(worst, std::abs(e(i)) / s(i));
    }
    ms_with += s.cwiseAbs2() / 5.0;
    ms_without += SigmaStack(r0.calibration).cwiseAbs2() / 5.0;
  }
  // The rms sigma over the five IMUs (each sigma carries its own a-posteriori variance
  // factor, ~15 % scatter with these few residuals).
  const Eigen::Matrix<double, 33, 1> ratio = (ms_without.array() / ms_with.array()).sqrt().matrix();
  std::printf("worst |error| / sigma %.2f; gyro sigma without / with the turns:\n", worst);
  for (int i = 12; i < 21; ++i) {
    std::printf("  %-22s %.3g -> %.3g (x%.2f)\n", TriadParameterName("gyro", i - 12).c_str(), std::sqrt(ms_without(i)),
                std::sqrt(ms_with(i)), ratio(i));
  }
  // A full turn about an axis accumulates 2 pi s of its scale factor error, so the scale
  // factors gain most where the table's moves turned least (z: only 90 deg moves; measured
  // x1.48, x2.27, x5.13 for x, y, z). A misalignment's cross-axis error turns with the body
  // and cancels over a full turn: the misalignments gain nothing from the turns (measured
  // x0.97 .. x1.19, the variance factors' scatter), they come from the 90/180 deg moves.
  EXPECT_GT(ratio(12), 1.2);
  EXPECT_GT(ratio(13), 2.0);
  EXPECT_GT(ratio(14), 4.0);
  for (int i = 15; i < 21; ++i) EXPECT_GT(ratio(i), 0.8) << TriadParameterName("gyro", i - 12);
}

TEST(MultiPositionTest, RateTableRotationsDoNotBiasTheEstimate) {
  // Noise-free, fixed errors. The turns are about one gimbal axis, fixed in the body, so
  // successive increments are parallel and the two-sample coning correction is exact but
  // for the Earth rate across the axis (7e-5 rad/s turning in body axes at the table rate):
  // its coning term, ~ omega_e Omega dt^2 / 2 = 6e-9 rad per sample at 100 deg/s and 100 Hz,
  // is corrected to a relative (Omega dt)^2 = 3e-4: ~1e-9 rad over the <= 1200 samples of
  // a turn, ~2e-10 in s and M (a turn is 2 pi rad). What remains is
  // the moves' truncation (cube of the move rate): 12 s moves make it 2e-9 (measured 2.3e-9
  // without the turns, 1.8e-9 with them; 5.8e-8 and 4.9e-8 with 4 s moves).
  for (const bool spins : {false, true}) {
    const sim::MultiPositionConfig table = SpinTable(spins, 12.0);
    sim::InertialErrorModel* model = nullptr;
    const std::vector<ImuSample> imu = Measure(Truth(table), Fixed(), 1, &model);
    const Eigen::Matrix<double, 33, 1> err = Stack(CalibrateMultiPosition(Data(table, imu)).calibration) - Stack(Truth(*model));
    std::printf("turns %d: |error| gyro scale/misalignment %.3g, gyro bias %.3g rad/s\n", spins ? 1 : 0,
                err.segment<9>(12).cwiseAbs().maxCoeff(), err.segment<3>(21).cwiseAbs().maxCoeff());
    EXPECT_LT(err.head<12>().cwiseAbs().maxCoeff(), 1e-12) << spins;     // accel: exact to rounding (6e-14)
    EXPECT_LT(err.segment<9>(12).cwiseAbs().maxCoeff(), 5e-9) << spins;  // the moves' 2e-9, see above
    EXPECT_LT(err.segment<3>(21).cwiseAbs().maxCoeff(), 1e-10) << spins; // rad/s (measured 2e-11)
    EXPECT_LT(err.tail<9>().cwiseAbs().maxCoeff(), 1e-10) << spins;      // (rad/s)/(m/s^2) (measured 5e-12)
  }
}

TEST(MultiPositionRecordTest, BadRecordsNameTheKey) {
  const std::string traj = "trajectory: {kind: multiposition, dwell_s: 5, steps: [{euler_deg: [0, 0, 0]}]}\n";
  ExpectInputError(WriteFile("mp_no_imu.yaml", "latitude_deg: 45\n" + traj), "imu");
  ExpectInputError(WriteFile("mp_no_traj.yaml", "imu: imu.csv\nlatitude_deg: 45\n"), "trajectory");
  ExpectInputError(WriteFile("mp_pendulum.yaml", "imu: imu.csv\nlatitude_deg: 45\ntrajectory: {kind: pendulum, length_m: 1}\n"),
                   "kind");
  ExpectInputError(WriteFile("mp_unknown.yaml", "imu: imu.csv\nlatitude_deg: 45\nrig: x\n" + traj), "rig");
}

TEST(MultiPositionRecordTest, RecordFileRoundTrip) {
  const sim::MultiPositionConfig table = Table(TwentyFourPositions(), 5.0, 3.0);
  const std::vector<ImuSample> imu = Measure(Truth(table), Fixed(), 1);
  CsvImuWriter writer(::testing::TempDir() + "/mp_imu.csv");
  for (const ImuSample& s : imu) writer.Write(s);
  writer.Commit();
  std::string steps;
  for (const Eigen::Vector3d& e : TwentyFourPositions()) {
    steps += "    - euler_deg: [" + std::to_string(e.x()) + ", " + std::to_string(e.y()) + ", " + std::to_string(e.z()) + "]\n";
  }
  const std::string record = WriteFile("mp_record.yaml", "imu: mp_imu.csv\nlatitude_deg: 45\nheight_m: 100\n"
                                                         "trajectory:\n  kind: multiposition\n  rotation_s: 3\n"
                                                         "  dwell_s: 5\n  steps:\n" + steps);
  const ImuCalibrationResult from_file = CalibrateMultiPositionRecord(record);
  const ImuCalibrationResult in_memory = CalibrateMultiPosition(Data(table, imu));
  // The CSV keeps 17 significant digits: the same solution to rounding.
  EXPECT_LT((Stack(from_file.calibration) - Stack(in_memory.calibration)).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(ImuCalibrationReportTest, NamesJsonAndText) {
  EXPECT_EQ(TriadParameterName("accel", 0), "accel.scale_factor.x");
  EXPECT_EQ(TriadParameterName("gyro", MisalignmentIndex(1, 2)), "gyro.misalignment.yz");
  EXPECT_EQ(TriadParameterName("accel", MisalignmentIndex(2, 0)), "accel.misalignment.zx");
  EXPECT_EQ(TriadParameterName("gyro", 11), "gyro.bias.z");
  EXPECT_EQ(GSensitivityParameterName(5), "g_sensitivity.yz");
  EXPECT_THROW(TriadParameterName("accel", 12), std::out_of_range);
  ImuCalibrationResult r;
  r.calibration.accel(9) = kMilliG_mps2;  // 1 mg
  r.calibration.gyro(0) = 100e-6;       // 100 ppm
  r.calibration.accel_sigma = Eigen::Matrix<double, 12, 1>::Constant(1e-6);
  r.unobservable.push_back("accel.scale_factor.x: no position puts gravity on x");
  r.positions = 6;
  const std::string json = ImuCalibrationJson(r, "multiposition");
  EXPECT_NE(json.find("\"rig\":\"multiposition\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"gyro.scale_factor.x\":{\"value\":0.0001"), std::string::npos) << json;
  EXPECT_NE(json.find("\"sigma\":null"), std::string::npos) << json;
  EXPECT_EQ(json.find("nan"), std::string::npos) << json;
  const std::string text = ImuCalibrationText(r, "multiposition");
  EXPECT_NE(text.find("accel.bias.x"), std::string::npos);
  EXPECT_NE(text.find("mg"), std::string::npos);
  EXPECT_NE(text.find("deg/h/g"), std::string::npos);
  EXPECT_NE(text.find("not observable"), std::string::npos);
}

}  // namespace calibration_multiposition_test
}  // namespace navtwin::calibration
