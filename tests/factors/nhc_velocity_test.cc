// NhcVelocity: meaning (zero for a vehicle moving along its x axis, whatever its attitude,
// with the lever-arm velocity of the reference point; a lateral or vertical velocity gives
// its sigma-scaled residual; the mounting rotates the constraint), tangent-space Jacobians
// (through Linearize) against central differences at zero, a tiny perturbation and a random
// state, and the constructor's checks.
#include "factors/nhc_velocity.h"

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "core/units.h"
#include "factors/attitude_manifold.h"
#include "solvers/linearize.h"
#include "tests/factors/tangent_jacobian_check.h"

namespace navtwin {
namespace factors_nhc_velocity_test {

using namespace tangent_check;  // Block, States, ExpectTangentJacobiansMatch, Std

const AttitudeManifold kAttitudeManifold;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Central-difference steps and tolerance as in gnss_models_test.cc (the residual is linear
// in v and smooth in the attitude; |r| <= ~300 here).
constexpr double kAttStep = 1e-6, kVelStep = 1e-3;
constexpr double kJacobianTol = 1e-7;

Eigen::Vector2d Eval(const ceres::CostFunction& f, const Eigen::Vector3d& v_n, const Eigen::Quaterniond& q) {
  const std::vector<Block> blocks = {{Std(v_n), nullptr, 0.0}, {Std(q), nullptr, 0.0}};
  return Residual(f, blocks);
}

TEST(NhcVelocity, ZeroForMotionAlongTheVehicleAxis) {
  const Eigen::Quaterniond q = QuatFromEuler<double>(5 * kDegToRad, -3 * kDegToRad, 130 * kDegToRad);
  const Eigen::Vector3d v_n = q * Eigen::Vector3d(12.0, 0.0, 0.0);
  const std::unique_ptr<ceres::CostFunction> f(
      NhcVelocity::Create(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, 0.3),
                          0.1, 0.2));
  EXPECT_LT(Eval(*f, v_n, q).norm(), 1e-12);
}

TEST(NhcVelocity, LateralAndVerticalVelocityGiveTheirSigmas) {
  const Eigen::Quaterniond q = QuatFromEuler<double>(0.0, 0.0, 40 * kDegToRad);
  const Eigen::Vector3d v_b(10.0, 0.3, -0.4);
  const std::unique_ptr<ceres::CostFunction> f(
      NhcVelocity::Create(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.1, 0.2));
  const Eigen::Vector2d r = Eval(*f, q * v_b, q);
  EXPECT_NEAR(r[0], 3.0, 1e-12);   // 0.3 / 0.1
  EXPECT_NEAR(r[1], -2.0, 1e-12);  // -0.4 / 0.2
}

TEST(NhcVelocity, LeverArmAndMountingEnterAsInTheModel) {
  // The IMU yawed 90 deg in the vehicle (its x axis points to the vehicle's right): the
  // vehicle moves along its own x, which is the body's -y.
  const Eigen::Matrix3d R_v_b = DcmFromEuler<double>(0.0, 0.0, 90 * kDegToRad);
  const Eigen::Quaterniond q = QuatFromEuler<double>(0.0, 0.0, 10 * kDegToRad);
  const Eigen::Vector3d lever_b(0.0, 1.5, 0.0), omega_b(0.0, 0.0, 0.2);
  // Body velocity such that the reference point moves along the vehicle x only.
  const Eigen::Vector3d v_ref_b = R_v_b.transpose() * Eigen::Vector3d(8.0, 0.0, 0.0);
  const Eigen::Vector3d v_b = v_ref_b - omega_b.cross(lever_b);
  const std::unique_ptr<ceres::CostFunction> f(NhcVelocity::Create(R_v_b, lever_b, omega_b, 0.1, 0.1));
  EXPECT_LT(Eval(*f, q * v_b, q).norm(), 1e-12);
  // Without the lever-arm velocity the same state violates the constraint.
  const std::unique_ptr<ceres::CostFunction> g(
      NhcVelocity::Create(R_v_b, Eigen::Vector3d::Zero(), omega_b, 0.1, 0.1));
  EXPECT_GT(Eval(*g, q * v_b, q).norm(), 1.0);
}

TEST(NhcVelocity, TangentJacobiansMatchCentralDifferences) {
  const Eigen::Matrix3d R_v_b = DcmFromEuler<double>(1 * kDegToRad, -2 * kDegToRad, 3 * kDegToRad);
  const Eigen::Vector3d lever_b(-1.2, 0.1, 0.4), omega_b(0.05, -0.02, 0.3);
  for (const State& s : States()) {
    SCOPED_TRACE(s.name);
    const std::unique_ptr<ceres::CostFunction> f(NhcVelocity::Create(R_v_b, lever_b, omega_b, 0.1, 0.05));
    const std::vector<Block> blocks = {{Std(s.v_n_mps), nullptr, kVelStep},
                                       {Std(s.q_n_b), &kAttitudeManifold, kAttStep}};
    ExpectTangentJacobiansMatch(*f, blocks, kJacobianTol);
  }
}

TEST(NhcVelocity, RejectsBadInput) {
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d z = Eigen::Vector3d::Zero();
  for (const double bad : {0.0, -1.0, kInf, std::nan("")}) {
    EXPECT_THROW(NhcVelocity(I, z, z, bad, 1.0), std::invalid_argument) << bad;
    EXPECT_THROW(NhcVelocity(I, z, z, 1.0, bad), std::invalid_argument) << bad;
  }
  EXPECT_THROW(NhcVelocity(I, Eigen::Vector3d(kInf, 0, 0), Eigen::Vector3d(0, 0, 1), 1.0, 1.0),
               std::invalid_argument);
}

}  // namespace factors_nhc_velocity_test
}  // namespace navtwin
