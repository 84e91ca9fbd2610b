// AttitudePrior: value at known points, autodiff Jacobian against central differences,
// and its tangent-space Jacobian (through AttitudeManifold) at the prior.
#include "factors/attitude_prior.h"

#include <limits>
#include <memory>
#include <stdexcept>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "factors/attitude_manifold.h"
#include "tests/factors/factor_test_util.h"

namespace navtwin {
namespace factors_attitude_prior_test {

using testing::Jacobian34;
using testing::Jacobian43;
using testing::NumericJacobian;
using testing::Residual;

// Central differences, h = 1e-6: truncation ~h^2 |r'''| and rounding ~eps |r| / h, both
// <= 1e-9 for |S| = O(10) (r''' = O(|S|)), so 1e-7 separates them from real errors.
constexpr double kJacobianTol = 1e-7;

Eigen::Matrix3d SqrtInformation() {
  // Upper triangular, as from a Cholesky factor of an information matrix (1/rad).
  Eigen::Matrix3d s;
  s << 10.0, 2.0, -1.0,
       0.0, 8.0, 0.5,
       0.0, 0.0, 3.0;
  return s;
}

TEST(AttitudePrior, ResidualIsWhitenedAttitudeError) {
  const Eigen::Quaterniond q_prior = QuatFromEuler(0.2, -0.1, 1.3);
  const Eigen::Vector3d phi_n(0.01, -0.02, 0.05);
  const Eigen::Quaterniond q = ApplyAttitudeError<double>(phi_n, q_prior);  // R = Exp(phi_n) R_prior
  const std::unique_ptr<ceres::CostFunction> f(AttitudePrior::Create(q_prior, SqrtInformation()));
  // Products of O(10) numbers: rounding ~1e-15.
  EXPECT_LT((Residual(*f, q.coeffs()) - SqrtInformation() * phi_n).norm(), 1e-13);
  EXPECT_LT(Residual(*f, q_prior.coeffs()).norm(), 1e-14);
  // Neither the sign nor the scale of the stored quaternion matters.
  EXPECT_LT((Residual(*f, -q.coeffs()) - SqrtInformation() * phi_n).norm(), 1e-13);
  EXPECT_LT((Residual(*f, 2.0 * q.coeffs()) - SqrtInformation() * phi_n).norm(), 1e-13);
}

TEST(AttitudePrior, AutodiffJacobianMatchesCentralDifferences) {
  const Eigen::Quaterniond q_prior = QuatFromEuler(-0.4, 0.3, -2.0);
  const std::unique_ptr<ceres::CostFunction> f(AttitudePrior::Create(q_prior, SqrtInformation()));
  for (const Eigen::Vector3d& phi_n : {Eigen::Vector3d(0.3, -0.2, 0.7), Eigen::Vector3d(1e-9, 0.0, -2e-9),
                                       Eigen::Vector3d(-2.0, 1.0, 1.5)}) {
    const Eigen::Vector4d q = ApplyAttitudeError<double>(phi_n, q_prior).coeffs();
    Jacobian34 autodiff;
    Residual(*f, q, &autodiff);
    EXPECT_LT((autodiff - NumericJacobian(*f, q)).norm(), kJacobianTol) << autodiff;
  }
}

TEST(AttitudePrior, TangentJacobianAtPriorIsSqrtInformation) {
  // r = S Minus(q, q_prior), so dr/d(delta) at q = q_prior is S times MinusJacobian *
  // PlusJacobian = S.
  const Eigen::Quaterniond q_prior = QuatFromEuler(0.7, 0.2, 0.1);
  const std::unique_ptr<ceres::CostFunction> f(AttitudePrior::Create(q_prior, SqrtInformation()));
  Jacobian34 ambient;
  Residual(*f, q_prior.coeffs(), &ambient);
  Jacobian43 plus;
  ASSERT_TRUE(AttitudeManifold().PlusJacobian(q_prior.coeffs().data(), plus.data()));
  EXPECT_LT((ambient * plus - SqrtInformation()).norm(), 1e-13);  // rounding on O(10) entries
}

TEST(AttitudePrior, RejectsInvalidArguments) {
  const Eigen::Matrix3d nan_matrix = Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
  EXPECT_THROW(AttitudePrior(Eigen::Quaterniond(0.0, 0.0, 0.0, 0.0), SqrtInformation()), std::invalid_argument);
  EXPECT_THROW(AttitudePrior(Eigen::Quaterniond::Identity(), nan_matrix), std::invalid_argument);
}

}  // namespace factors_attitude_prior_test
}  // namespace navtwin
