// Prior on an attitude q_n_b (e.g. an initial alignment) in the attitude-error
// convention of core/rotation.h:
//
//   r = S * Log(q_n_b (x) q_n_b_prior^-1)          (3 residuals, dimensionless)
//
// i.e. the rotation vector phi_n (rad, navigation frame) with R_n_b = Exp(phi_n) R_prior,
// whitened by S = sqrt_information (3x3, 1/rad), S^T S = P^-1 for the prior covariance
// P (rad^2) of phi_n. Parameter block: q_n_b, 4 doubles (x, y, z, w), to be used with
// AttitudeManifold. The residual is invariant to the sign and the scale of q_n_b.
#pragma once

#include <stdexcept>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"

namespace navtwin {

class AttitudePrior {
 public:
  /// Throws std::invalid_argument for a zero or non-finite prior or a non-finite sqrt_information.
  AttitudePrior(const Eigen::Quaterniond& q_n_b_prior, const Eigen::Matrix3d& sqrt_information)
      : q_n_b_prior_(q_n_b_prior.normalized()), sqrt_information_(sqrt_information) {
    if (!q_n_b_prior.coeffs().allFinite() || !(q_n_b_prior.norm() > 0.0)) {
      throw std::invalid_argument("AttitudePrior: q_n_b_prior must be finite and non-zero");
    }
    if (!sqrt_information.allFinite()) {
      throw std::invalid_argument("AttitudePrior: sqrt_information must be finite");
    }
  }

  template <typename T>
  bool operator()(const T* q_n_b_ptr, T* residual_ptr) const {
    const Eigen::Map<const Quaternion<T>> q_n_b(q_n_b_ptr);
    const Vector3<T> phi_n_rad = AttitudeError<T>(q_n_b, q_n_b_prior_.cast<T>());
    Eigen::Map<Vector3<T>> residual(residual_ptr);
    residual = sqrt_information_.cast<T>() * phi_n_rad;
    return true;
  }

  /// Residual block sizes: 3 residuals; parameter block q_n_b (4).
  static ceres::CostFunction* Create(const Eigen::Quaterniond& q_n_b_prior,
                                     const Eigen::Matrix3d& sqrt_information) {
    return new ceres::AutoDiffCostFunction<AttitudePrior, 3, 4>(
        new AttitudePrior(q_n_b_prior, sqrt_information));
  }

 private:
  Eigen::Quaterniond q_n_b_prior_;
  Eigen::Matrix3d sqrt_information_;
};

}  // namespace navtwin
