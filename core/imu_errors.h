// The IMU errors the aided-INS estimators carry (biases and scale factors per axis) and the
// correction of a sample for them, shared by the filter's mechanization and the batch's
// preintegration (docs/ins-error-model.md):
//   omega_meas = (1 + sg) omega_true + bg + noise,   f_meas = (1 + sa) f_true + ba + noise
// so a sample is corrected as  dtheta_c = (dtheta - bg dt) / (1 + sg),
//                              dv_c     = (dv - ba dt) / (1 + sa).
#pragma once

#include <Eigen/Core>

#include "core/types.h"

namespace navtwin {

/// Estimated IMU errors (body FRD axes, after the mounting rotation).
struct ImuErrors {
  Eigen::Vector3d bg_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d sg = Eigen::Vector3d::Zero();  ///< gyro scale-factor errors (dimensionless)
  Eigen::Vector3d sa = Eigen::Vector3d::Zero();  ///< accelerometer scale-factor errors
};

/// A triad's axis misalignments (non-orthogonality and small rotation of its axes): the six
/// off-diagonal entries of its error matrix, omega_meas = (I + S + M) omega_true + b, in the
/// order (M01, M02, M10, M12, M20, M21), M_ij = axis i's sensitivity to axis j
/// (docs/imu-error-model.md). The estimators linearise them at zero.
using AxisMisalignment = Eigen::Matrix<double, 6, 1>;

/// d(M x)/d(m) for the six entries above: column (i, j) is x_j e_i.
inline Eigen::Matrix<double, 3, 6> AxisMisalignmentColumns(const Eigen::Vector3d& x) {
  Eigen::Matrix<double, 3, 6> K = Eigen::Matrix<double, 3, 6>::Zero();
  K(0, 0) = x(1);
  K(0, 1) = x(2);
  K(1, 2) = x(0);
  K(1, 3) = x(2);
  K(2, 4) = x(0);
  K(2, 5) = x(1);
  return K;
}

/// I + diag(s) + M of a triad with scale-factor errors s and axis misalignments m.
inline Eigen::Matrix3d TriadErrorMatrix(const Eigen::Vector3d& s, const AxisMisalignment& m) {
  Eigen::Matrix3d E = Eigen::Matrix3d::Identity();
  E.diagonal() += s;
  E(0, 1) = m(0);
  E(0, 2) = m(1);
  E(1, 0) = m(2);
  E(1, 2) = m(3);
  E(2, 0) = m(4);
  E(2, 1) = m(5);
  return E;
}

/// An IMU sample corrected for the estimated errors: (dtheta - bg dt) / (1 + sg), etc.
inline ImuSample CorrectImu(const ImuSample& raw, const ImuErrors& e) {
  ImuSample c = raw;
  c.dtheta_b_rad = (raw.dtheta_b_rad - e.bg_radps * raw.dt_s).cwiseQuotient(Eigen::Vector3d::Ones() + e.sg);
  c.dv_b_mps = (raw.dv_b_mps - e.ba_mps2 * raw.dt_s).cwiseQuotient(Eigen::Vector3d::Ones() + e.sa);
  return c;
}

}  // namespace navtwin
