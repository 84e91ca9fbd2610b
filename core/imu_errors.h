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

/// An IMU sample corrected for the estimated errors: (dtheta - bg dt) / (1 + sg), etc.
inline ImuSample CorrectImu(const ImuSample& raw, const ImuErrors& e) {
  ImuSample c = raw;
  c.dtheta_b_rad = (raw.dtheta_b_rad - e.bg_radps * raw.dt_s).cwiseQuotient(Eigen::Vector3d::Ones() + e.sg);
  c.dv_b_mps = (raw.dv_b_mps - e.ba_mps2 * raw.dt_s).cwiseQuotient(Eigen::Vector3d::Ones() + e.sa);
  return c;
}

}  // namespace navtwin
