// Magnetic heading measurements (one residual, rad / sigma). Declination D: magnetic north
// is D rad east of true north. Angle differences are wrapped with wrap(a) = atan2(sin a,
// cos a) in (-pi, pi], which is smooth, so Jets differentiate through it.
//
// MagHeading: calibrated 3-axis field m_b (body FRD, uT). Rotated into NED with the
// estimated attitude, its horizontal azimuth is the magnetic-north azimuth; true attitude
// gives D:
//   m_n = R_n_b(q) m_b,   h = |(m_n,N, m_n,E)|,   a = wrap(atan2(m_n,E, m_n,N) - D)
//   r = (h / H0) a / sigma
// with H0 > 0 a constant reference horizontal intensity (uT). A heading estimate too large
// by d (R_est = Rz(d) R_true) gives r = (h/H0) d / sigma (= d / sigma when H0 = h). Uses the
// full attitude (tilt included), so it needs no levelled field.
//
// Why h / H0 (errors in variables). The sample m_b is noisy and enters the Jacobian as well
// as the residual. For the bare angle a/sigma, the Jacobian column of the rotation about
// magnetic east (which tilts the field towards the horizontal) is -m_D m_E / h^2: it is made
// of the same cross-meridian noise m_E as a itself, so E[J^T r] != 0. Minimising a^2 rewards
// a larger h (the same cross-meridian noise is a smaller angle), and a filter at 50 Hz
// with sigma = noise / h walks the attitude towards "field horizontal" (tens of degrees in
// minutes). With the factor h / H0, h a ~= m_E' (the cross-meridian component, uT) and its
// Jacobian about magnetic east is m_D (a m_N - m_E) / h = O(noise^3): unbiased. Near the
// truth r = (cross-meridian noise) / (H0 sigma), so sigma = noise_uT / H0 whitens it (the
// vertical noise does not enter to first order).
//
// A second errors-in-variables effect remains for any function of R m_b: its null space is
// the rotation about the *measured* direction R m_b, not the field's, so the noise component
// in the magnetic meridian perpendicular to the field (the "dip" direction) gives every
// sample an information about the rotation about the field that is not there, ~ (noise /
// (H0 sigma))^2 rad^-2 per sample, and zero-mean updates along it: at 50 Hz the filter
// becomes overconfident about that rotation (unobservable in straight flight) and lets it
// wander. RemoveDipNoise takes that component out of the sample before the factor is built,
// using a reference attitude and a reference field direction (both constants).
// Undefined (r = 0) when the field is vertical in NED.
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
}  // namespace mag_heading_detail

class MagHeading {
 public:
  static constexpr int kResiduals = 1;
  static constexpr int kAttitudeSize = 4;  ///< block 0: q_n_b (x, y, z, w)

  /// m_b_uT: calibrated body field (finite, nonzero horizontal part once rotated);
  /// sigma_rad > 0 and finite: the heading std at horizontal intensity H0
  /// (noise_uT / H0 for white per-axis noise); horizontal_field_uT = H0 > 0 and finite, a
  /// constant (a field model's, or the mean horizontal field of the record). Else
  /// std::invalid_argument.
  MagHeading(const Eigen::Vector3d& m_b_uT, double declination_rad, double sigma_rad, double horizontal_field_uT)
      : m_b_uT_(m_b_uT), declination_rad_(declination_rad), inv_sigma_h0_(1.0 / (sigma_rad * horizontal_field_uT)) {
    mag_heading_detail::CheckSigma(sigma_rad, "MagHeading");
    if (!m_b_uT.allFinite() || !std::isfinite(declination_rad)) {
      throw std::invalid_argument("MagHeading: m_b_uT and declination_rad must be finite");
    }
    if (!(horizontal_field_uT > 0.0) || !std::isfinite(horizontal_field_uT)) {
      throw std::invalid_argument("MagHeading: horizontal_field_uT must be positive and finite");
    }
  }

  template <typename T>
  bool operator()(const T* q_n_b_ptr, T* residual) const {
    using std::atan2;
    using std::sqrt;
    const Eigen::Map<const Quaternion<T>> q_n_b(q_n_b_ptr);
    const Vector3<T> m_n = DcmFromQuat<T>(q_n_b) * m_b_uT_.cast<T>();
    const T h2 = m_n.x() * m_n.x() + m_n.y() * m_n.y();
    if (!(h2 > T(0.0))) {  // vertical field: no azimuth (and sqrt(0) has no derivative)
      residual[0] = T(0.0);
      return true;
    }
    const T a = WrapPi(atan2(m_n.y(), m_n.x()) - T(declination_rad_));
    residual[0] = sqrt(h2) * a * T(inv_sigma_h0_);
    return true;
  }

  /// 1 residual; block q_n_b (4).
  static ceres::CostFunction* Create(const Eigen::Vector3d& m_b_uT, double declination_rad, double sigma_rad,
                                     double horizontal_field_uT) {
    return new ceres::AutoDiffCostFunction<MagHeading, kResiduals, kAttitudeSize>(
        new MagHeading(m_b_uT, declination_rad, sigma_rad, horizontal_field_uT));
  }

  /// The sample without its component along the dip direction d (header comment): with
  /// f = field_ned_uT / |field_ned_uT| (a reference field direction, e.g. the mean of
  /// R m_b over the record) and d = unit(z - (z.f) f) (down, NED; in the field's vertical
  /// plane, perpendicular to f),
  ///   m_b' = m_b - (d . R(q_ref) m_b) R(q_ref)^T d.
  /// The component carries no heading (the field has none along d) and only the noise
  /// and the reference attitude's tilt error about magnetic east; the azimuth changes to
  /// second order. Returns m_b unchanged when f is zero, vertical or not finite.
  static Eigen::Vector3d RemoveDipNoise(const Eigen::Vector3d& m_b_uT, const Eigen::Quaterniond& q_ref,
                                        const Eigen::Vector3d& field_ned_uT) {
    const double norm = field_ned_uT.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) return m_b_uT;
    const Eigen::Vector3d f = field_ned_uT / norm;
    Eigen::Vector3d d = Eigen::Vector3d::UnitZ() - f.z() * f;
    const double d_norm = d.norm();
    if (!(d_norm > 1e-9)) return m_b_uT;
    d /= d_norm;
    const Eigen::Matrix3d R = q_ref.normalized().toRotationMatrix();
    return m_b_uT - d.dot(R * m_b_uT) * (R.transpose() * d);
  }

 private:
  Eigen::Vector3d m_b_uT_;
  double declination_rad_;
  double inv_sigma_h0_;  ///< 1 / (sigma H0)
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
    residual[0] = WrapPi(yaw - T(heading_meas_rad_)) * T(inv_sigma_);
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
