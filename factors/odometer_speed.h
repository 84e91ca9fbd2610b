// Wheel-odometer speed of the vehicle reference point with a scale-factor error s (an
// estimated parameter): the odometer reads (1 + s) times the forward speed, so with the
// IMU-to-vehicle mounting R_v_b, the reference point at lever arm l_b (body FRD, m) and
// the body angular rate omega_ib_b (rad/s, bias-corrected gyro output, a known input):
//
//   v_v = R_v_b (R_n_b^T v_n + omega_ib_b x l_b)               (VehicleFrameVelocity)
//   r   = ((1 + s) v_v,x - speed_meas) / sigma                 (1 residual)
//
// Parameter blocks: v_n (3), q_n_b (4, x y z w, AttitudeManifold), s (1, dimensionless).
#pragma once

#include <cmath>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>

#include "factors/nhc_velocity.h"

namespace navtwin {

class OdometerSpeed {
 public:
  static constexpr int kResiduals = 1;
  static constexpr int kVelocitySize = 3;  ///< block 0: v_n_mps
  static constexpr int kAttitudeSize = 4;  ///< block 1: q_n_b (x, y, z, w)
  static constexpr int kScaleSize = 1;     ///< block 2: scale-factor error s

  /// sigma_mps > 0 and finite, inputs finite (else std::invalid_argument).
  OdometerSpeed(const Eigen::Matrix3d& R_v_b, const Eigen::Vector3d& lever_arm_b_m,
                const Eigen::Vector3d& omega_ib_b_radps, double speed_meas_mps, double sigma_mps)
      : R_v_b_(R_v_b), lever_velocity_b_mps_(omega_ib_b_radps.cross(lever_arm_b_m)), speed_mps_(speed_meas_mps) {
    if (!(sigma_mps > 0.0) || !std::isfinite(sigma_mps)) {
      throw std::invalid_argument("OdometerSpeed: sigma_mps must be positive and finite");
    }
    if (!R_v_b.allFinite() || !lever_velocity_b_mps_.allFinite() || !std::isfinite(speed_meas_mps)) {
      throw std::invalid_argument("OdometerSpeed: mounting, lever arm, omega and speed must be finite");
    }
    inv_sigma_ = 1.0 / sigma_mps;
  }

  template <typename T>
  bool operator()(const T* v_n, const T* q_n_b, const T* scale, T* residual) const {
    const Vector3<T> v_v = VehicleFrameVelocity<T>(v_n, q_n_b, R_v_b_, lever_velocity_b_mps_);
    residual[0] = ((T(1.0) + scale[0]) * v_v.x() - T(speed_mps_)) * T(inv_sigma_);
    return true;
  }

  /// 1 residual; blocks v_n (3), q_n_b (4), s (1).
  static ceres::CostFunction* Create(const Eigen::Matrix3d& R_v_b, const Eigen::Vector3d& lever_arm_b_m,
                                     const Eigen::Vector3d& omega_ib_b_radps, double speed_meas_mps,
                                     double sigma_mps) {
    return new ceres::AutoDiffCostFunction<OdometerSpeed, kResiduals, kVelocitySize, kAttitudeSize, kScaleSize>(
        new OdometerSpeed(R_v_b, lever_arm_b_m, omega_ib_b_radps, speed_meas_mps, sigma_mps));
  }

 private:
  Eigen::Matrix3d R_v_b_;
  Eigen::Vector3d lever_velocity_b_mps_;  ///< omega_ib_b x l_b, m/s
  double speed_mps_;
  double inv_sigma_ = 0.0;
};

}  // namespace navtwin
