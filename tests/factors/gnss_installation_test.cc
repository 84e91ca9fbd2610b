// GnssAntennaPosition and GnssAntennaVelocity (factors/gnss_installation.h): with nothing
// unknown and no time offset they equal GnssPosition and GnssVelocity; at the true state of
// a fix taken with a latency they leave only the stated second-order error; their
// tangent-space Jacobians (through Linearize) match central differences at zero, a tiny
// perturbation and a random state for every choice of unknowns; the constructors' checks.
#include "factors/gnss_installation.h"

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/units.h"
#include "factors/attitude_manifold.h"
#include "factors/gnss_position.h"
#include "factors/gnss_velocity.h"
#include "factors/position_manifold.h"
#include "tests/factors/tangent_jacobian_check.h"

namespace navtwin {
namespace factors_gnss_installation_test {

using namespace tangent_check;  // Block, States, ExpectTangentJacobiansMatch, Std

const PositionManifold kPositionManifold;
const AttitudeManifold kAttitudeManifold;

// Central-difference steps: position 1 m, velocity 1e-3 m/s, lever arm 1e-3 m (the
// residuals are linear in these), attitude 1e-6 rad (truncation ~h^2 |r'''| ~ 1e-12 |r|,
// rounding ~eps |r| / h ~ 1e-10 |r|), time offset 1e-4 s (linear). 1e-7 relative to
// max(1, |J|) is far above rounding and truncation and far below real errors.
constexpr double kPosStep = 1.0, kAttStep = 1e-6, kVelStep = 1e-3, kLeverStep = 1e-3, kTauStep = 1e-4;
constexpr double kJacobianTol = 1e-7;

const Eigen::Vector3d kLever(0.8, -0.3, -1.5);
constexpr double kTau = 0.12;
const Eigen::Vector3d kOmega(0.3, -0.2, 0.5);
const Eigen::Vector3d kAccel(1.5, -0.7, 2.0);
const Eigen::Vector3d kAlpha(-0.4, 0.6, 0.2);
const Eigen::Vector3d kJerk(0.3, 0.5, -0.2);
const BodyMotion kMotion{kOmega, kAlpha, kAccel, kJerk};

/// The geodetic point at NED offset d from p (exact, through ECEF).
Eigen::Vector3d Offset(const Eigen::Vector3d& p, const Eigen::Vector3d& d_ned_m) {
  const wgs84::Geodetic g = wgs84::NedToGeodetic(d_ned_m, {p[0], p[1], p[2]});
  return Eigen::Vector3d(g.lat_rad, g.lon_rad, g.h_m);
}

GnssInstallation Installation(bool lever_arm, bool time_offset) {
  GnssInstallation x;
  x.lever_arm = lever_arm;
  x.time_offset = time_offset;
  x.lever_arm_b_m = kLever;
  x.time_offset_s = kTau;
  return x;
}

/// The unknowns' blocks at their true values (the lever arm's and tau's).
void AppendUnknowns(const GnssInstallation& x, std::vector<Block>* blocks) {
  if (x.lever_arm) {
    for (int i = 0; i < 3; ++i) blocks->push_back({{kLever[i]}, nullptr, kLeverStep});
  }
  if (x.time_offset) blocks->push_back({{kTau}, nullptr, kTauStep});
}

TEST(GnssInstallation, WithoutUnknownsAndOffsetTheModelsAreTheFixedOnes) {
  const Eigen::Vector3d pos(48.1 * kDegToRad, 11.6 * kDegToRad, 520.0);
  const Eigen::Quaterniond q = QuatFromEuler(-5.0 * kDegToRad, 10.0 * kDegToRad, 100.0 * kDegToRad);
  const Eigen::Vector3d v(12.0, -3.0, 0.5);
  GnssInstallation fixed = Installation(false, false);
  fixed.time_offset_s = 0.0;
  const Eigen::Vector3d p_meas = Offset(pos, Eigen::Vector3d(1.0, -2.0, 0.5));
  const Eigen::Vector3d sigma(0.5, 0.7, 1.1);
  const std::unique_ptr<ceres::CostFunction> a(GnssAntennaPosition::Create(p_meas, fixed, kMotion, sigma));
  const std::unique_ptr<ceres::CostFunction> b(GnssPosition::Create(p_meas, kLever, sigma));
  const Eigen::VectorXd ra = Residual(*a, {{Std(pos), nullptr, 0}, {Std(q), nullptr, 0}, {Std(v), nullptr, 0}});
  const Eigen::VectorXd rb = Residual(*b, {{Std(pos), nullptr, 0}, {Std(q), nullptr, 0}});
  EXPECT_LT((ra - rb).norm(), 1e-12 * rb.norm());
  const Eigen::Vector3d v_meas(11.0, -2.5, 0.7);
  const std::unique_ptr<ceres::CostFunction> c(GnssAntennaVelocity::Create(v_meas, fixed, kMotion, sigma));
  const std::unique_ptr<ceres::CostFunction> d(GnssVelocity::Create(v_meas, kLever, kOmega, sigma));
  const Eigen::VectorXd rc = Residual(*c, {{Std(v), nullptr, 0}, {Std(q), nullptr, 0}});
  const Eigen::VectorXd rd = Residual(*d, {{Std(v), nullptr, 0}, {Std(q), nullptr, 0}});
  EXPECT_LT((rc - rd).norm(), 1e-12 * rd.norm());
}

// A vehicle turning at a constant rate w about the vertical with constant speed s: its
// acceleration is w x v, the antenna's position and velocity at t - tau are exact (circle).
// The models at t leave the next terms of the series (the header): in position the IMU's
// snap w^3 s tau^4 / 24 and the lever arm's jerk w^3 |l_h| tau^3 / 6, in velocity
// w^3 s tau^3 / 6 and w^3 |l_h| tau^2 / 2, here 0.1 um and 6 um/s against a tau v of 2.4 m.
TEST(GnssInstallation, AtTheTruthOfADelayedFixOnlyTheSecondOrderErrorRemains) {
  const Eigen::Vector3d pos(37.45 * kDegToRad, 126.65 * kDegToRad, 300.0);
  const double w = 0.1, speed = 20.0, tau = 0.12, heading = 30.0 * kDegToRad;
  const Eigen::Vector3d lever(0.3, -0.3, -0.3);
  const auto attitude = [&](double dt) { return QuatFromEuler(0.0, 0.0, heading + w * dt); };
  const auto velocity = [&](double dt) {
    return Eigen::Vector3d(speed * std::cos(heading + w * dt), speed * std::sin(heading + w * dt), 0.0);
  };
  // The IMU's NED offset dt after t (a circle of radius speed / w).
  const auto offset = [&](double dt) {
    const double r = speed / w;
    return Eigen::Vector3d(r * (std::sin(heading + w * dt) - std::sin(heading)),
                           -r * (std::cos(heading + w * dt) - std::cos(heading)), 0.0);
  };
  const Eigen::Vector3d omega(0.0, 0.0, w);
  const Eigen::Vector3d a_n = omega.cross(velocity(0.0));
  const BodyMotion motion{omega, Eigen::Vector3d::Zero(), a_n, omega.cross(a_n)};
  const Eigen::Vector3d antenna_then = offset(-tau) + DcmFromQuat(attitude(-tau)) * lever;
  const Eigen::Vector3d v_ant_then = velocity(-tau) + DcmFromQuat(attitude(-tau)) * omega.cross(lever);
  const Eigen::Vector3d sigma = Eigen::Vector3d::Ones();  // residuals in m and m/s
  GnssInstallation x;
  x.time_offset = true;
  x.lever_arm = true;
  const std::unique_ptr<ceres::CostFunction> fp(
      GnssAntennaPosition::Create(Offset(pos, antenna_then), x, motion, sigma));
  const std::unique_ptr<ceres::CostFunction> fv(GnssAntennaVelocity::Create(v_ant_then, x, motion, sigma));
  const std::vector<Block> unknowns = {{{lever[0]}, nullptr, 0}, {{lever[1]}, nullptr, 0}, {{lever[2]}, nullptr, 0},
                                       {{tau}, nullptr, 0}};
  std::vector<Block> p_blocks = {{Std(pos), nullptr, 0}, {Std(attitude(0.0)), nullptr, 0},
                                 {Std(velocity(0.0)), nullptr, 0}};
  p_blocks.insert(p_blocks.end(), unknowns.begin(), unknowns.end());
  std::vector<Block> v_blocks = {{Std(velocity(0.0)), nullptr, 0}, {Std(attitude(0.0)), nullptr, 0}};
  v_blocks.insert(v_blocks.end(), unknowns.begin(), unknowns.end());
  const double w3 = w * w * w, l_h = lever.head<2>().norm();
  const double position_bound = w3 * w * speed * std::pow(tau, 4) / 24.0 + w3 * l_h * std::pow(tau, 3) / 6.0;
  const double velocity_bound = w3 * speed * std::pow(tau, 3) / 6.0 + 0.5 * w3 * l_h * tau * tau;
  const double position_error = Residual(*fp, p_blocks).norm();
  const double velocity_error = Residual(*fv, v_blocks).norm();
  EXPECT_LT(position_error, position_bound + 1e-6);  // plus the chart's ~1e-7 m
  EXPECT_LT(velocity_error, velocity_bound + 1e-9);
  // Without the offset the same fix is off by about tau v: the model carries the fix back.
  std::vector<Block> no_tau = p_blocks;
  no_tau.back().x = {0.0};
  EXPECT_GT(Residual(*fp, no_tau).norm(), 0.9 * speed * tau);
  EXPECT_LT(position_error, 1e-4 * speed * tau);
}

TEST(GnssInstallation, TangentJacobiansMatchCentralDifferences) {
  for (const bool lever_arm : {false, true}) {
    for (const bool time_offset : {false, true}) {
      const GnssInstallation x = Installation(lever_arm, time_offset);
      for (const State& s : States()) {
        SCOPED_TRACE(s.name + (lever_arm ? " lever arm" : "") + (time_offset ? " time offset" : ""));
        const Eigen::Vector3d p_meas = Offset(s.pos, Eigen::Vector3d(2.0, -1.0, 0.5));
        const std::unique_ptr<ceres::CostFunction> fp(
            GnssAntennaPosition::Create(p_meas, x, kMotion, Eigen::Vector3d(0.5, 0.8, 2.0)));
        std::vector<Block> p_blocks = {{Std(s.pos), &kPositionManifold, kPosStep},
                                       {Std(s.q_n_b), &kAttitudeManifold, kAttStep},
                                       {Std(s.v_n_mps), nullptr, kVelStep}};
        AppendUnknowns(x, &p_blocks);
        ExpectTangentJacobiansMatch(*fp, p_blocks, kJacobianTol);
        const std::unique_ptr<ceres::CostFunction> fv(GnssAntennaVelocity::Create(
            Eigen::Vector3d(1.0, -2.0, 0.3), x, kMotion, Eigen::Vector3d(0.05, 0.05, 0.1)));
        std::vector<Block> v_blocks = {{Std(s.v_n_mps), nullptr, kVelStep},
                                       {Std(s.q_n_b), &kAttitudeManifold, kAttStep}};
        AppendUnknowns(x, &v_blocks);
        ExpectTangentJacobiansMatch(*fv, v_blocks, kJacobianTol);
      }
    }
  }
}

TEST(GnssInstallation, TimeOffsetJacobianIsTheSeriesDerivative) {
  const State s = States().back();
  const GnssInstallation x = Installation(false, true);
  const Eigen::Vector3d sigma(0.5, 0.8, 2.0);
  const std::unique_ptr<ceres::CostFunction> fp(
      GnssAntennaPosition::Create(Offset(s.pos, Eigen::Vector3d(2, -1, 0.5)), x, kMotion, sigma));
  std::vector<Block> blocks = {{Std(s.pos), &kPositionManifold, kPosStep},
                               {Std(s.q_n_b), &kAttitudeManifold, kAttStep},
                               {Std(s.v_n_mps), nullptr, kVelStep}};
  AppendUnknowns(x, &blocks);
  const Linearization lin = LinearizeAt(*fp, blocks);
  const Eigen::Matrix3d R_n_b = DcmFromQuat(s.q_n_b);
  const Eigen::Vector3d v_ant = s.v_n_mps + R_n_b * kOmega.cross(kLever);
  const Eigen::Vector3d a_ant = kAccel + R_n_b * (kAlpha.cross(kLever) + kOmega.cross(kOmega.cross(kLever)));
  // d/dtau of -tau v_ant + tau^2 / 2 a_ant - tau^3 / 6 j.
  const Eigen::Vector3d d_position = -v_ant + kTau * a_ant - 0.5 * kTau * kTau * kJerk;
  EXPECT_LT((lin.jacobians[3].col(0) - d_position.cwiseQuotient(sigma)).norm(), 1e-12 * d_position.norm());
  const std::unique_ptr<ceres::CostFunction> fv(
      GnssAntennaVelocity::Create(Eigen::Vector3d::Zero(), x, kMotion, sigma));
  std::vector<Block> v_blocks = {{Std(s.v_n_mps), nullptr, kVelStep}, {Std(s.q_n_b), &kAttitudeManifold, kAttStep}};
  AppendUnknowns(x, &v_blocks);
  const Linearization lv = LinearizeAt(*fv, v_blocks);
  const Eigen::Vector3d d_velocity = -a_ant + kTau * kJerk;
  EXPECT_LT((lv.jacobians[2].col(0) - d_velocity.cwiseQuotient(sigma)).norm(), 1e-12 * d_velocity.norm());
}

TEST(GnssInstallation, ConstructorsRejectBadValues) {
  const GnssInstallation x = Installation(true, true);
  const Eigen::Vector3d p(0.5, 0.5, 10.0), ok(1.0, 1.0, 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(GnssAntennaPosition(p, x, kMotion, Eigen::Vector3d(1.0, 0.0, 1.0)), std::invalid_argument);
  EXPECT_THROW(GnssAntennaPosition(Eigen::Vector3d(nan, 0, 0), x, kMotion, ok), std::invalid_argument);
  BodyMotion bad_motion = kMotion;
  bad_motion.alpha_ib_b_radps2.x() = nan;
  EXPECT_THROW(GnssAntennaVelocity(ok, x, bad_motion, ok), std::invalid_argument);
  EXPECT_THROW(GnssAntennaVelocity(ok, x, kMotion, Eigen::Vector3d(-1.0, 1.0, 1.0)), std::invalid_argument);
  GnssInstallation bad = x;
  bad.time_offset_s = nan;
  EXPECT_THROW(GnssAntennaVelocity(ok, bad, kMotion, ok), std::invalid_argument);
}

}  // namespace factors_gnss_installation_test
}  // namespace navtwin
