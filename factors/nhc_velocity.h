// Non-holonomic constraint (NHC) of a ground vehicle that neither slides sideways nor
// leaves the road: the velocity of the vehicle reference point (e.g. the middle of the
// rear axle) has no lateral and no vertical component in the vehicle frame v (FRD, fixed
// to the chassis). With the IMU-to-vehicle mounting R_v_b, the reference point at lever
// arm l_b (body FRD, m) from the IMU and the body angular rate omega_ib_b (rad/s,
// bias-corrected gyro output, a known input):
//
//   v_v = R_v_b (R_n_b^T v_n + omega_ib_b x l_b)
//   r   = [v_v,y / sigma_lateral, v_v,z / sigma_vertical]          (2 residuals)
//
// The Earth-rate term of the lever-arm velocity is neglected as in GnssVelocity (below
// 1.5e-4 m/s for |l_b| < 2 m). Parameter blocks: v_n (3), q_n_b (4, x y z w,
// AttitudeManifold).
#pragma once

#include <cmath>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"

namespace navtwin {

/// v_v = R_v_b (R_n_b^T v_n + lever_velocity_b), the velocity of the vehicle reference
/// point in the vehicle frame; lever_velocity_b = omega_ib_b x l_b.
template <typename T>
Vector3<T> VehicleFrameVelocity(const T* v_n_ptr, const T* q_n_b_ptr, const Eigen::Matrix3d& R_v_b,
                                const Eigen::Vector3d& lever_velocity_b_mps) {
  const Eigen::Map<const Vector3<T>> v_n(v_n_ptr);
  const Eigen::Map<const Quaternion<T>> q_n_b(q_n_b_ptr);
  const Vector3<T> v_b = DcmFromQuat<T>(q_n_b).transpose() * v_n + lever_velocity_b_mps.cast<T>();
  return R_v_b.cast<T>() * v_b;
}

class NhcVelocity {
 public:
  static constexpr int kResiduals = 2;
  static constexpr int kVelocitySize = 3;  ///< block 0: v_n_mps
  static constexpr int kAttitudeSize = 4;  ///< block 1: q_n_b (x, y, z, w)

  /// sigmas > 0 and finite, inputs finite (else std::invalid_argument).
  NhcVelocity(const Eigen::Matrix3d& R_v_b, const Eigen::Vector3d& lever_arm_b_m,
              const Eigen::Vector3d& omega_ib_b_radps, double sigma_lateral_mps, double sigma_vertical_mps)
      : R_v_b_(R_v_b), lever_velocity_b_mps_(omega_ib_b_radps.cross(lever_arm_b_m)) {
    if (!(sigma_lateral_mps > 0.0) || !std::isfinite(sigma_lateral_mps) || !(sigma_vertical_mps > 0.0) ||
        !std::isfinite(sigma_vertical_mps)) {
      throw std::invalid_argument("NhcVelocity: the sigmas must be positive and finite");
    }
    if (!R_v_b.allFinite() || !lever_velocity_b_mps_.allFinite()) {
      throw std::invalid_argument("NhcVelocity: mounting, lever arm and omega must be finite");
    }
    inv_sigma_lateral_ = 1.0 / sigma_lateral_mps;
    inv_sigma_vertical_ = 1.0 / sigma_vertical_mps;
  }

  template <typename T>
  bool operator()(const T* v_n, const T* q_n_b, T* residual) const {
    const Vector3<T> v_v = VehicleFrameVelocity<T>(v_n, q_n_b, R_v_b_, lever_velocity_b_mps_);
    residual[0] = v_v.y() * T(inv_sigma_lateral_);
    residual[1] = v_v.z() * T(inv_sigma_vertical_);
    return true;
  }

  /// 2 residuals; blocks v_n (3), q_n_b (4).
  static ceres::CostFunction* Create(const Eigen::Matrix3d& R_v_b, const Eigen::Vector3d& lever_arm_b_m,
                                     const Eigen::Vector3d& omega_ib_b_radps, double sigma_lateral_mps,
                                     double sigma_vertical_mps) {
    return new ceres::AutoDiffCostFunction<NhcVelocity, kResiduals, kVelocitySize, kAttitudeSize>(
        new NhcVelocity(R_v_b, lever_arm_b_m, omega_ib_b_radps, sigma_lateral_mps, sigma_vertical_mps));
  }

 private:
  Eigen::Matrix3d R_v_b_;
  Eigen::Vector3d lever_velocity_b_mps_;  ///< omega_ib_b x l_b, m/s
  double inv_sigma_lateral_ = 0.0;
  double inv_sigma_vertical_ = 0.0;
};

}  // namespace navtwin
