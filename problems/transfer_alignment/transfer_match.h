// The transfer-alignment matching residual of one master record (seed 002, issue 6), for
// the batch (problems/transfer_alignment/batch.cc): the slave's attitude and velocity
// against the master's, carried forward over the delay by the model shared with the
// filter, problems/transfer_alignment/delay_model.h (AttitudeMatchResidual,
// VelocityMatchResidual; no maths of its own here).
//
// Frames: n = NED, b = master body FRD, s = slave IMU axes; misalignment M = R_b_s.
// Parameter blocks (ambient sizes):
//   q_n_s [4]  slave attitude, x y z w (AttitudeManifold: R_true = Exp(phi_n) R_est)
//   v_n   [3]  slave velocity, m/s
//   q_b_s [4]  misalignment, x y z w (AttitudeManifold: M_true = Exp(mu_b) M_est, mu in
//              master body axes, as the filter's misalignment state)
//   tau   [1]  transfer delay, s
// The record's data time is tag - tau. The slave state sits at t_state = tag - lead_s
// (lead_s = tag - t_state >= 0 is a constant of the factor), so the master's state at
// t_state is the record's carried forward over
//   dt(tau) = t_state - (tag - tau) = tau - lead_s,
// continuous and differentiable in tau. lead_s = 0 is the seed's form (the state at the
// record's tag, the master carried over the whole delay, as the filter does). The batch
// uses the record whose data time is nearest the state (lead_s ~ tau), so that |dt| is at
// most half a record interval and the truncation of the delay series (the third-order
// term omega''' dt^3 / 6) stays negligible; docs/transfer-alignment-batch.md.
//
// Residuals (6), true slave minus prediction, whitened by the master noise:
//   r[0..3) = AttitudeMatchResidual(R_n_s, R_b_s, m, dt, order) / sigma_att_rad   (NED axes)
//   r[3..6) = VelocityMatchResidual(v_n, m, dt, order, lever_arm_b_m) / sigma_vel_mps
#pragma once

#include <cmath>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"
#include "problems/transfer_alignment/delay_model.h"

namespace navtwin::transfer {

class TransferMatch {
 public:
  static constexpr int kResiduals = 6;
  static constexpr int kSlaveAttitudeSize = 4;  ///< block 0: q_n_s (x, y, z, w)
  static constexpr int kVelocitySize = 3;       ///< block 1: v_n_mps
  static constexpr int kMisalignmentSize = 4;   ///< block 2: q_b_s (x, y, z, w)
  static constexpr int kDelaySize = 1;          ///< block 3: tau_s

  /// master: the record's kinematics (held by value); lead_s = tag - t_state (finite);
  /// sigmas: 1-sigma master attitude error per axis (rad) and velocity noise per axis
  /// (m/s), positive and finite. Throws std::invalid_argument otherwise.
  TransferMatch(const transfer::MasterKinematics& master, double lead_s, transfer::DelayOrder order,
                const Eigen::Vector3d& lever_arm_b_m, double attitude_sigma_rad, double velocity_sigma_mps)
      : master_(master), lead_s_(lead_s), order_(order), lever_arm_b_m_(lever_arm_b_m) {
    if (!(attitude_sigma_rad > 0.0) || !std::isfinite(attitude_sigma_rad) || !(velocity_sigma_mps > 0.0) ||
        !std::isfinite(velocity_sigma_mps)) {
      throw std::invalid_argument("TransferMatch: the master sigmas must be positive and finite");
    }
    if (!std::isfinite(lead_s) || !lever_arm_b_m.allFinite() || !master.v_n_mps.allFinite() ||
        !master.q_n_b.coeffs().allFinite() || !master.omega_nb_b_radps.allFinite() ||
        !master.omega_dot_nb_b_radps2.allFinite() || !master.a_n_mps2.allFinite() ||
        !master.a_dot_n_mps3.allFinite()) {
      throw std::invalid_argument("TransferMatch: non-finite master kinematics, lead or lever arm");
    }
    inv_sigma_att_ = 1.0 / attitude_sigma_rad;
    inv_sigma_vel_ = 1.0 / velocity_sigma_mps;
  }

  template <typename T>
  bool operator()(const T* q_n_s_ptr, const T* v_n_ptr, const T* q_b_s_ptr, const T* tau_ptr, T* residual_ptr) const {
    const Eigen::Map<const Quaternion<T>> q_n_s(q_n_s_ptr);
    const Eigen::Map<const Quaternion<T>> q_b_s(q_b_s_ptr);
    const Eigen::Map<const Vector3<T>> v_n(v_n_ptr);
    const T dt_s = tau_ptr[0] - T(lead_s_);
    const Matrix3<T> R_n_s = DcmFromQuat<T>(q_n_s);
    const Matrix3<T> R_b_s = DcmFromQuat<T>(q_b_s);
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residual_ptr);
    r.template head<3>() = transfer::AttitudeMatchResidual<T>(R_n_s, R_b_s, master_, dt_s, order_) * T(inv_sigma_att_);
    r.template tail<3>() =
        transfer::VelocityMatchResidual<T>(Vector3<T>(v_n), master_, dt_s, order_, lever_arm_b_m_) * T(inv_sigma_vel_);
    return true;
  }

  /// 6 residuals; blocks q_n_s (4), v_n (3), q_b_s (4), tau (1). The caller owns it.
  static ceres::CostFunction* Create(const transfer::MasterKinematics& master, double lead_s,
                                     transfer::DelayOrder order, const Eigen::Vector3d& lever_arm_b_m,
                                     double attitude_sigma_rad, double velocity_sigma_mps) {
    return new ceres::AutoDiffCostFunction<TransferMatch, kResiduals, kSlaveAttitudeSize, kVelocitySize,
                                           kMisalignmentSize, kDelaySize>(
        new TransferMatch(master, lead_s, order, lever_arm_b_m, attitude_sigma_rad, velocity_sigma_mps));
  }

 private:
  transfer::MasterKinematics master_;
  double lead_s_;
  transfer::DelayOrder order_;
  Eigen::Vector3d lever_arm_b_m_;
  double inv_sigma_att_ = 0.0;
  double inv_sigma_vel_ = 0.0;
};

}  // namespace navtwin::transfer
