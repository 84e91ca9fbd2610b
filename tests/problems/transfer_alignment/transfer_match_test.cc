// TransferMatch (problems/transfer_alignment/transfer_match.h): zero residual at the truth of a master in
// uniform rotation and acceleration (where the delay series is exact), the meaning of the
// delay and misalignment derivatives, tangent-space Jacobians (AutoDiff through Linearize)
// against central differences at zero, a tiny perturbation and a random point, and the
// constructor's checks.
#include "problems/transfer_alignment/transfer_match.h"

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "factors/attitude_manifold.h"
#include "solvers/linearize.h"
#include "tests/factors/tangent_jacobian_check.h"

namespace navtwin::transfer {
namespace transfer_alignment_transfer_match_test {

using namespace tangent_check;  // Block, States, ExpectTangentJacobiansMatch, Std
using transfer::DelayOrder;
using transfer::MasterKinematics;

const AttitudeManifold kAttitudeManifold;
constexpr double kAttSigma_rad = 0.5e-3, kVelSigma_mps = 0.05;

// Central-difference steps: attitude 1e-6 rad, velocity 1e-3 m/s (the residual is linear
// in it), delay 1e-6 s. Truncation ~h^2 |r'''| ~ 1e-12 |r|; rounding ~eps |r| / h: with
// whitened |r| up to ~6e3 (pi / 0.5 mrad) that is ~1.3e-6, against max |J| ~ 2e3..1e5 at
// the random point. 1e-7 relative to max(1, max |J|) is above both and far below a wrong
// sign or frame (relative error 1).
constexpr double kAttStep = 1e-6, kVelStep = 1e-3, kTauStep = 1e-6;
constexpr double kJacobianTol = 1e-7;

/// A master whose body rate and NED acceleration are constant over the carry-forward
/// interval: omega_dot = 0, a_dot = 0, so R(t) = R Exp(omega dt) and v(t) = v + a dt hold
/// exactly and the second-order series is exact.
MasterKinematics UniformMaster() {
  MasterKinematics m;
  m.tag_s = 12.34;
  m.q_n_b = QuatFromEuler(0.4, -0.1, 2.1);
  m.v_n_mps = Eigen::Vector3d(150.0, -80.0, 3.0);
  m.omega_nb_b_radps = Eigen::Vector3d(1.2, -0.3, 0.25);
  m.a_n_mps2 = Eigen::Vector3d(-4.0, 9.0, 1.5);
  return m;
}

Eigen::Matrix<double, 6, 1> Eval(const ceres::CostFunction& f, const Eigen::Quaterniond& q_n_s,
                                 const Eigen::Vector3d& v_n, const Eigen::Quaterniond& q_b_s, double tau_s) {
  const std::vector<Block> blocks = {
      {Std(q_n_s), nullptr, 0.0}, {Std(v_n), nullptr, 0.0}, {Std(q_b_s), nullptr, 0.0}, {{tau_s}, nullptr, 0.0}};
  return Residual(f, blocks);
}

TEST(TransferMatch, ZeroAtTheTruthForEveryLeadAndOrder) {
  const MasterKinematics m = UniformMaster();
  const Eigen::Quaterniond M = QuatFromEuler(0.5e-2, -0.3e-2, 0.8e-2);  // R_b_s
  const Eigen::Vector3d lever_b(2.0, -0.5, 0.3);
  const double tau = 0.3;
  // lead 0: the state at the record's tag (carried 0.3 s); lead 0.29: the state 10 ms
  // after the record's data time (the batch's choice).
  for (const double lead : {0.0, 0.29, 0.31}) {
    SCOPED_TRACE(lead);
    const double dt = tau - lead;
    const Eigen::Matrix3d R_n_b = DcmFromQuat(m.q_n_b) * ExpSO3<double>(m.omega_nb_b_radps * dt);
    const Eigen::Quaterniond q_n_s(QuatFromDcm<double>(R_n_b * DcmFromQuat(M)));
    // The slave IMU at lever arm l moves with v + R (omega x l).
    const Eigen::Vector3d v_s = m.v_n_mps + m.a_n_mps2 * dt + R_n_b * m.omega_nb_b_radps.cross(lever_b);
    const std::unique_ptr<ceres::CostFunction> f(
        TransferMatch::Create(m, lead, DelayOrder::kSecond, lever_b, kAttSigma_rad, kVelSigma_mps));
    // Rounding of O(100) m/s sums / 0.05 m/s and of O(1) rotations / 0.5 mrad: ~1e-11.
    EXPECT_LT(Eval(*f, q_n_s, v_s, M, tau).norm(), 1e-9);
    // Order 1 carries the attitude only: the velocity residual is a dt / sigma.
    const std::unique_ptr<ceres::CostFunction> f1(
        TransferMatch::Create(m, lead, DelayOrder::kFirst, lever_b, kAttSigma_rad, kVelSigma_mps));
    const Eigen::Matrix<double, 6, 1> r1 = Eval(*f1, q_n_s, v_s, M, tau);
    EXPECT_LT(r1.head<3>().norm(), 1e-9);
    EXPECT_LT((r1.tail<3>() - m.a_n_mps2 * dt / kVelSigma_mps).norm(), 1e-9);
  }
}

TEST(TransferMatch, DelayAndMisalignmentDerivativesHaveTheirMeaning) {
  // At the truth with lead = tau (dt = 0): d r_att / d tau = -R_n_b omega / sigma (a later
  // data time rotates the prediction by R_n_b omega d tau, Exp on the left in NED), d r_vel
  // / d tau = -a / sigma; d r_att / d mu = -R_n_b / sigma (M_true = Exp(mu) M in master
  // body axes); d r_att / d phi = I / sigma (R_n_s = Exp(phi) R_n_s).
  MasterKinematics m = UniformMaster();
  m.omega_dot_nb_b_radps2 = Eigen::Vector3d(3.0, -1.0, 0.5);  // no first-order effect at dt = 0
  m.a_dot_n_mps3 = Eigen::Vector3d(0.5, 0.2, -0.1);
  const Eigen::Quaterniond M = QuatFromEuler(0.01, 0.02, -0.03);
  const double tau = 0.3;
  const Eigen::Matrix3d R_n_b = DcmFromQuat(m.q_n_b);
  const Eigen::Quaterniond q_n_s(QuatFromDcm<double>(R_n_b * DcmFromQuat(M)));
  const std::unique_ptr<ceres::CostFunction> f(TransferMatch::Create(m, tau, DelayOrder::kSecond,
                                                                     Eigen::Vector3d::Zero(), kAttSigma_rad,
                                                                     kVelSigma_mps));
  const std::vector<Block> blocks = {{Std(q_n_s), &kAttitudeManifold, kAttStep},
                                     {Std(m.v_n_mps), nullptr, kVelStep},
                                     {Std(M), &kAttitudeManifold, kAttStep},
                                     {{tau}, nullptr, kTauStep}};
  const Linearization lin = LinearizeAt(*f, blocks);
  EXPECT_LT(lin.residual.norm(), 1e-9);
  // AutoDiff: exact to rounding of O(1e4) entries.
  const double tol = 1e-8;
  EXPECT_LT((lin.jacobians[0].topRows<3>() - Eigen::Matrix3d::Identity() / kAttSigma_rad).norm(), tol);
  EXPECT_LT((lin.jacobians[1].bottomRows<3>() - Eigen::Matrix3d::Identity() / kVelSigma_mps).norm(), tol);
  EXPECT_LT((lin.jacobians[2].topRows<3>() + R_n_b / kAttSigma_rad).norm(), tol);
  EXPECT_LT((lin.jacobians[3].topRows<3>() + R_n_b * m.omega_nb_b_radps / kAttSigma_rad).norm(), tol);
  EXPECT_LT((lin.jacobians[3].bottomRows<3>() + m.a_n_mps2 / kVelSigma_mps).norm(), tol);
}

TEST(TransferMatch, TangentJacobiansMatchCentralDifferences) {
  std::mt19937 rng(6002);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random3 = [&]() { return Eigen::Vector3d(u(rng), u(rng), u(rng)); };
  for (const State& s : States()) {
    SCOPED_TRACE(s.name);
    const bool random = s.name == "random";
    MasterKinematics m;
    Eigen::Quaterniond M = Eigen::Quaterniond::Identity();
    double tau = 0.0, lead = 0.0;
    Eigen::Vector3d lever = Eigen::Vector3d::Zero();
    if (s.name == "tiny") {
      m.q_n_b = QuatFromRotVec<double>(Eigen::Vector3d(-2e-9, 1e-9, 1e-9));
      m.omega_nb_b_radps = Eigen::Vector3d(1e-9, 0.0, -1e-9);
      M = QuatFromRotVec<double>(Eigen::Vector3d(1e-9, 1e-9, -2e-9));
      tau = 1e-9;
    } else if (random) {
      m.q_n_b = QuatFromRotVec<double>(2.0 * random3());
      m.v_n_mps = 100.0 * random3();
      m.omega_nb_b_radps = 2.0 * random3();
      m.omega_dot_nb_b_radps2 = 5.0 * random3();
      m.a_n_mps2 = 10.0 * random3();
      m.a_dot_n_mps3 = 3.0 * random3();
      M = QuatFromRotVec<double>(0.05 * random3());
      tau = 0.3 + 0.05 * u(rng);
      lead = 0.28;
      lever = random3();
    }
    for (const DelayOrder order : {DelayOrder::kFirst, DelayOrder::kSecond}) {
      SCOPED_TRACE(static_cast<int>(order));
      const std::unique_ptr<ceres::CostFunction> f(
          TransferMatch::Create(m, lead, order, lever, kAttSigma_rad, kVelSigma_mps));
      const std::vector<Block> blocks = {{Std(s.q_n_b), &kAttitudeManifold, kAttStep},
                                         {Std(s.v_n_mps), nullptr, kVelStep},
                                         {Std(M), &kAttitudeManifold, kAttStep},
                                         {{tau}, nullptr, kTauStep}};
      // Away from |r_att| = pi, where Log jumps and no derivative exists.
      ASSERT_LT(Residual(*f, blocks).head<3>().norm() * kAttSigma_rad, 3.0);
      ExpectTangentJacobiansMatch(*f, blocks, kJacobianTol);
    }
  }
}

TEST(TransferMatch, RejectsBadArguments) {
  const MasterKinematics m = UniformMaster();
  const Eigen::Vector3d z = Eigen::Vector3d::Zero();
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (const double bad : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_THROW(TransferMatch(m, 0.0, DelayOrder::kSecond, z, bad, 0.05), std::invalid_argument) << bad;
    EXPECT_THROW(TransferMatch(m, 0.0, DelayOrder::kSecond, z, 1e-3, bad), std::invalid_argument) << bad;
  }
  EXPECT_THROW(TransferMatch(m, kNaN, DelayOrder::kSecond, z, 1e-3, 0.05), std::invalid_argument);
  EXPECT_THROW(TransferMatch(m, 0.0, DelayOrder::kSecond, Eigen::Vector3d(0, kInf, 0), 1e-3, 0.05),
               std::invalid_argument);
  MasterKinematics bad = m;
  bad.a_dot_n_mps3.x() = kNaN;
  EXPECT_THROW(TransferMatch(bad, 0.0, DelayOrder::kSecond, z, 1e-3, 0.05), std::invalid_argument);
}

}  // namespace transfer_alignment_transfer_match_test
}  // namespace navtwin::transfer
