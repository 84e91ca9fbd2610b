// The multi-position calibration residuals (problems/calibration/imu_calibration_residuals.h): the
// analytic Jacobian of GyroMoveCost against autodiff of GyroMoveResidual, and the zero
// residuals at the true parameters.
#include "problems/calibration/imu_calibration_residuals.h"

#include <cmath>

#include <ceres/autodiff_cost_function.h>
#include <gtest/gtest.h>

#include "core/sim/random.h"
#include "problems/calibration/imu_calibration.h"

namespace navtwin::calibration {
namespace calibration_imu_calibration_residuals_test {

using J12 = Eigen::Matrix<double, 3, kTriadParameters, Eigen::RowMajor>;
using J9 = Eigen::Matrix<double, 3, kGSensitivityParameters, Eigen::RowMajor>;

/// A 2 s coning motion at 100 Hz (rate direction turning), with specific force samples.
GyroMove ConingMove() {
  GyroMove m;
  const double dt = 0.01;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  for (int k = 1; k <= 200; ++k) {
    const double t = k * dt;
    ImuSample s;
    s.t_s = t;
    s.dt_s = dt;
    s.dtheta_b_rad = dt * Eigen::Vector3d(0.8 * std::cos(2.0 * t), 0.8 * std::sin(2.0 * t), 0.5);
    s.dv_b_mps = dt * Eigen::Vector3d(1.0, -2.0, -9.8);
    m.samples.push_back(s);
    R = R * ExpSO3(s.dtheta_b_rad);
  }
  m.R_true = R * ExpSO3(Eigen::Vector3d(1e-3, -2e-3, 5e-4));  // a residual away from 0
  m.sigma_rad = 1e-3;
  return m;
}

TEST(GyroMoveCostTest, AnalyticJacobianMatchesAutodiff) {
  const GyroMove move = ConingMove();
  sim::Rng rng(5);
  Eigen::Matrix<double, kTriadParameters, 1> gyro;
  Eigen::Matrix<double, kGSensitivityParameters, 1> g9;
  for (int i = 0; i < kTriadParameters; ++i) gyro(i) = (i < 9 ? 2e-3 : 1e-3) * rng.Normal();
  for (int i = 0; i < kGSensitivityParameters; ++i) g9(i) = 1e-4 * rng.Normal();
  const double* params[] = {gyro.data(), g9.data()};

  const GyroMoveCost analytic(&move);
  Eigen::Vector3d r_a, r_d;
  J12 Ja_g, Jd_g;
  J9 Ja_G, Jd_G;
  double* ja[] = {Ja_g.data(), Ja_G.data()};
  ASSERT_TRUE(analytic.Evaluate(params, r_a.data(), ja));

  const ceres::AutoDiffCostFunction<GyroMoveResidual, 3, kTriadParameters, kGSensitivityParameters> autodiff(
      new GyroMoveResidual(&move));
  double* jd[] = {Jd_g.data(), Jd_G.data()};
  ASSERT_TRUE(autodiff.Evaluate(params, r_d.data(), jd));

  // Same residual code path up to rounding (the analytic form normalises q every step).
  EXPECT_LT((r_a - r_d).cwiseAbs().maxCoeff(), 1e-9 * r_d.norm() + 1e-12);
  // First-order Jr terms are exact derivatives: agreement to rounding of 200-sample sums.
  const double scale = std::max(Jd_g.cwiseAbs().maxCoeff(), Jd_G.cwiseAbs().maxCoeff());
  EXPECT_LT((Ja_g - Jd_g).cwiseAbs().maxCoeff(), 1e-8 * scale) << "analytic\n" << Ja_g << "\nautodiff\n" << Jd_g;
  EXPECT_LT((Ja_G - Jd_G).cwiseAbs().maxCoeff(), 1e-8 * scale) << "analytic\n" << Ja_G << "\nautodiff\n" << Jd_G;
}

TEST(StaticResidualsTest, ZeroAtTheTrueParameters) {
  Eigen::Matrix<double, kTriadParameters, 1> p;
  for (int i = 0; i < kTriadParameters; ++i) p(i) = 1e-3 * (i + 1);
  Eigen::Matrix<double, kGSensitivityParameters, 1> g9 = Eigen::Matrix<double, 9, 1>::Constant(1e-5);
  const Eigen::Vector3d f(1.0, -2.0, -9.5), w(1e-5, 2e-5, -3e-5);
  const StaticAccelResidual a(f, MeasuredSpecificForce(p.data(), f), Eigen::Vector3d::Constant(1e-4));
  const StaticGyroResidual g(w, f, MeasuredRate(p.data(), g9.data(), w, f), Eigen::Vector3d::Constant(1e-6));
  Eigen::Vector3d r;
  ASSERT_TRUE(a(p.data(), r.data()));
  EXPECT_LT(r.norm(), 1e-9);  // rounding of 10 m/s^2 over sigma 1e-4
  ASSERT_TRUE(g(p.data(), g9.data(), r.data()));
  EXPECT_LT(r.norm(), 1e-9);
}

// The report's residual rows (imu_calibration.h StaticResiduals): a position measured
// with the calibration's own errors at its temperature has zero residual after and the raw
// error before; evaluated at another temperature the temperature terms show.
TEST(CalibrationResidualRowsTest, AfterIsZeroForTheModelsOwnErrorsAtTheirTemperature) {
  ImuCalibration c;
  c.accel << 500e-6, -300e-6, 200e-6, 1e-3, -2e-3, 0.5e-3, 1.5e-3, -1e-3, 2e-3, 0.02, -0.01, 0.03;
  c.gyro << 100e-6, 50e-6, -80e-6, 0.3e-3, -0.2e-3, 0.1e-3, 0.4e-3, -0.3e-3, 0.2e-3, 1e-4, -2e-4, 5e-5;
  c.g_sensitivity << 1e-5, 0, 0, 0, 2e-5, 0, 0, 0, -1e-5;
  TemperatureTerms t;
  t.reference_degC = 25.0;
  t.accel_bias_mps2 = {Eigen::Vector3d(1e-4, -2e-4, 3e-4)};
  t.accel_scale_factor = {Eigen::Vector3d::Zero()};
  t.gyro_bias_rad_per_s = {Eigen::Vector3d(1e-6, 2e-6, -1e-6)};
  t.gyro_scale_factor = {Eigen::Vector3d::Zero()};
  c.temperature = t;
  StaticPosition p;
  p.t0_s = 1.0;
  p.t1_s = 9.0;
  p.temperature_degC = 45.0;
  p.f_true_b_mps2 = Eigen::Vector3d(1.0, -2.0, -9.5);
  p.omega_true_b_radps = Eigen::Vector3d(3e-5, -2e-5, 6e-5);
  const ImuCalibration at = c.At(p.temperature_degC);
  p.f_mean_b_mps2 = MeasuredSpecificForce(at.accel.data(), p.f_true_b_mps2);
  p.omega_mean_b_radps = MeasuredRate(at.gyro.data(), at.g_sensitivity.data(), p.omega_true_b_radps, p.f_true_b_mps2);
  const std::vector<CalibrationResidual> rows = StaticResiduals(c, {p});
  ASSERT_EQ(rows.size(), 1u);
  // Rounding of ~10 m/s^2 and ~1e-4 rad/s values.
  EXPECT_LT(rows[0].accel_after_mps2.norm(), 1e-14);
  EXPECT_LT(rows[0].gyro_after_radps.norm(), 1e-18);
  EXPECT_LT((rows[0].accel_before_mps2 - (p.f_mean_b_mps2 - p.f_true_b_mps2)).norm(), 1e-15);
  EXPECT_EQ(rows[0].t0_s, 1.0);
  EXPECT_EQ(rows[0].temperature_degC, 45.0);
  // Taken at the reference temperature instead, the 20 degC of bias slope remain.
  p.temperature_degC = 25.0;
  const CalibrationResidual wrong = StaticResiduals(c, {p}).front();
  EXPECT_NEAR(wrong.accel_after_mps2.x(), 20.0 * 1e-4, 1e-12);
  EXPECT_NEAR(wrong.gyro_after_radps.y(), 20.0 * 2e-6, 1e-15);
}

}  // namespace calibration_imu_calibration_residuals_test
}  // namespace navtwin::calibration
