// OdometerSpeed: meaning (zero for the true forward speed times the scale factor, with the
// lever-arm velocity and the mounting; a speed error gives its sigma-scaled residual),
// tangent-space Jacobians (through Linearize) against central differences at zero, a tiny
// perturbation and a random state, d r / d s = v_x / sigma, and the constructor's checks.
#include "factors/odometer_speed.h"

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
namespace factors_odometer_speed_test {

using namespace tangent_check;  // Block, States, ExpectTangentJacobiansMatch, Std

const AttitudeManifold kAttitudeManifold;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Steps and tolerance as in gnss_models_test.cc; the residual is bilinear in (v, s).
constexpr double kAttStep = 1e-6, kVelStep = 1e-3, kScaleStep = 1e-4;
constexpr double kJacobianTol = 1e-7;

double Eval(const ceres::CostFunction& f, const Eigen::Vector3d& v_n, const Eigen::Quaterniond& q, double s) {
  const std::vector<Block> blocks = {{Std(v_n), nullptr, 0.0}, {Std(q), nullptr, 0.0}, {{s}, nullptr, 0.0}};
  return Residual(f, blocks)[0];
}

TEST(OdometerSpeed, ZeroForTheScaledForwardSpeedOfTheReferencePoint) {
  const Eigen::Matrix3d R_v_b = DcmFromEuler<double>(0.0, 1 * kDegToRad, -2 * kDegToRad);
  const Eigen::Quaterniond q = QuatFromEuler<double>(3 * kDegToRad, -4 * kDegToRad, 75 * kDegToRad);
  const Eigen::Vector3d lever_b(-1.4, 0.2, 0.5), omega_b(0.01, -0.02, 0.25);
  const Eigen::Vector3d v_n(8.0, 6.0, -0.3);
  const double s = 0.004;
  const double forward = (R_v_b * (q.conjugate() * v_n + omega_b.cross(lever_b))).x();
  const std::unique_ptr<ceres::CostFunction> f(
      OdometerSpeed::Create(R_v_b, lever_b, omega_b, (1.0 + s) * forward, 0.05));
  EXPECT_LT(std::abs(Eval(*f, v_n, q, s)), 1e-12);
  // 0.1 m/s too fast a reading: -2 sigma.
  const std::unique_ptr<ceres::CostFunction> g(
      OdometerSpeed::Create(R_v_b, lever_b, omega_b, (1.0 + s) * forward + 0.1, 0.05));
  EXPECT_NEAR(Eval(*g, v_n, q, s), -2.0, 1e-12);
}

TEST(OdometerSpeed, TangentJacobiansMatchCentralDifferences) {
  const Eigen::Matrix3d R_v_b = DcmFromEuler<double>(-1 * kDegToRad, 2 * kDegToRad, 1.5 * kDegToRad);
  const Eigen::Vector3d lever_b(-1.2, 0.1, 0.4), omega_b(0.05, -0.02, 0.3);
  for (const State& st : States()) {
    SCOPED_TRACE(st.name);
    const std::unique_ptr<ceres::CostFunction> f(OdometerSpeed::Create(R_v_b, lever_b, omega_b, 7.0, 0.1));
    const double s = 0.003;
    const std::vector<Block> blocks = {{Std(st.v_n_mps), nullptr, kVelStep},
                                       {Std(st.q_n_b), &kAttitudeManifold, kAttStep},
                                       {{s}, nullptr, kScaleStep}};
    ExpectTangentJacobiansMatch(*f, blocks, kJacobianTol);
    // d r / d s = v_x / sigma.
    const Linearization lin = LinearizeAt(*f, blocks);
    const double v_x = (R_v_b * (st.q_n_b.conjugate() * st.v_n_mps + omega_b.cross(lever_b))).x();
    EXPECT_NEAR(lin.jacobians[2](0, 0), v_x / 0.1, 1e-9 * std::max(1.0, std::abs(v_x / 0.1)));
  }
}

TEST(OdometerSpeed, RejectsBadInput) {
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d z = Eigen::Vector3d::Zero();
  for (const double bad : {0.0, -1.0, kInf, std::nan("")}) EXPECT_THROW(OdometerSpeed(I, z, z, 1.0, bad), std::invalid_argument);
  EXPECT_THROW(OdometerSpeed(I, z, z, std::nan(""), 1.0), std::invalid_argument);
}

}  // namespace factors_odometer_speed_test
}  // namespace navtwin
