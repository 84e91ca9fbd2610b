// The analytic Jacobian of the transfer-alignment matching residuals (filter.h,
// MatchResidualAndJacobian) against ceres::Jet autodiff of the problems/transfer_alignment/delay_model.h residuals.
#include <random>

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include "core/rotation.h"
#include "problems/transfer_alignment/delay_model.h"
#include "problems/transfer_alignment/filter.h"

namespace navtwin::transfer {
namespace transfer_alignment_delay_model_test {

using Jet = ceres::Jet<double, kTransferStates>;
using Matrix6x10 = Eigen::Matrix<double, 6, kTransferStates>;

struct Point {
  Eigen::Matrix3d R_n_s;
  Eigen::Vector3d v_n_s_mps;
  Eigen::Matrix3d R_b_s;
  MasterKinematics m;
  double tau_s;
  Eigen::Vector3d lever_arm_b_m;
};

// dr/d(dx) at dx = 0 by autodiff, with the error-state definitions of filter.h (true =
// estimate (+) dx): v + dv, Exp(phi) R_n_s, Exp(mu) R_b_s, tau + dtau.
Matrix6x10 AutodiffJacobian(const Point& p, DelayOrder order) {
  Eigen::Matrix<Jet, kTransferStates, 1> dx;
  for (int i = 0; i < kTransferStates; ++i) dx(i) = Jet(0.0, i);
  const Eigen::Matrix<Jet, 3, 1> v = p.v_n_s_mps.cast<Jet>() + dx.segment<3>(0);
  const Eigen::Matrix<Jet, 3, 3> R_n_s = ExpSO3<Jet>(dx.segment<3>(3)) * p.R_n_s.cast<Jet>();
  const Eigen::Matrix<Jet, 3, 3> R_b_s = ExpSO3<Jet>(dx.segment<3>(6)) * p.R_b_s.cast<Jet>();
  const Jet tau = Jet(p.tau_s) + dx(9);
  Eigen::Matrix<Jet, 6, 1> r;
  r.head<3>() = VelocityMatchResidual<Jet>(v, p.m, tau, order, p.lever_arm_b_m);
  r.tail<3>() = AttitudeMatchResidual<Jet>(R_n_s, R_b_s, p.m, tau, order);
  Matrix6x10 J;
  for (int i = 0; i < 6; ++i) J.row(i) = r(i).v.transpose();
  return J;
}

// A master record with wing-rock-sized rates: |omega| ~ 1.6 rad/s (94 deg/s),
// |omega_dot| ~ 5 rad/s^2, a ~ 30 m/s^2.
MasterKinematics Kinematics(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  auto vec = [&](double s) -> Eigen::Vector3d { return Eigen::Vector3d(n(rng), n(rng), n(rng)) * s; };
  MasterKinematics m;
  m.tag_s = 12.3;
  m.q_n_b = QuatFromRotVec<double>(vec(1.0));
  m.v_n_mps = vec(100.0);
  m.omega_nb_b_radps = vec(0.9);
  m.omega_dot_nb_b_radps2 = vec(3.0);
  m.a_n_mps2 = vec(15.0);
  m.a_dot_n_mps3 = vec(20.0);
  return m;
}

// At the truth (zero residual), near it (tiny perturbation) and at a random point with
// residuals of ~0.3 rad, where the SO(3) Jacobians of Log and Exp differ from I by ~5 %.
// Both are exact derivatives of the same functions, so they agree to rounding: 1e-9
// relative to the largest entry (entries up to ~1e2 for dtau).
TEST(TransferDelayModel, AnalyticJacobianMatchesAutodiff) {
  std::mt19937 rng(42);
  std::normal_distribution<double> n(0.0, 1.0);
  for (DelayOrder order : {DelayOrder::kFirst, DelayOrder::kSecond}) {
    for (int lever = 0; lever < 2; ++lever) {
      for (double spread : {0.0, 1e-6, 0.3}) {
        Point p;
        p.m = Kinematics(rng);
        p.tau_s = 0.3;
        p.R_b_s = ExpSO3<double>(Eigen::Vector3d(0.01, -0.005, 0.014));
        p.lever_arm_b_m = lever ? Eigen::Vector3d(1.5, -0.4, 0.7) : Eigen::Vector3d::Zero();
        // Estimate = truth (+) a perturbation of size `spread` rad (velocity 10x in m/s).
        const Eigen::Matrix3d R_pred = CompensatedMasterDcm<double>(p.m, p.tau_s, order) * p.R_b_s;
        const Eigen::Vector3d e(n(rng), n(rng), n(rng));
        p.R_n_s = ExpSO3<double>(Eigen::Vector3d(spread * e)) * R_pred;
        p.v_n_s_mps = CompensatedMasterVelocity<double>(p.m, p.tau_s, order) + 10.0 * spread * e;
        Eigen::Matrix<double, 6, 1> r;
        Matrix6x10 H;
        MatchResidualAndJacobian(p.R_n_s, p.v_n_s_mps, p.R_b_s, p.m, p.tau_s, order, p.lever_arm_b_m, &r, &H);
        const Matrix6x10 J = AutodiffJacobian(p, order);
        const double scale = J.cwiseAbs().maxCoeff();
        EXPECT_LT((H - J).cwiseAbs().maxCoeff(), 1e-9 * scale)
            << "order " << static_cast<int>(order) << " lever " << lever << " spread " << spread << "\nH\n"
            << H << "\nautodiff\n" << J;
        if (spread == 0.0 && lever == 0) {
          EXPECT_LT(r.norm(), 1e-12);
        }
      }
    }
  }
}

// The brief's first-order forms hold at the truth: attitude rows d/dphi = I, d/dmu =
// -R_n_b_pred, d/dtau = -R_n_b_pred Jr(theta) (omega + omega_dot tau) (Jr -> I as theta -> 0);
// velocity rows d/ddv = I, d/dtau = -(a + a_dot tau) for order 2 and 0 for order 1.
TEST(TransferDelayModel, JacobianAtTruthHasTheFirstOrderForm) {
  std::mt19937 rng(7);
  MasterKinematics m = Kinematics(rng);
  const double tau = 1e-4;  // theta ~ 1e-4 rad: Jr(theta) = I to 1e-4
  const Eigen::Matrix3d M = Eigen::Matrix3d::Identity();
  for (DelayOrder order : {DelayOrder::kFirst, DelayOrder::kSecond}) {
    const Eigen::Matrix3d C = CompensatedMasterDcm<double>(m, tau, order);
    Eigen::Matrix<double, 6, 1> r;
    Matrix6x10 H;
    MatchResidualAndJacobian(C * M, CompensatedMasterVelocity<double>(m, tau, order), M, m, tau, order,
                             Eigen::Vector3d::Zero(), &r, &H);
    EXPECT_LT((H.block<3, 3>(3, 3) - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_LT((H.block<3, 3>(3, 6) + C).norm(), 1e-12);
    Eigen::Vector3d w = m.omega_nb_b_radps;
    if (order == DelayOrder::kSecond) w += m.omega_dot_nb_b_radps2 * tau;
    EXPECT_LT((H.block<3, 1>(3, 9) + C * w).norm(), 1e-3 * w.norm());  // Jr(theta) - I ~ |theta| / 2
    EXPECT_LT((H.block<3, 3>(0, 0) - Eigen::Matrix3d::Identity()).norm(), 1e-15);
    Eigen::Vector3d h_tau_v = Eigen::Vector3d::Zero();
    if (order == DelayOrder::kSecond) h_tau_v = -(m.a_n_mps2 + m.a_dot_n_mps3 * tau);
    EXPECT_LT((H.block<3, 1>(0, 9) - h_tau_v).norm(), 1e-12);
  }
}

}  // namespace transfer_alignment_delay_model_test
}  // namespace navtwin::transfer
