// GNSS antenna velocity measurement v_meas_n (NED, m/s) of an antenna at lever arm l_b
// (body FRD, m), with the body angular rate omega_ib_b (rad/s, bias-corrected gyro output,
// held fixed as a known input of the measurement):
//
//   v_ant_n = v_n + R_n_b (omega_ib_b x l_b)
//   r = (v_ant_n - v_meas_n) / sigma_ned                        (3 residuals, NED)
//
// The Earth-rate term -omega_in_n x (R_n_b l_b) of the full lever-arm velocity is
// neglected: |omega_in| is the Earth rate 7.29e-5 rad/s plus the transport rate (~2e-6
// rad/s at 10 m/s), so the term is below 1.5e-4 m/s for |l_b| < 2 m (below 1e-4 m/s for
// |l_b| < 1.3 m), far under any GNSS velocity sigma (>= 0.01 m/s).
// Parameter blocks: v_n (3, Euclidean), q_n_b (4, x y z w, AttitudeManifold).
#pragma once

#include <cmath>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"

namespace navtwin {

class GnssVelocity {
 public:
  static constexpr int kResiduals = 3;
  static constexpr int kVelocitySize = 3;  ///< block 0: v_n_mps
  static constexpr int kAttitudeSize = 4;  ///< block 1: q_n_b (x, y, z, w)

  /// std_ned_mps: 1-sigma per NED axis, each > 0 and finite (else std::invalid_argument).
  GnssVelocity(const Eigen::Vector3d& v_meas_n_mps, const Eigen::Vector3d& lever_arm_b_m,
               const Eigen::Vector3d& omega_ib_b_radps, const Eigen::Vector3d& std_ned_mps)
      : v_meas_n_mps_(v_meas_n_mps), lever_velocity_b_mps_(omega_ib_b_radps.cross(lever_arm_b_m)) {
    for (int i = 0; i < 3; ++i) {
      if (!(std_ned_mps[i] > 0.0) || !std::isfinite(std_ned_mps[i])) {
        throw std::invalid_argument("GnssVelocity: std_ned_mps must be positive and finite");
      }
    }
    if (!v_meas_n_mps.allFinite() || !lever_arm_b_m.allFinite() || !omega_ib_b_radps.allFinite()) {
      throw std::invalid_argument("GnssVelocity: v_meas, lever arm and omega must be finite");
    }
    inv_sigma_ = std_ned_mps.cwiseInverse();
  }
  /// The same sigma on the three NED axes.
  GnssVelocity(const Eigen::Vector3d& v_meas_n_mps, const Eigen::Vector3d& lever_arm_b_m,
               const Eigen::Vector3d& omega_ib_b_radps, double std_mps)
      : GnssVelocity(v_meas_n_mps, lever_arm_b_m, omega_ib_b_radps, Eigen::Vector3d::Constant(std_mps)) {}

  template <typename T>
  bool operator()(const T* v_n_ptr, const T* q_n_b_ptr, T* residual_ptr) const {
    const Eigen::Map<const Vector3<T>> v_n(v_n_ptr);
    const Eigen::Map<const Quaternion<T>> q_n_b(q_n_b_ptr);
    const Vector3<T> v_ant_n = v_n + DcmFromQuat<T>(q_n_b) * lever_velocity_b_mps_.cast<T>();
    Eigen::Map<Vector3<T>> residual(residual_ptr);
    residual = (v_ant_n - v_meas_n_mps_.cast<T>()).cwiseProduct(inv_sigma_.cast<T>());
    return true;
  }

  /// 3 residuals; blocks v_n (3), q_n_b (4).
  static ceres::CostFunction* Create(const Eigen::Vector3d& v_meas_n_mps, const Eigen::Vector3d& lever_arm_b_m,
                                     const Eigen::Vector3d& omega_ib_b_radps,
                                     const Eigen::Vector3d& std_ned_mps) {
    return new ceres::AutoDiffCostFunction<GnssVelocity, kResiduals, kVelocitySize, kAttitudeSize>(
        new GnssVelocity(v_meas_n_mps, lever_arm_b_m, omega_ib_b_radps, std_ned_mps));
  }
  static ceres::CostFunction* Create(const Eigen::Vector3d& v_meas_n_mps, const Eigen::Vector3d& lever_arm_b_m,
                                     const Eigen::Vector3d& omega_ib_b_radps, double std_mps) {
    return Create(v_meas_n_mps, lever_arm_b_m, omega_ib_b_radps, Eigen::Vector3d::Constant(std_mps));
  }

 private:
  Eigen::Vector3d v_meas_n_mps_;
  Eigen::Vector3d lever_velocity_b_mps_;  ///< omega_ib_b x l_b, m/s
  Eigen::Vector3d inv_sigma_;
};

}  // namespace navtwin
