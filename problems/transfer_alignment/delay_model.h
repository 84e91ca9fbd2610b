// The one model of transfer alignment with a transfer delay (seed 002, patent KR 10-1741076),
// shared by the filter and the batch: the master's attitude and velocity carried forward
// over the delay, and the attitude and velocity matching residuals. Templated so that the
// Ceres residuals (the delay and the misalignment as parameters) use the same code.
//
// Frames: n = local NED; b = the master's (vehicle) body FRD; s = the slave IMU's axes.
// Misalignment M = R_b_s (slave axes to master body axes), so R_n_s = R_n_b M.
// Delay: the master record received (tagged) at t carries the master's state at t - tau.
//
// Compensation over tau (the seed's Taylor series), with omega = omega_nb^b (master body
// rate relative to NED), omega_dot its rate, a = dv_n/dt, a_dot its rate, all at t - tau:
//   attitude  R_n_b(t) = R_n_b(t - tau) Exp(theta),
//             order 1: theta = omega tau;  order 2: theta = omega tau + omega_dot tau^2 / 2.
//             Exp(theta) = I + [omega x] tau + ([omega_dot x] + [omega x]^2) tau^2 / 2 + O(tau^3),
//             the seed's C (I + [w x] tau + ([w_dot x] + [w x]^2) tau^2 / 2) to second order; for
//             order 1 Exp(omega tau) is the seed's (I + [w x] tau) made orthonormal.
//   velocity  order 1: v(t) = v(t - tau) (the seed's case 1 compensates the attitude only);
//             order 2: v(t) = v(t - tau) + a tau + a_dot tau^2 / 2.
// Residuals (true slave minus predicted, zero at the truth):
//   attitude  r_att = Log( R_n_s_slave (R_n_b_pred M)^T )        (3, rad, NED axes)
//   velocity  r_vel = v_slave - v_pred - R_n_b_pred (omega_ib x l)  (3, m/s; l = lever arm
//             from the master's reference point to the slave IMU, body axes; optional, 0 by
//             default; omega_ib ~ omega_nb + the Earth and transport rates, which at a lever
//             arm of metres are below 1e-4 m/s and are left out).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"

namespace navtwin::transfer {

enum class DelayOrder { kFirst = 1, kSecond = 2 };

/// The master's state and its derivatives at one record's data time (record tag - delay).
struct MasterKinematics {
  double tag_s = 0.0;                 ///< time the record was received (its time tag)
  Eigen::Quaterniond q_n_b = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_n_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega_nb_b_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega_dot_nb_b_radps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_n_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_dot_n_mps3 = Eigen::Vector3d::Zero();
};

/// theta of the header comment (master body axes).
template <typename T>
Eigen::Matrix<T, 3, 1> DelayRotationVector(const MasterKinematics& m, const T& tau_s, DelayOrder order) {
  Eigen::Matrix<T, 3, 1> theta = m.omega_nb_b_radps.cast<T>() * tau_s;
  if (order == DelayOrder::kSecond) theta += m.omega_dot_nb_b_radps2.cast<T>() * (T(0.5) * tau_s * tau_s);
  return theta;
}

/// R_n_b carried forward over tau.
template <typename T>
Eigen::Matrix<T, 3, 3> CompensatedMasterDcm(const MasterKinematics& m, const T& tau_s, DelayOrder order) {
  const Eigen::Matrix<T, 3, 3> R_n_b = m.q_n_b.toRotationMatrix().cast<T>();
  return R_n_b * ExpSO3<T>(DelayRotationVector<T>(m, tau_s, order));
}

/// v_n carried forward over tau.
template <typename T>
Eigen::Matrix<T, 3, 1> CompensatedMasterVelocity(const MasterKinematics& m, const T& tau_s, DelayOrder order) {
  Eigen::Matrix<T, 3, 1> v = m.v_n_mps.cast<T>();
  if (order == DelayOrder::kSecond) {
    v += m.a_n_mps2.cast<T>() * tau_s + m.a_dot_n_mps3.cast<T>() * (T(0.5) * tau_s * tau_s);
  }
  return v;
}

/// r_att of the header comment. R_n_s: the slave's attitude (slave axes to NED);
/// R_b_s: the misalignment.
template <typename T>
Eigen::Matrix<T, 3, 1> AttitudeMatchResidual(const Eigen::Matrix<T, 3, 3>& R_n_s, const Eigen::Matrix<T, 3, 3>& R_b_s,
                                             const MasterKinematics& m, const T& tau_s, DelayOrder order) {
  const Eigen::Matrix<T, 3, 3> R_n_s_pred = CompensatedMasterDcm<T>(m, tau_s, order) * R_b_s;
  return LogSO3<T>(Eigen::Matrix<T, 3, 3>(R_n_s * R_n_s_pred.transpose()));
}

/// r_vel of the header comment (lever arm l in master body axes, m).
template <typename T>
Eigen::Matrix<T, 3, 1> VelocityMatchResidual(const Eigen::Matrix<T, 3, 1>& v_n_slave_mps, const MasterKinematics& m,
                                             const T& tau_s, DelayOrder order,
                                             const Eigen::Vector3d& lever_arm_b_m = Eigen::Vector3d::Zero()) {
  Eigen::Matrix<T, 3, 1> r = v_n_slave_mps - CompensatedMasterVelocity<T>(m, tau_s, order);
  if (!lever_arm_b_m.isZero()) {
    const Eigen::Matrix<T, 3, 3> R_n_b = CompensatedMasterDcm<T>(m, tau_s, order);
    const Eigen::Matrix<T, 3, 1> w = m.omega_nb_b_radps.cast<T>();
    r -= R_n_b * w.cross(lever_arm_b_m.cast<T>());
  }
  return r;
}

}  // namespace navtwin::transfer
