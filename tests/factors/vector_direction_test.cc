// VectorDirection: value at known points, autodiff Jacobian against central differences,
// and its tangent-space Jacobian (through AttitudeManifold).
#include "factors/vector_direction.h"

#include <limits>
#include <memory>
#include <stdexcept>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "factors/attitude_manifold.h"
#include "tests/factors/factor_test_util.h"

namespace navtwin {
namespace factors_vector_direction_test {

using testing::Jacobian34;
using testing::Jacobian43;
using testing::NumericJacobian;
using testing::Residual;

// Central differences, h = 1e-6: truncation ~h^2 |r'''| and rounding ~eps |r| / h, both
// <= 1e-8 for sigma = 0.05 (|r| and its derivatives are O(1/sigma) = 20), so 1e-6
// separates them from real errors (Jacobian entries are O(20)).
constexpr double kJacobianTol = 1e-6;
constexpr double kSigma = 0.05;

TEST(VectorDirection, ResidualAtKnownAttitudes) {
  // Yaw +90 deg: body forward (x) points east, body right (y) points south.
  const Eigen::Quaterniond q_yaw90 = QuatFromEuler(0.0, 0.0, M_PI / 2.0);
  const Eigen::Vector3d forward_b(1.0, 0.0, 0.0), right_b(0.0, 1.0, 0.0);
  const Eigen::Vector3d north_n(1.0, 0.0, 0.0), east_n(0.0, 1.0, 0.0);
  const std::unique_ptr<ceres::CostFunction> matching(VectorDirection::Create(forward_b, east_n, kSigma));
  const std::unique_ptr<ceres::CostFunction> right_vs_north(VectorDirection::Create(right_b, north_n, kSigma));
  // Entries are O(1/sigma) = 20; rounding of cos/sin(pi/2) gives ~1e-15.
  EXPECT_LT(Residual(*matching, q_yaw90.coeffs()).norm(), 1e-14);
  EXPECT_LT((Residual(*right_vs_north, q_yaw90.coeffs()) - Eigen::Vector3d(-2.0, 0.0, 0.0) / kSigma).norm(),
            1e-13);
  // Not sensitive to the scale of the stored quaternion (R is taken from the normalised q).
  EXPECT_LT((Residual(*right_vs_north, 3.0 * q_yaw90.coeffs()) - Eigen::Vector3d(-2.0, 0.0, 0.0) / kSigma).norm(),
            1e-13);
}

TEST(VectorDirection, AutodiffJacobianMatchesCentralDifferences) {
  const Eigen::Vector3d u_b = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const Eigen::Vector3d r_n = Eigen::Vector3d(-0.2, 0.1, 0.9).normalized();
  const std::unique_ptr<ceres::CostFunction> f(VectorDirection::Create(u_b, r_n, kSigma));
  for (const Eigen::Vector3d& euler : {Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::Vector3d(-1.0, 1.2, -3.0),
                                       Eigen::Vector3d(0.0, 0.0, 0.0)}) {
    const Eigen::Vector4d q = QuatFromEuler(euler.x(), euler.y(), euler.z()).coeffs();
    Jacobian34 autodiff;
    Residual(*f, q, &autodiff);
    EXPECT_LT((autodiff - NumericJacobian(*f, q)).norm(), kJacobianTol) << autodiff;
  }
}

TEST(VectorDirection, TangentJacobianIsMinusSkewOfRotatedObservation) {
  // d/d(phi) [Exp(phi) R u_b - r_n] / sigma = -[R u_b]x / sigma (left perturbation).
  const Eigen::Vector3d u_b = Eigen::Vector3d(0.6, 0.0, -0.8);
  const std::unique_ptr<ceres::CostFunction> f(VectorDirection::Create(u_b, Eigen::Vector3d::UnitZ(), kSigma));
  const Eigen::Quaterniond q = QuatFromEuler(0.4, -0.3, 2.2);
  Jacobian34 ambient;
  Residual(*f, q.coeffs(), &ambient);
  Jacobian43 plus;
  ASSERT_TRUE(AttitudeManifold().PlusJacobian(q.coeffs().data(), plus.data()));
  const Eigen::Matrix3d expected = -Skew<double>(q * u_b) / kSigma;
  EXPECT_LT((ambient * plus - expected).norm(), 1e-13);  // rounding on O(20) entries
}

TEST(VectorDirection, RejectsInvalidSigma) {
  const Eigen::Vector3d u = Eigen::Vector3d::UnitX();
  EXPECT_THROW(VectorDirection(u, u, 0.0), std::invalid_argument);
  EXPECT_THROW(VectorDirection(u, u, -0.1), std::invalid_argument);
  EXPECT_THROW(VectorDirection(u, u, std::numeric_limits<double>::infinity()), std::invalid_argument);
  EXPECT_THROW(VectorDirection(u, Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()), 0.1),
               std::invalid_argument);
}

}  // namespace factors_vector_direction_test
}  // namespace navtwin
