// GNSS antenna position measurement p_meas = {lat_rad, lon_rad, h_m} of an antenna at lever
// arm l_b (body FRD, m) from the IMU reference point:
//
//   r = (PositionMinus(pos, p_meas) + R_n_b(q) l_b) / sigma_ned     (3 residuals, NED)
//
// i.e. (predicted antenna position - measured antenna position) in metres NED, the NED
// offset of the IMU from p_meas plus the lever arm rotated into NED, divided per axis by
// std_ned_m. PositionMinus (factors/position_manifold.h) evaluates the radii at p_meas.
// Parameter blocks: pos {lat_rad, lon_rad, h_m} (3, PositionManifold), q_n_b (4, x y z w,
// AttitudeManifold). R_n_b is taken from the normalised q_n_b.
#pragma once

#include <cmath>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"
#include "factors/position_manifold.h"

namespace navtwin {

class GnssPosition {
 public:
  static constexpr int kResiduals = 3;
  static constexpr int kPositionSize = 3;  ///< block 0: {lat_rad, lon_rad, h_m}
  static constexpr int kAttitudeSize = 4;  ///< block 1: q_n_b (x, y, z, w)

  /// p_meas: {lat_rad, lon_rad, h_m} of the antenna; lever_arm_b_m: antenna in body FRD;
  /// std_ned_m: 1-sigma per NED axis, each > 0 and finite (else std::invalid_argument).
  GnssPosition(const Eigen::Vector3d& p_meas, const Eigen::Vector3d& lever_arm_b_m,
               const Eigen::Vector3d& std_ned_m)
      : p_meas_(p_meas), lever_arm_b_m_(lever_arm_b_m) {
    for (int i = 0; i < 3; ++i) {
      if (!(std_ned_m[i] > 0.0) || !std::isfinite(std_ned_m[i])) {
        throw std::invalid_argument("GnssPosition: std_ned_m must be positive and finite");
      }
    }
    if (!p_meas.allFinite() || !lever_arm_b_m.allFinite()) {
      throw std::invalid_argument("GnssPosition: p_meas and lever_arm_b_m must be finite");
    }
    inv_sigma_ = std_ned_m.cwiseInverse();
  }
  /// The same sigma on the three NED axes.
  GnssPosition(const Eigen::Vector3d& p_meas, const Eigen::Vector3d& lever_arm_b_m, double std_m)
      : GnssPosition(p_meas, lever_arm_b_m, Eigen::Vector3d::Constant(std_m)) {}

  template <typename T>
  bool operator()(const T* pos, const T* q_n_b_ptr, T* residual_ptr) const {
    const Eigen::Map<const Quaternion<T>> q_n_b(q_n_b_ptr);
    const T p_meas[3] = {T(p_meas_[0]), T(p_meas_[1]), T(p_meas_[2])};
    Vector3<T> dp_ned;
    PositionMinus(pos, p_meas, dp_ned.data());
    const Vector3<T> antenna_offset_n = DcmFromQuat<T>(q_n_b) * lever_arm_b_m_.cast<T>();
    Eigen::Map<Vector3<T>> residual(residual_ptr);
    residual = (dp_ned + antenna_offset_n).cwiseProduct(inv_sigma_.cast<T>());
    return true;
  }

  /// 3 residuals; blocks pos (3), q_n_b (4).
  static ceres::CostFunction* Create(const Eigen::Vector3d& p_meas, const Eigen::Vector3d& lever_arm_b_m,
                                     const Eigen::Vector3d& std_ned_m) {
    return new ceres::AutoDiffCostFunction<GnssPosition, kResiduals, kPositionSize, kAttitudeSize>(
        new GnssPosition(p_meas, lever_arm_b_m, std_ned_m));
  }
  static ceres::CostFunction* Create(const Eigen::Vector3d& p_meas, const Eigen::Vector3d& lever_arm_b_m,
                                     double std_m) {
    return Create(p_meas, lever_arm_b_m, Eigen::Vector3d::Constant(std_m));
  }

 private:
  Eigen::Vector3d p_meas_;
  Eigen::Vector3d lever_arm_b_m_;
  Eigen::Vector3d inv_sigma_;
};

}  // namespace navtwin
