// GnssPosition and GnssVelocity: meaning (zero residual for the true state with a lever arm
// and a rotated attitude; a 1 m north / 0.1 m/s east error gives +1 sigma-scaled residual),
// tangent-space Jacobians (through Linearize) against central differences at zero, a tiny
// perturbation and a random state, and the constructor's checks.
#include "factors/gnss_position.h"
#include "factors/gnss_velocity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/units.h"
#include "factors/attitude_manifold.h"
#include "factors/position_manifold.h"
#include "solvers/linearize.h"
#include "tests/factors/tangent_jacobian_check.h"

namespace navtwin {
namespace factors_gnss_models_test {

using namespace tangent_check;  // Block, States, ExpectTangentJacobiansMatch, Std

const PositionManifold kPositionManifold;
const AttitudeManifold kAttitudeManifold;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Central-difference steps: position 1 m (the residuals are linear in the NED tangent:
// rounding ~eps |lat| R / 1 m ~ 1e-9), attitude 1e-6 rad (truncation ~h^2 |r'''| ~ 1e-12
// |r|, rounding ~eps |r| / h ~ 1e-10 |r|), velocity 1e-3 m/s (linear). With |r| <= ~20
// here, 1e-7 relative to max(1, |J|) is far above both and far below real errors.
constexpr double kPosStep = 1.0, kAttStep = 1e-6, kVelStep = 1e-3;
constexpr double kJacobianTol = 1e-7;

/// The geodetic point at NED offset d from p (exact, through ECEF).
Eigen::Vector3d Offset(const Eigen::Vector3d& p, const Eigen::Vector3d& d_ned_m) {
  const wgs84::Geodetic g = wgs84::NedToGeodetic(d_ned_m, {p[0], p[1], p[2]});
  return Eigen::Vector3d(g.lat_rad, g.lon_rad, g.h_m);
}

Eigen::Vector3d Eval(const ceres::CostFunction& f, const Eigen::Vector3d& a, const Eigen::Quaterniond& q) {
  const std::vector<Block> blocks = {{Std(a), nullptr, 0.0}, {Std(q), nullptr, 0.0}};
  return Residual(f, blocks);
}

TEST(GnssPosition, ZeroForTheTrueStateWithLeverArmAndAttitude) {
  const Eigen::Vector3d pos(48.1 * kDegToRad, 11.6 * kDegToRad, 520.0);
  const Eigen::Quaterniond q = QuatFromEuler(-5.0 * kDegToRad, 10.0 * kDegToRad, 100.0 * kDegToRad);
  const Eigen::Vector3d lever_b(0.8, -0.3, -1.5);
  // The antenna's true geodetic position, exact through ECEF.
  const Eigen::Vector3d p_ant = Offset(pos, DcmFromQuat(q) * lever_b);
  const std::unique_ptr<ceres::CostFunction> f(GnssPosition::Create(p_ant, lever_b, Eigen::Vector3d(0.5, 0.5, 1.0)));
  // The chart's second-order error over |l| = 1.7 m: ~|l|^2 / R ~ 5e-7 m, / 0.5 m sigma.
  EXPECT_LT(Eval(*f, pos, q).norm(), 2e-6);
  // A wrong attitude moves the predicted antenna: a yaw error of 90 deg moves it by
  // (Rz(90) - I) R l, so the residual is far from zero.
  const Eigen::Quaterniond q_wrong = ApplyAttitudeError<double>(Eigen::Vector3d(0, 0, M_PI / 2), q);
  EXPECT_GT(Eval(*f, pos, q_wrong).norm(), 1.0);
}

TEST(GnssPosition, OneMetreNorthErrorGivesPlusOneSigma) {
  const Eigen::Vector3d truth(-33.9 * kDegToRad, 151.2 * kDegToRad, 40.0);
  const Eigen::Quaterniond q = QuatFromEuler(2.0 * kDegToRad, -3.0 * kDegToRad, -140.0 * kDegToRad);
  const Eigen::Vector3d lever_b(0.2, 0.1, -0.9);
  const Eigen::Vector3d sigma(0.5, 0.8, 2.0);
  const Eigen::Vector3d p_ant = Offset(truth, DcmFromQuat(q) * lever_b);
  const std::unique_ptr<ceres::CostFunction> f(GnssPosition::Create(p_ant, lever_b, sigma));
  // Estimate 1 m north of the truth: predicted minus measured = +1 m north.
  // Chart error ~ (1 m + |l|)^2 / R ~ 1e-6 m.
  const Eigen::Vector3d r_north = Eval(*f, Offset(truth, Eigen::Vector3d(1, 0, 0)), q);
  EXPECT_NEAR(r_north.x(), 1.0 / sigma.x(), 1e-5);
  EXPECT_NEAR(r_north.y(), 0.0, 1e-5);
  EXPECT_NEAR(r_north.z(), 0.0, 1e-5);
  // 2 m up: the down residual is -2 m / sigma_d.
  const Eigen::Vector3d r_up = Eval(*f, Offset(truth, Eigen::Vector3d(0, 0, -2)), q);
  EXPECT_NEAR(r_up.z(), -2.0 / sigma.z(), 1e-5);
  EXPECT_NEAR(r_up.head<2>().norm(), 0.0, 1e-5);
}

TEST(GnssPosition, TangentJacobiansMatchCentralDifferences) {
  const Eigen::Vector3d lever_b(0.5, -0.3, -1.2), sigma(0.5, 0.6, 1.2);
  for (const State& s : States()) {
    SCOPED_TRACE(s.name);
    // Measurement a few metres from the prediction so that the residual is not zero.
    const Eigen::Vector3d p_meas = Offset(s.pos, Eigen::Vector3d(1.5, -2.0, 0.7));
    const std::unique_ptr<ceres::CostFunction> f(GnssPosition::Create(p_meas, lever_b, sigma));
    const std::vector<Block> blocks = {{Std(s.pos), &kPositionManifold, kPosStep},
                                       {Std(s.q_n_b), &kAttitudeManifold, kAttStep}};
    ExpectTangentJacobiansMatch(*f, blocks, kJacobianTol);
    // In the tangent, d r / d dp_ned = diag(1/sigma) up to the radii ratio at pos vs
    // p_meas (a few metres apart: ~1e-6 relative), and d r / d phi = -[R l]x / sigma
    // (d(Exp(phi) R l) = phi x R l).
    const Linearization lin = LinearizeAt(*f, blocks);
    const Eigen::Matrix3d inv_sigma = sigma.cwiseInverse().asDiagonal();
    EXPECT_LT((lin.jacobians[0] - inv_sigma).norm(), 1e-5);
    const Eigen::Vector3d l_n = DcmFromQuat(s.q_n_b) * lever_b;
    EXPECT_LT((lin.jacobians[1] + inv_sigma * Skew<double>(l_n)).norm(), 1e-12);
  }
}

TEST(GnssPosition, RejectsBadSigma) {
  const Eigen::Vector3d p(0.5, 0.1, 10.0), l(0, 0, 0);
  for (const double bad : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_THROW(GnssPosition(p, l, bad), std::invalid_argument) << bad;
    EXPECT_THROW(GnssPosition(p, l, Eigen::Vector3d(1.0, bad, 1.0)), std::invalid_argument) << bad;
  }
  EXPECT_THROW(GnssPosition(Eigen::Vector3d(kNaN, 0, 0), l, 1.0), std::invalid_argument);
  EXPECT_NO_THROW(GnssPosition(p, l, 1e-3));
}

TEST(GnssVelocity, ZeroForTheTrueStateWithLeverArmRotation) {
  // Heading east (yaw 90 deg), turning right at 0.5 rad/s, antenna 2 m ahead: the antenna
  // moves 0.5 * 2 = 1 m/s to the right of the heading, i.e. south.
  const Eigen::Quaterniond q = QuatFromEuler(0.0, 0.0, M_PI / 2);
  const Eigen::Vector3d v(0.3, 15.0, -0.2), lever_b(2.0, 0.0, 0.0), omega_b(0.0, 0.0, 0.5);
  const Eigen::Vector3d v_ant = v + Eigen::Vector3d(-1.0, 0.0, 0.0);
  const std::unique_ptr<ceres::CostFunction> f(GnssVelocity::Create(v_ant, lever_b, omega_b, 0.1));
  EXPECT_LT(Eval(*f, v, q).norm(), 1e-13);  // rounding of O(10) m/s sums, / 0.1
  // Same with a general attitude, rate and lever arm, against v + R (omega x l) formed here.
  const Eigen::Quaterniond q2 = QuatFromEuler(0.3, -0.2, 2.0);
  const Eigen::Vector3d l2(0.4, -0.7, -1.1), w2(0.2, -0.1, 0.3);
  const std::unique_ptr<ceres::CostFunction> f2(
      GnssVelocity::Create(v + DcmFromQuat(q2) * w2.cross(l2), l2, w2, Eigen::Vector3d(0.1, 0.2, 0.3)));
  EXPECT_LT(Eval(*f2, v, q2).norm(), 1e-13);
}

TEST(GnssVelocity, EastErrorGivesPlusOneSigma) {
  const Eigen::Quaterniond q = QuatFromEuler(0.1, 0.05, -1.0);
  const Eigen::Vector3d v(10.0, -4.0, 0.5), lever_b(0.5, 0.5, -1.0), omega_b(0.01, 0.02, -0.3);
  const Eigen::Vector3d sigma(0.05, 0.1, 0.2);
  const std::unique_ptr<ceres::CostFunction> f(
      GnssVelocity::Create(v + DcmFromQuat(q) * omega_b.cross(lever_b), lever_b, omega_b, sigma));
  const Eigen::Vector3d r = Eval(*f, v + Eigen::Vector3d(0.0, 0.1, 0.0), q);
  // Rounding of O(10) m/s differences, / 0.05: ~1e-14.
  EXPECT_NEAR(r.x(), 0.0, 1e-12);
  EXPECT_NEAR(r.y(), 1.0, 1e-12);  // 0.1 m/s / 0.1 m/s
  EXPECT_NEAR(r.z(), 0.0, 1e-12);
}

TEST(GnssVelocity, TangentJacobiansMatchCentralDifferences) {
  const Eigen::Vector3d lever_b(1.0, -0.5, -1.5), omega_b(0.3, -0.2, 0.8), sigma(0.05, 0.05, 0.1);
  for (const State& s : States()) {
    SCOPED_TRACE(s.name);
    const std::unique_ptr<ceres::CostFunction> f(
        GnssVelocity::Create(s.v_n_mps + Eigen::Vector3d(0.05, -0.1, 0.02), lever_b, omega_b, sigma));
    const std::vector<Block> blocks = {{Std(s.v_n_mps), nullptr, kVelStep},
                                       {Std(s.q_n_b), &kAttitudeManifold, kAttStep}};
    ExpectTangentJacobiansMatch(*f, blocks, kJacobianTol);
    // d r / d v = diag(1/sigma); d r / d phi = -[R (omega x l)]x / sigma.
    const Linearization lin = LinearizeAt(*f, blocks);
    const Eigen::Matrix3d inv_sigma = sigma.cwiseInverse().asDiagonal();
    EXPECT_LT((lin.jacobians[0] - inv_sigma).norm(), 1e-12);
    const Eigen::Vector3d u_n = DcmFromQuat(s.q_n_b) * omega_b.cross(lever_b);
    EXPECT_LT((lin.jacobians[1] + inv_sigma * Skew<double>(u_n)).norm(), 1e-12);
  }
}

TEST(GnssVelocity, RejectsBadSigma) {
  const Eigen::Vector3d z = Eigen::Vector3d::Zero();
  for (const double bad : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_THROW(GnssVelocity(z, z, z, bad), std::invalid_argument) << bad;
    EXPECT_THROW(GnssVelocity(z, z, z, Eigen::Vector3d(bad, 1.0, 1.0)), std::invalid_argument) << bad;
  }
  EXPECT_THROW(GnssVelocity(z, z, Eigen::Vector3d(0, kInf, 0), 1.0), std::invalid_argument);
}

}  // namespace factors_gnss_models_test
}  // namespace navtwin
