// A body-frame unit-vector observation u_b of a known NED reference direction r_n
// (star tracker, sun sensor, normalised magnetometer or accelerometer):
//
//   r = (R_n_b(q_n_b) u_b - r_n) / sigma            (3 residuals, dimensionless)
//
// sigma: standard deviation of each component of the observed unit vector (for small
// errors, the angular error in rad). One residual per observation; the sum over several
// non-parallel directions is Wahba's problem. Parameter block: q_n_b, 4 doubles
// (x, y, z, w), to be used with AttitudeManifold; R_n_b is taken from the normalised q_n_b.
#pragma once

#include <cmath>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"

namespace navtwin {

class VectorDirection {
 public:
  /// u_b, r_n: unit vectors (body FRD, NED); sigma > 0 (unit-vector components).
  /// Throws std::invalid_argument for a non-positive or non-finite sigma or a non-finite vector.
  VectorDirection(const Eigen::Vector3d& u_b, const Eigen::Vector3d& r_n, double sigma)
      : u_b_(u_b), r_n_(r_n), inv_sigma_(1.0 / sigma) {
    if (!(sigma > 0.0) || !std::isfinite(sigma)) {
      throw std::invalid_argument("VectorDirection: sigma must be positive and finite");
    }
    if (!u_b.allFinite() || !r_n.allFinite()) {
      throw std::invalid_argument("VectorDirection: u_b and r_n must be finite");
    }
  }

  template <typename T>
  bool operator()(const T* q_n_b_ptr, T* residual_ptr) const {
    const Eigen::Map<const Quaternion<T>> q_n_b(q_n_b_ptr);
    const Vector3<T> u_n = DcmFromQuat<T>(q_n_b) * u_b_.cast<T>();
    Eigen::Map<Vector3<T>> residual(residual_ptr);
    residual = (u_n - r_n_.cast<T>()) * T(inv_sigma_);
    return true;
  }

  /// Residual block sizes: 3 residuals; parameter block q_n_b (4).
  static ceres::CostFunction* Create(const Eigen::Vector3d& u_b, const Eigen::Vector3d& r_n,
                                     double sigma) {
    return new ceres::AutoDiffCostFunction<VectorDirection, 3, 4>(new VectorDirection(u_b, r_n, sigma));
  }

 private:
  Eigen::Vector3d u_b_;
  Eigen::Vector3d r_n_;
  double inv_sigma_;
};

}  // namespace navtwin
