// The magnetometer iron model: the one meaning of "hard iron" and "soft iron" in navtwin.
//
//   sensor:      m_raw = (I + S) m_b + h            (uT, body/sensor axes)
//   correction:  m_b   = A (m_raw - h),   A = (I + S)^-1
//
// h is the hard iron (a constant offset, uT), S the soft iron (a dimensionless distortion,
// 0 for none) and A the correction matrix that undoes it. "Soft iron" always names S, the
// distortion; the matrix a calibration estimates and applies is A, the correction. The
// simulator draws S and h, the GNSS/INS configuration gives S and h, the magnetometer
// calibration fits A and h (symmetric A: the rotation part of A is the sensor alignment, not
// iron), and the calibration file stores A and h.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

namespace navtwin {

struct MagIronModel {
  Eigen::Vector3d hard_iron_uT = Eigen::Vector3d::Zero();  ///< h
  Eigen::Matrix3d soft_iron = Eigen::Matrix3d::Zero();     ///< S (dimensionless)

  /// m_raw = (I + S) m_b + h: the field a sensor with this iron reads.
  Eigen::Vector3d Apply(const Eigen::Vector3d& m_b_uT) const {
    return (Eigen::Matrix3d::Identity() + soft_iron) * m_b_uT + hard_iron_uT;
  }
  /// m_b = (I + S)^-1 (m_raw - h): the field with the iron removed.
  Eigen::Vector3d Remove(const Eigen::Vector3d& m_raw_uT) const {
    return (Eigen::Matrix3d::Identity() + soft_iron).partialPivLu().solve(m_raw_uT - hard_iron_uT);
  }
  /// A = (I + S)^-1.
  Eigen::Matrix3d Correction() const { return (Eigen::Matrix3d::Identity() + soft_iron).inverse(); }
  /// The model of a correction A (invertible) and hard iron h: S = A^-1 - I.
  static MagIronModel FromCorrection(const Eigen::Vector3d& hard_iron_uT, const Eigen::Matrix3d& correction) {
    return {hard_iron_uT, correction.inverse() - Eigen::Matrix3d::Identity()};
  }
};

/// m_b = A (m_raw - h) for a correction A and hard iron h as a calibration gives them.
inline Eigen::Vector3d RemoveIron(const Eigen::Vector3d& m_raw_uT, const Eigen::Vector3d& hard_iron_uT,
                                  const Eigen::Matrix3d& correction) {
  return correction * (m_raw_uT - hard_iron_uT);
}

}  // namespace navtwin
