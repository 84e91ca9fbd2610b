// The multi-position calibration residuals (problems/calibration/imu_calibration_residuals.h): the
// analytic Jacobian of GyroMoveCost against autodiff of GyroMoveResidual, and the zero
// residuals at the true parameters.
#include "problems/calibration/imu_calibration_residuals.h"

#include <cmath>

#include <ceres/autodiff_cost_function.h>
#include <gtest/gtest.h>

#include "core/sim/random.h"

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

}  // namespace calibration_imu_calibration_residuals_test
}  // namespace navtwin::calibration
