// MagEllipsoid: meaning (zero on the ellipsoid of the true hard and soft iron, first order
// off it), Jacobians of all three blocks against central differences and against the
// closed form of the header at the zero-residual point, a tiny perturbation of it and a
// random point (fixed seed), the finite value at A (m - h) = 0, and the constructor's checks.
#include "problems/calibration/mag_ellipsoid.h"

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>
#include <Eigen/Core>
#include <Eigen/LU>

namespace navtwin::calibration {
namespace calibration_mag_ellipsoid_test {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Parameters (h, A_sym, B) as one 10-vector, in block order.
using Params = Eigen::Matrix<double, 10, 1>;
using Jacobian = Eigen::Matrix<double, 1, 10>;

double Eval(const ceres::CostFunction& f, const Params& p, Jacobian* jacobian = nullptr) {
  const double* parameters[] = {p.data(), p.data() + 3, p.data() + 9};
  Eigen::Matrix<double, 1, 3, Eigen::RowMajor> jh;
  Eigen::Matrix<double, 1, 6, Eigen::RowMajor> ja;
  double jb = 0.0;
  double* jacobians[] = {jh.data(), ja.data(), &jb};
  double r = 0.0;
  EXPECT_TRUE(f.Evaluate(parameters, &r, jacobian != nullptr ? jacobians : nullptr));
  if (jacobian != nullptr) *jacobian << jh, ja, jb;
  return r;
}

/// Central differences, step 1e-6 in every coordinate (uT for h and B, 1 for A).
Jacobian Numeric(const ceres::CostFunction& f, const Params& p) {
  constexpr double kStep = 1e-6;
  Jacobian j;
  for (int i = 0; i < 10; ++i) {
    const Params d = kStep * Params::Unit(i);
    j(i) = (Eval(f, p + d) - Eval(f, p - d)) / (2.0 * kStep);
  }
  return j;
}

/// The header's closed form: dr/dh = -(u^T A)/sigma, dr/dA_ij = u_i d_j / sigma (symmetric
/// entries summed), dr/dB = -1/sigma.
Jacobian ClosedForm(const Eigen::Vector3d& m, const Params& p, double sigma) {
  const Eigen::Vector3d h = p.head<3>();
  const Eigen::Matrix3d A = MagEllipsoid::SymmetricFromUpper(p.data() + 3);
  const Eigen::Vector3d d = m - h;
  const Eigen::Vector3d u = (A * d).normalized();
  Jacobian j;
  j.head<3>() = -(u.transpose() * A) / sigma;
  j(3) = u(0) * d(0);
  j(4) = u(0) * d(1) + u(1) * d(0);
  j(5) = u(0) * d(2) + u(2) * d(0);
  j(6) = u(1) * d(1);
  j(7) = u(1) * d(2) + u(2) * d(1);
  j(8) = u(2) * d(2);
  j.segment<6>(3) /= sigma;
  j(9) = -1.0 / sigma;
  return j;
}

Params Truth() {
  Params p;
  p << 12.0, -25.0, 18.0,                  // h, uT
      0.96, 0.03, -0.02, 1.04, 0.05, 0.99,  // A = (I + S)^-1 for a small symmetric S
      50.0;                                 // B, uT
  return p;
}

/// A sample on the truth's ellipsoid: m = A^-1 B u + h for the unit direction u.
Eigen::Vector3d OnEllipsoid(const Params& p, const Eigen::Vector3d& u) {
  const Eigen::Matrix3d A = MagEllipsoid::SymmetricFromUpper(p.data() + 3);
  return A.inverse() * (p(9) * u.normalized()) + p.head<3>();
}

// The residual is |v| - B with |v| ~ 50 uT (sigma 0.5: r ~ 100): central differences with
// step 1e-6 have truncation ~h^2 |r'''| ~ 1e-12 * 1e2 and rounding ~eps |r| / h ~ 2e-8, so
// 1e-6 is safely above both and far below any real error (Jacobian entries are 0.1 - 100).
constexpr double kJacobianTol = 1e-6;

void ExpectJacobianMatches(const Eigen::Vector3d& m, const Params& p, double sigma) {
  const std::unique_ptr<ceres::CostFunction> f(MagEllipsoid::Create(m, sigma));
  Jacobian analytic;
  Eval(*f, p, &analytic);
  const Jacobian numeric = Numeric(*f, p);
  const Jacobian closed = ClosedForm(m, p, sigma);
  for (int i = 0; i < 10; ++i) {
    const double scale = std::max(1.0, std::abs(numeric(i)));
    EXPECT_NEAR(analytic(i), numeric(i), kJacobianTol * scale) << "column " << i;
    EXPECT_NEAR(analytic(i), closed(i), 1e-12 * scale) << "column " << i;  // same formula: rounding only
  }
}

TEST(MagEllipsoid, ZeroOnTheTrueEllipsoidAndFirstOrderOffIt) {
  const Params p = Truth();
  const double sigma = 0.5;
  for (const Eigen::Vector3d& u : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0.3, -0.8, 0.5),
                                   Eigen::Vector3d(-0.1, 0.2, -1.0)}) {
    const Eigen::Vector3d m = OnEllipsoid(p, u);
    const std::unique_ptr<ceres::CostFunction> f(MagEllipsoid::Create(m, sigma));
    EXPECT_NEAR(Eval(*f, p), 0.0, 1e-12);  // rounding of 50 uT / 0.5
    // A raw sample moved by A^-1 u: the calibrated field grows by exactly 1 uT along u.
    const Eigen::Matrix3d A = MagEllipsoid::SymmetricFromUpper(p.data() + 3);
    const Eigen::Vector3d out = m + A.inverse() * u.normalized();
    const std::unique_ptr<ceres::CostFunction> g(MagEllipsoid::Create(out, sigma));
    EXPECT_NEAR(Eval(*g, p), 1.0 / sigma, 1e-12);
  }
}

TEST(MagEllipsoid, JacobianAtTheZeroResidualPoint) {
  const Params p = Truth();
  ExpectJacobianMatches(OnEllipsoid(p, Eigen::Vector3d(0.4, 0.5, -0.7)), p, 0.5);
}

TEST(MagEllipsoid, JacobianAtATinyPerturbation) {
  Params p = Truth();
  const Eigen::Vector3d m = OnEllipsoid(p, Eigen::Vector3d(-0.6, 0.1, 0.8));
  p += 1e-6 * Params::Ones();
  ExpectJacobianMatches(m, p, 0.5);
}

TEST(MagEllipsoid, JacobianAtRandomPoints) {
  std::mt19937 rng(20240807);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int k = 0; k < 20; ++k) {
    Params p = Truth();
    for (int i = 0; i < 3; ++i) p(i) += 10.0 * normal(rng);
    for (int i = 3; i < 9; ++i) p(i) += 0.1 * normal(rng);
    p(9) += 5.0 * normal(rng);
    const Eigen::Vector3d m(40.0 * normal(rng), 40.0 * normal(rng), 40.0 * normal(rng));
    ExpectJacobianMatches(m, p, 0.3 + 0.1 * k);
  }
}

TEST(MagEllipsoid, FiniteWhereTheCalibratedFieldIsZero) {
  Params p = Truth();
  const Eigen::Vector3d m = p.head<3>();  // m = h: A (m - h) = 0, no direction
  const std::unique_ptr<ceres::CostFunction> f(MagEllipsoid::Create(m, 0.5));
  Jacobian j;
  EXPECT_DOUBLE_EQ(Eval(*f, p, &j), -p(9) / 0.5);
  EXPECT_TRUE(j.allFinite());
  EXPECT_DOUBLE_EQ(j(9), -1.0 / 0.5);
}

TEST(MagEllipsoid, RejectsBadArguments) {
  EXPECT_THROW(MagEllipsoid(Eigen::Vector3d::Zero(), 0.0), std::invalid_argument);
  EXPECT_THROW(MagEllipsoid(Eigen::Vector3d::Zero(), -1.0), std::invalid_argument);
  EXPECT_THROW(MagEllipsoid(Eigen::Vector3d::Zero(), kNaN), std::invalid_argument);
  EXPECT_THROW(MagEllipsoid(Eigen::Vector3d(kNaN, 0, 0), 1.0), std::invalid_argument);
}

}  // namespace calibration_mag_ellipsoid_test
}  // namespace navtwin::calibration
