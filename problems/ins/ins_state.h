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
// core/imu_errors.h.
#pragma once

#include <Eigen/Core>

#include "core/imu_errors.h"
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

using ::navtwin::CorrectImu;
using ::navtwin::ImuErrors;

/// Navigation state (at the IMU) plus the IMU errors.
struct InsState {
  NavState nav;
  ImuErrors imu;
};

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
