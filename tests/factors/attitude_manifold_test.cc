// AttitudeManifold: the manifold invariants of Hertzberg et al. (those of Ceres'
// EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD, which needs gmock linked; not used here) at the
// identity, a 1e-9 rad perturbation, a random attitude and near pi.
#include "factors/attitude_manifold.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <ceres/manifold_test_utils.h>
#include <gtest/gtest.h>

#include "core/rotation.h"

namespace navtwin {
namespace factors_attitude_manifold_test {

using Vec4 = Eigen::Vector4d;  // quaternion coefficients (x, y, z, w)
using Mat43 = Eigen::Matrix<double, 4, 3, Eigen::RowMajor>;
using Mat34 = Eigen::Matrix<double, 3, 4, Eigen::RowMajor>;

// Round trips Plus/Minus only lose rounding on O(1) quaternion components (a few 1e-16
// each, doubled by the factor 2 of Log): 1e-14 absolute leaves a margin of ~10x.
constexpr double kRoundTripTol = 1e-14;
// Central differences with step h = 1e-6: truncation error ~h^2 * |f'''| ~ 1e-12 (all
// derivatives of Exp/Log are O(1) away from pi) and rounding ~eps / h ~ 1e-10, so
// 1e-8 is well above both and far below any real error (entries are 0.5 .. 2).
constexpr double kStep = 1e-6;
constexpr double kJacobianTol = 1e-8;

Vec4 Coeffs(const Eigen::Quaterniond& q) { return q.coeffs(); }

Vec4 Plus(const AttitudeManifold& m, const Vec4& x, const Eigen::Vector3d& delta) {
  Vec4 out;
  EXPECT_TRUE(m.Plus(x.data(), delta.data(), out.data()));
  return out;
}

Eigen::Vector3d Minus(const AttitudeManifold& m, const Vec4& y, const Vec4& x) {
  Eigen::Vector3d out;
  EXPECT_TRUE(m.Minus(y.data(), x.data(), out.data()));
  return out;
}

/// Distance between two quaternions as rotations (q and -q are the same attitude).
double QuatDistance(const Vec4& a, const Vec4& b) { return std::min((a - b).norm(), (a + b).norm()); }

struct Case {
  std::string name;
  Vec4 x;                 // the point
  Eigen::Vector3d delta;  // a tangent step at x
  Vec4 y;                 // a second point, y = Plus(x, psi)
};

std::vector<Case> Cases() {
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const auto random_vector = [&]() { return Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)); };
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, -2.0, 0.5).normalized();
  const Eigen::Vector3d axis2 = Eigen::Vector3d(-0.3, 0.4, 1.0).normalized();

  std::vector<Case> cases;
  const Vec4 identity = Coeffs(Eigen::Quaterniond::Identity());
  cases.push_back({"identity", identity, random_vector(), Coeffs(QuatFromRotVec<double>(random_vector()))});

  // Exercises the series branches of QuatFromRotVec / RotVecFromQuat.
  const Vec4 tiny = Coeffs(QuatFromRotVec<double>(1e-9 * axis));
  cases.push_back({"tiny", tiny, 1e-9 * axis2, Coeffs(QuatFromRotVec<double>(1e-9 * axis2) * Eigen::Quaterniond(tiny))});

  const Vec4 random = Coeffs(QuatFromRotVec<double>(3.0 * random_vector().normalized() * std::abs(uniform(rng))));
  cases.push_back({"random", random, random_vector(), Coeffs(QuatFromRotVec<double>(random_vector()) * Eigen::Quaterniond(random))});

  // x itself a rotation by nearly pi, and a step and a difference of nearly pi.
  const Vec4 near_pi = Coeffs(QuatFromRotVec<double>((M_PI - 1e-6) * axis));
  cases.push_back({"near_pi", near_pi, (M_PI - 1e-3) * axis2,
                   Coeffs(QuatFromRotVec<double>((M_PI - 1e-4) * axis) * Eigen::Quaterniond(near_pi))});
  return cases;
}

Mat43 NumericPlusJacobian(const AttitudeManifold& m, const Vec4& x) {
  Mat43 jacobian;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d h = kStep * Eigen::Vector3d::Unit(i);
    jacobian.col(i) = (Plus(m, x, h) - Plus(m, x, -h)) / (2.0 * kStep);
  }
  return jacobian;
}

// d Minus(y, x) / dy at y = x, y moved freely in R^4 (Minus is scale invariant in y).
Mat34 NumericMinusJacobian(const AttitudeManifold& m, const Vec4& x) {
  Mat34 jacobian;
  for (int i = 0; i < 4; ++i) {
    const Vec4 h = kStep * Vec4::Unit(i);
    jacobian.col(i) = (Minus(m, x + h, x) - Minus(m, x - h, x)) / (2.0 * kStep);
  }
  return jacobian;
}

TEST(AttitudeManifold, SizesAreQuaternionAndRotationVector) {
  const AttitudeManifold m;
  EXPECT_EQ(m.AmbientSize(), 4);
  EXPECT_EQ(m.TangentSize(), 3);
}

TEST(AttitudeManifold, PlusIsLeftPerturbationInNavigationFrame) {
  // Plus(x, delta) must equal Exp(delta) * R(x) as a matrix: the project's convention.
  const AttitudeManifold m;
  const Eigen::Quaterniond q = QuatFromEuler(0.1, -0.2, 2.5);
  const Eigen::Vector3d delta(0.03, -0.01, 0.2);
  const Vec4 out = Plus(m, q.coeffs(), delta);
  const Eigen::Matrix3d expected = ExpSO3<double>(delta) * q.toRotationMatrix();
  // Products of O(1) rotation matrices: rounding ~1e-16 per entry.
  EXPECT_LT((DcmFromQuat<double>(Eigen::Quaterniond(out)) - expected).norm(), 1e-14);
  // A rotation about the nav-frame down axis changes the yaw only.
  const Vec4 yawed = Plus(m, q.coeffs(), Eigen::Vector3d(0.0, 0.0, 0.3));
  const Eigen::Vector3d euler0 = EulerFromQuat(q);
  const Eigen::Vector3d euler1 = EulerFromQuat(Eigen::Quaterniond(yawed));
  EXPECT_NEAR(euler1.x(), euler0.x(), 1e-14);
  EXPECT_NEAR(euler1.y(), euler0.y(), 1e-14);
  EXPECT_NEAR(euler1.z(), euler0.z() + 0.3, 1e-14);
}

TEST(AttitudeManifold, InvariantsHold) {
  const AttitudeManifold m;
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    // Plus(x, 0) = x, Minus(x, x) = 0.
    EXPECT_LT((Plus(m, c.x, Eigen::Vector3d::Zero()) - c.x).norm(), kRoundTripTol);
    EXPECT_LT(Minus(m, c.x, c.x).norm(), kRoundTripTol);
    // Minus(Plus(x, delta), x) = delta (absolute: |delta| is 1e-9 in the tiny case).
    EXPECT_LT((Minus(m, Plus(m, c.x, c.delta), c.x) - c.delta).norm(), kRoundTripTol);
    // Plus(x, Minus(y, x)) = y up to the sign of the quaternion.
    EXPECT_LT(QuatDistance(Plus(m, c.x, Minus(m, c.y, c.x)), c.y), kRoundTripTol);
    // The sign of the stored quaternion does not matter to Minus.
    EXPECT_LT((Minus(m, -c.y, c.x) - Minus(m, c.y, c.x)).norm(), kRoundTripTol);
    EXPECT_LT((Minus(m, c.y, -c.x) - Minus(m, c.y, c.x)).norm(), kRoundTripTol);
  }
}

TEST(AttitudeManifold, JacobiansMatchCentralDifferences) {
  const AttitudeManifold m;
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    Mat43 plus_jacobian;
    Mat34 minus_jacobian;
    ASSERT_TRUE(m.PlusJacobian(c.x.data(), plus_jacobian.data()));
    ASSERT_TRUE(m.MinusJacobian(c.x.data(), minus_jacobian.data()));
    EXPECT_LT((plus_jacobian - NumericPlusJacobian(m, c.x)).norm(), kJacobianTol) << plus_jacobian;
    EXPECT_LT((minus_jacobian - NumericMinusJacobian(m, c.x)).norm(), kJacobianTol) << minus_jacobian;
    // MinusJacobian * PlusJacobian = I3 (Xi^T Xi = I for a unit quaternion): rounding only.
    EXPECT_LT((minus_jacobian * plus_jacobian - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  }
}

// Ceres' own manifold checks (ceres/manifold_test_utils.h) on the same points.
TEST(AttitudeManifold, CeresManifoldInvariantsHold) {
  using namespace ceres;  // the macro names Ceres' matchers and ceres::Vector unqualified
  const AttitudeManifold m;
  for (const Case& c : Cases()) {
    const Vector x = c.x, delta = c.delta, y = c.y;
    // At the 1e-9 rad point the quaternion holds |delta| only to ~1e-16 absolute
    // (1e-7 relative), so the relative checks get 1e-6 there and 1e-9 elsewhere.
    const double tolerance = c.name == "tiny" ? 1e-6 : 1e-9;
    EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD(m, x, delta, y, tolerance);
  }
}

}  // namespace factors_attitude_manifold_test
}  // namespace navtwin
