// The hand-placed calibration (problems/calibration/handheld.h): simulated hand-placed
// sequences (sim::HandheldSchedule) through a MEMS error model drawn per run, in memory; the
// estimates against the truth expressed in the accelerometer-defined body axes; a Monte
// Carlo of the sigma's honesty over 12-36 orientations; what too few orientations give.
#include "problems/calibration/handheld.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include <Eigen/QR>
#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/imu_error_model.h"
#include "core/rotation.h"
#include "core/sim/calibration_rig.h"
#include "core/sim/inertial_errors.h"
#include "core/sim/random.h"
#include "core/sim/analytic_trajectory.h"
#include "core/units.h"

namespace navtwin::calibration {
namespace calibration_handheld_test {

constexpr double kLat_rad = 37.45 * kDegToRad;
constexpr double kHeight_m = 300.0;
constexpr double kRate_hz = 100.0;
using Triad = Eigen::Matrix<double, 12, 1>;

/// MEMS errors drawn per run (1 sigma): the size of docs/calibration/table-mems.yaml's.
sim::InertialErrorConfig Mems() {
  sim::InertialErrorConfig c;
  c.gyro.bias.sigma = 300.0 * kDegPerHour_radps;
  c.gyro.white_noise = 0.3 * kDegToRad / 60.0;  // 0.3 deg/sqrt(h)
  c.gyro.scale_factor.sigma = 4000e-6;
  c.gyro.misalignment.sigma = 2e-3;
  c.accel.bias.sigma = 6.0 * kMilliG_mps2;
  c.accel.white_noise = 0.05 / 60.0;  // 0.05 m/s/sqrt(h)
  c.accel.scale_factor.sigma = 4000e-6;
  c.accel.misalignment.sigma = 2e-3;
  return c;
}

struct HandheldRun {
  HandheldData data;
  Triad accel_true, gyro_true;  ///< in the accelerometer-defined body axes (below)
};

Triad TriadOf(const Eigen::Matrix3d& K, const Eigen::Vector3d& bias) {
  Triad v;
  for (int r = 0; r < 3; ++r) {
    v(r) = K(r, r) - 1.0;
    v(9 + r) = bias(r);
    for (int c = 0; c < 3; ++c) {
      if (c != r) v(MisalignmentIndex(r, c)) = K(r, c);
    }
  }
  return v;
}

/// A hand-placed sequence of `positions` placements (placement seed `seed`) measured by a
/// MEMS IMU drawn with `seed`. The truth in the estimator's axes: with K_a = L R (L lower
/// triangular, R a rotation), f_m = L (R f) + b_a, so the accelerometer's is L and the body
/// axes are R's; the gyro's is K_g R^T; its bias the mean measured rate at the first
/// attitude, b_g + K_g omega_ie_b (the Earth rate is in what the still period measures).
HandheldRun Simulate(int positions, std::uint64_t seed) {
  sim::HandheldConfig h;
  h.positions = positions;
  h.placement_seed = seed;
  const sim::MultiPositionRig rig(sim::HandheldSchedule(h));
  sim::InertialErrorModel model(Mems(), sim::Rng(seed).Stream("imu"), false);
  HandheldRun run;
  run.data.latitude_rad = kLat_rad;
  run.data.height_m = kHeight_m;
  run.data.imu_path = "simulated";
  sim::SynthesizeImu(rig, wgs84::Geodetic{kLat_rad, 0.0, kHeight_m}, kRate_hz, rig.duration_s(),
                     [&](const ImuSample& s, const NavState&) {
                       if (s.dt_s <= 0.0) return;
                       ImuSample m = s;
                       model.Apply(s.t_s, s.dt_s, 25.0, s.dtheta_b_rad, s.dv_b_mps, &m.dtheta_b_rad, &m.dv_b_mps);
                       run.data.imu.push_back(m);
                     });
  const sim::DrawnTriadErrors& a = model.accel().drawn();
  const sim::DrawnTriadErrors& g = model.gyro().drawn();
  const Eigen::Matrix3d K_a = Eigen::Matrix3d::Identity() + Eigen::Matrix3d(a.scale_factor.asDiagonal()) + a.misalignment;
  const Eigen::Matrix3d K_g = Eigen::Matrix3d::Identity() + Eigen::Matrix3d(g.scale_factor.asDiagonal()) + g.misalignment;
  // K_a^T = Q U (U upper triangular, positive diagonal) -> K_a = U^T Q^T: L = U^T, R = Q^T.
  Eigen::HouseholderQR<Eigen::Matrix3d> qr(K_a.transpose());
  Eigen::Matrix3d Q = qr.householderQ();
  Eigen::Matrix3d U = qr.matrixQR().triangularView<Eigen::Upper>();
  for (int i = 0; i < 3; ++i) {
    if (U(i, i) < 0.0) {
      U.row(i) *= -1.0;
      Q.col(i) *= -1.0;
    }
  }
  const Eigen::Matrix3d R = Q.transpose();
  const Eigen::Vector3d e0 = rig.Euler_rad(0.0);
  const Eigen::Matrix3d R_n_b = DcmFromEuler(e0.x(), e0.y(), e0.z());
  const Eigen::Vector3d omega_ie_b = R_n_b.transpose() * wgs84::EarthRateNed(kLat_rad);
  run.accel_true = TriadOf(U.transpose(), a.bias);
  run.gyro_true = TriadOf(K_g * R.transpose(), g.bias + K_g * omega_ie_b);
  return run;
}

/// Per estimated parameter of `r` (the names of imu_calibration.h): |error| / sigma.
std::vector<double> ZScores(const ImuCalibrationResult& r, const HandheldRun& run) {
  std::vector<double> z;
  for (int i = 0; i < 12; ++i) {
    if (std::isfinite((*r.calibration.accel_sigma)(i))) {
      z.push_back(std::abs(r.calibration.accel(i) - run.accel_true(i)) / (*r.calibration.accel_sigma)(i));
    }
    z.push_back(std::abs(r.calibration.gyro(i) - run.gyro_true(i)) / (*r.calibration.gyro_sigma)(i));
  }
  return z;
}

TEST(HandheldCalibration, RecoversTheErrorsInTheAccelerometerAxes) {
  const HandheldRun run = Simulate(20, 3);
  StillDetection detection;
  const ImuCalibrationResult r = CalibrateHandheld(run.data, {}, &detection);
  EXPECT_EQ(detection.intervals, 21);  // the first still period and 20 placements
  EXPECT_EQ(r.estimated.size(), 21u);  // 9 accelerometer, 12 gyro
  EXPECT_EQ(r.unobservable.size(), 4u);
  const std::vector<double> z = ZScores(r, run);
  ASSERT_EQ(z.size(), 21u);
  // One draw of 21 parameters: 4 sigma leaves a false alarm below 0.2 %.
  for (std::size_t i = 0; i < z.size(); ++i) EXPECT_LT(z[i], 4.0) << "parameter " << i;
  // The calibration removes the raw errors: the gravity magnitude residual falls to the noise.
  EXPECT_LT(r.accel_residual_rms_mps2, 0.2 * kMilliG_mps2);
}

TEST(HandheldCalibration, TooFewOrientationsSayWhatIsMissing) {
  const HandheldRun run = Simulate(6, 5);
  try {
    CalibrateHandheld(run.data);
    ADD_FAILURE() << "7 orientations accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("at least 10 orientations"), std::string::npos) << e.what();
  }
}

// 100 sequences of 12-36 orientations (each its own placements and IMU): the fraction of
// (run, parameter) pairs within 3 sigma, and the sigma against the orientations.
TEST(HandheldCalibration, MonteCarloSigmaIsHonest) {
  int within = 0, total = 0;
  // Per third of the range: the mean gyro scale-factor sigma and the RMS of its error.
  double sigma_sum[3] = {0, 0, 0}, error_ss[3] = {0, 0, 0};
  int count[3] = {0, 0, 0};
  for (int k = 0; k < 100; ++k) {
    const int positions = 12 + (k * 7) % 25;
    const HandheldRun run = Simulate(positions, 1000 + static_cast<std::uint64_t>(k));
    const ImuCalibrationResult r = CalibrateHandheld(run.data);
    for (const double z : ZScores(r, run)) {
      within += z <= 3.0 ? 1 : 0;
      ++total;
    }
    const int bucket = positions < 20 ? 0 : positions < 28 ? 1 : 2;
    sigma_sum[bucket] += (*r.calibration.gyro_sigma).head<3>().mean() / 1e-6;
    error_ss[bucket] += (r.calibration.gyro.head<3>() - run.gyro_true.head<3>()).squaredNorm() / 3.0 / 1e-12;
    ++count[bucket];
  }
  const double fraction = static_cast<double>(within) / total;
  std::printf("handheld Monte Carlo: %d of %d (run, parameter) within 3 sigma: %.4f\n", within, total, fraction);
  std::printf("gyro scale factor, mean sigma / RMS error: 12-19 orientations %.0f / %.0f ppm, 20-27 %.0f / %.0f ppm, "
              "28-36 %.0f / %.0f ppm\n",
              sigma_sum[0] / count[0], std::sqrt(error_ss[0] / count[0]), sigma_sum[1] / count[1],
              std::sqrt(error_ss[1] / count[1]), sigma_sum[2] / count[2], std::sqrt(error_ss[2] / count[2]));
  RecordProperty("fraction_within_3_sigma", std::to_string(fraction));
  // Gaussian errors with honest sigma: 99.7 %; the issue asks >= 97 %.
  EXPECT_GE(fraction, 0.97);
}

}  // namespace calibration_handheld_test
}  // namespace navtwin::calibration
