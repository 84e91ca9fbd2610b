// The aided-INS state shared by every filter, RTS smoother and batch smoother built on
// the strapdown mechanization, and the layout of the error state they use
// (docs/ins-error-model.md, docs/architecture.md).
//
// Error state (true minus estimate), 15 or 21 components:
//   [ 0, 3)  dp_ned_m     position error in local NED metres:
//                         [(lat_t - lat_e)(M + h), (lon_t - lon_e)(N + h) cos lat, -(h_t - h_e)]
//   [ 3, 6)  dv_ned_mps   velocity error, v_t - v_e
//   [ 6, 9)  phi_n_rad    attitude error, R_n_b_true = Exp(phi_n) R_n_b_est (core/rotation.h)
//   [ 9,12)  dbg_radps    gyro bias error
//   [12,15)  dba_mps2     accelerometer bias error
//   [15,18)  dsg          gyro scale-factor error (dimensionless)      21-state filter only
//   [18,21)  dsa          accelerometer scale-factor error             21-state filter only
//
// IMU error model (per axis, in the IMU axes after the mounting rotation into body FRD):
//   omega_meas = (1 + sg) omega_true + bg + noise,   f_meas = (1 + sa) f_true + ba + noise
// so a sample is corrected as  dtheta_c = (dtheta - bg dt) / (1 + sg),
//                              dv_c     = (dv - ba dt) / (1 + sa).
#pragma once

#include <Eigen/Core>

#include "core/types.h"

namespace navtwin::ins {

/// Time tags within this are the same epoch (IMU rates stay far below 1 MHz; files written
/// at the same epochs agree to the microsecond).
constexpr double kSameEpoch_s = 1e-6;

/// Indices of the error-state blocks.
namespace err {
constexpr int kPos = 0;
constexpr int kVel = 3;
constexpr int kAtt = 6;
constexpr int kBg = 9;
constexpr int kBa = 12;
constexpr int kSg = 15;
constexpr int kSa = 18;
constexpr int kSize15 = 15;
constexpr int kSize21 = 21;
}  // namespace err

/// Estimated IMU errors (body FRD axes, after the mounting rotation).
struct ImuErrors {
  Eigen::Vector3d bg_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d sg = Eigen::Vector3d::Zero();  ///< gyro scale-factor errors (dimensionless)
  Eigen::Vector3d sa = Eigen::Vector3d::Zero();  ///< accelerometer scale-factor errors
};

/// Navigation state (at the IMU) plus the IMU errors.
struct InsState {
  NavState nav;
  ImuErrors imu;
};

/// An IMU sample corrected for the estimated errors: (dtheta - bg dt) / (1 + sg), etc.
inline ImuSample CorrectImu(const ImuSample& raw, const ImuErrors& e) {
  ImuSample c = raw;
  c.dtheta_b_rad = (raw.dtheta_b_rad - e.bg_radps * raw.dt_s).cwiseQuotient(Eigen::Vector3d::Ones() + e.sg);
  c.dv_b_mps = (raw.dv_b_mps - e.ba_mps2 * raw.dt_s).cwiseQuotient(Eigen::Vector3d::Ones() + e.sa);
  return c;
}

/// A state of a solution with the standard deviations of its error state (15 or 21
/// entries, the layout above; empty when not computed). Units: m, m/s, rad, rad/s, m/s^2, -.
/// aux: the auxiliary states that aiding sources add (e.g. an odometer scale factor;
/// problems/ins/aiding.h) in the order of the sources' registration, their errors
/// (true minus estimate) appended after the INS error states; aux_std their standard
/// deviations (empty when not computed).
struct NavEpoch {
  InsState state;
  Eigen::VectorXd std;
  Eigen::VectorXd aux;
  Eigen::VectorXd aux_std;
};

}  // namespace navtwin::ins
