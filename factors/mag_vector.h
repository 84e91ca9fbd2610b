// Magnetometer field-vector measurement m_b (body FRD, uT, calibrated: hard/soft iron
// removed) of a known local field m_n (NED, uT, e.g. from a geomagnetic model):
//
//   r = (R_n_b(q)^T m_n - m_b) / sigma                          (3 residuals, body axes)
//
// Parameter block: q_n_b (4, x y z w, AttitudeManifold); R_n_b from the normalised q.
#pragma once

#include <cmath>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"

namespace navtwin {

class MagVector {
 public:
  static constexpr int kResiduals = 3;
  static constexpr int kAttitudeSize = 4;  ///< block 0: q_n_b (x, y, z, w)

  /// sigma_uT > 0 and finite, vectors finite (else std::invalid_argument).
  MagVector(const Eigen::Vector3d& m_b_uT, const Eigen::Vector3d& field_ned_uT, double sigma_uT)
      : m_b_uT_(m_b_uT), field_ned_uT_(field_ned_uT), inv_sigma_(1.0 / sigma_uT) {
    if (!(sigma_uT > 0.0) || !std::isfinite(sigma_uT)) {
      throw std::invalid_argument("MagVector: sigma_uT must be positive and finite");
    }
    if (!m_b_uT.allFinite() || !field_ned_uT.allFinite()) {
      throw std::invalid_argument("MagVector: m_b_uT and field_ned_uT must be finite");
    }
  }

  template <typename T>
  bool operator()(const T* q_n_b_ptr, T* residual_ptr) const {
    const Eigen::Map<const Quaternion<T>> q_n_b(q_n_b_ptr);
    const Vector3<T> predicted_b = DcmFromQuat<T>(q_n_b).transpose() * field_ned_uT_.cast<T>();
    Eigen::Map<Vector3<T>> residual(residual_ptr);
    residual = (predicted_b - m_b_uT_.cast<T>()) * T(inv_sigma_);
    return true;
  }

  /// 3 residuals; block q_n_b (4).
  static ceres::CostFunction* Create(const Eigen::Vector3d& m_b_uT, const Eigen::Vector3d& field_ned_uT,
                                     double sigma_uT) {
    return new ceres::AutoDiffCostFunction<MagVector, kResiduals, kAttitudeSize>(
        new MagVector(m_b_uT, field_ned_uT, sigma_uT));
  }

 private:
  Eigen::Vector3d m_b_uT_;
  Eigen::Vector3d field_ned_uT_;
  double inv_sigma_;
};

}  // namespace navtwin
