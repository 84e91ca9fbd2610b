// Magnetic heading measurements (one residual, rad / sigma). Declination D: magnetic north
// is D rad east of true north. Angle differences are wrapped with wrap(a) = atan2(sin a,
// cos a) in (-pi, pi], which is smooth, so Jets differentiate through it.
//
// MagHeading: calibrated 3-axis field m_b (body FRD, uT). Rotated into NED with the
// estimated attitude, its horizontal azimuth is the magnetic-north azimuth; true attitude
// gives D:
//   m_n = R_n_b(q) m_b,   r = wrap(atan2(m_n,E, m_n,N) - D) / sigma
// A heading estimate too large by d (R_est = Rz(d) R_true) gives r = +d / sigma. Uses the
// full attitude (tilt included), so it needs no levelled field. Undefined when the field
// is vertical in NED (|m_n,N| = |m_n,E| = 0).
//
// MagHeading2Axis: only the two horizontal-plane axes (mx, my) of a compass held level
// (or already de-tilted). The measured heading is psi_m = atan2(-my, mx) + D and
//   r = wrap(yaw(q) - psi_m) / sigma,    yaw(q) = atan2(R(1,0), R(0,0)) (ZYX yaw).
// For a level body both models agree.
//
// Parameter block (both): q_n_b (4, x y z w, AttitudeManifold); R from the normalised q.
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"

namespace navtwin {

namespace mag_heading_detail {
inline void CheckSigma(double sigma_rad, const char* what) {
  if (!(sigma_rad > 0.0) || !std::isfinite(sigma_rad)) {
    throw std::invalid_argument(std::string(what) + ": sigma_rad must be positive and finite");
  }
}
/// wrap(a) = atan2(sin a, cos a) in (-pi, pi].
template <typename T>
T WrapAngle(const T& a) {
  using std::atan2;
  using std::cos;
  using std::sin;
  return atan2(sin(a), cos(a));
}
}  // namespace mag_heading_detail

class MagHeading {
 public:
  static constexpr int kResiduals = 1;
  static constexpr int kAttitudeSize = 4;  ///< block 0: q_n_b (x, y, z, w)

  /// m_b_uT: calibrated body field (finite, nonzero horizontal part once rotated);
  /// sigma_rad > 0 and finite (else std::invalid_argument).
  MagHeading(const Eigen::Vector3d& m_b_uT, double declination_rad, double sigma_rad)
      : m_b_uT_(m_b_uT), declination_rad_(declination_rad), inv_sigma_(1.0 / sigma_rad) {
    mag_heading_detail::CheckSigma(sigma_rad, "MagHeading");
    if (!m_b_uT.allFinite() || !std::isfinite(declination_rad)) {
      throw std::invalid_argument("MagHeading: m_b_uT and declination_rad must be finite");
    }
  }

  template <typename T>
  bool operator()(const T* q_n_b_ptr, T* residual) const {
    using std::atan2;
    const Eigen::Map<const Quaternion<T>> q_n_b(q_n_b_ptr);
    const Vector3<T> m_n = DcmFromQuat<T>(q_n_b) * m_b_uT_.cast<T>();
    residual[0] = mag_heading_detail::WrapAngle(atan2(m_n.y(), m_n.x()) - T(declination_rad_)) * T(inv_sigma_);
    return true;
  }

  /// 1 residual; block q_n_b (4).
  static ceres::CostFunction* Create(const Eigen::Vector3d& m_b_uT, double declination_rad, double sigma_rad) {
    return new ceres::AutoDiffCostFunction<MagHeading, kResiduals, kAttitudeSize>(
        new MagHeading(m_b_uT, declination_rad, sigma_rad));
  }

 private:
  Eigen::Vector3d m_b_uT_;
  double declination_rad_;
  double inv_sigma_;
};

class MagHeading2Axis {
 public:
  static constexpr int kResiduals = 1;
  static constexpr int kAttitudeSize = 4;  ///< block 0: q_n_b (x, y, z, w)

  /// mx_uT, my_uT: body x (forward) and y (right) field components of a level compass;
  /// sigma_rad > 0 and finite (else std::invalid_argument).
  MagHeading2Axis(double mx_uT, double my_uT, double declination_rad, double sigma_rad)
      : inv_sigma_(1.0 / sigma_rad) {
    mag_heading_detail::CheckSigma(sigma_rad, "MagHeading2Axis");
    if (!std::isfinite(mx_uT) || !std::isfinite(my_uT) || !std::isfinite(declination_rad)) {
      throw std::invalid_argument("MagHeading2Axis: mx_uT, my_uT and declination_rad must be finite");
    }
    heading_meas_rad_ = std::atan2(-my_uT, mx_uT) + declination_rad;
  }

  /// The measured true heading psi_m = atan2(-my, mx) + D, rad (not wrapped).
  double heading_meas_rad() const { return heading_meas_rad_; }

  template <typename T>
  bool operator()(const T* q_n_b_ptr, T* residual) const {
    using std::atan2;
    const Eigen::Map<const Quaternion<T>> q_n_b(q_n_b_ptr);
    const Matrix3<T> R_n_b = DcmFromQuat<T>(q_n_b);
    const T yaw = atan2(R_n_b(1, 0), R_n_b(0, 0));
    residual[0] = mag_heading_detail::WrapAngle(yaw - T(heading_meas_rad_)) * T(inv_sigma_);
    return true;
  }

  /// 1 residual; block q_n_b (4).
  static ceres::CostFunction* Create(double mx_uT, double my_uT, double declination_rad, double sigma_rad) {
    return new ceres::AutoDiffCostFunction<MagHeading2Axis, kResiduals, kAttitudeSize>(
        new MagHeading2Axis(mx_uT, my_uT, declination_rad, sigma_rad));
  }

 private:
  double heading_meas_rad_ = 0.0;
  double inv_sigma_;
};

}  // namespace navtwin
