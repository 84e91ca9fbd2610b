// Magnetometer ellipsoid (hard + symmetric soft iron) residual of one raw sample m (sensor
// axes, uT). Model (problems/calibration/mag_calibration.h): m = (I + S) m_b + h + n with
// |m_b| = B, so the calibrated field A (m - h), A = (I + S)^-1 (symmetric), has magnitude B:
//
//   v = A (m - h),    r = (|v| - B) / sigma                        (1 residual, uT / uT)
//
//   A = [[a0, a1, a2],
//        [a1, a3, a4],        (A_sym block: A00 A01 A02 A11 A12 A22, the order of
//        [a2, a4, a5]]         MagCalibration::correction_sigma)
//
// Jacobian (what autodiff computes; written out for reference):
//   dr/dh = -(u^T A) / sigma,  u = v / |v|;   dr/dA_ij = u_i d_j / sigma, d = m - h
//   (symmetric entries: dr/da1 = (u_0 d_1 + u_1 d_0) / sigma, ...);   dr/dB = -1 / sigma.
// At v = 0 the norm has no derivative; the residual is then -B / sigma with zero Jacobian
// for h and A (never NaN).
//
// Parameter blocks: h (3, uT), A_sym (6, dimensionless), B (1, uT; hold it constant when the
// field magnitude is given: B and the scale of A are not separable from magnitudes alone).
#pragma once

#include <cmath>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>

namespace navtwin::calibration {

class MagEllipsoid {
 public:
  static constexpr int kResiduals = 1;
  static constexpr int kHardIronSize = 3;   ///< block 0: h (uT)
  static constexpr int kCorrectionSize = 6; ///< block 1: A00 A01 A02 A11 A12 A22
  static constexpr int kFieldSize = 1;      ///< block 2: B (uT)

  /// m_uT finite; sigma_uT > 0 and finite (else std::invalid_argument).
  MagEllipsoid(const Eigen::Vector3d& m_uT, double sigma_uT) : m_uT_(m_uT), inv_sigma_(1.0 / sigma_uT) {
    if (!(sigma_uT > 0.0) || !std::isfinite(sigma_uT)) {
      throw std::invalid_argument("MagEllipsoid: sigma_uT must be positive and finite");
    }
    if (!m_uT.allFinite()) throw std::invalid_argument("MagEllipsoid: m_uT must be finite");
  }

  /// A from its 6 upper-triangle entries (A00 A01 A02 A11 A12 A22).
  template <typename T>
  static Eigen::Matrix<T, 3, 3> SymmetricFromUpper(const T* a) {
    Eigen::Matrix<T, 3, 3> A;
    A << a[0], a[1], a[2],
         a[1], a[3], a[4],
         a[2], a[4], a[5];
    return A;
  }

  template <typename T>
  bool operator()(const T* hard_iron_ptr, const T* a_sym_ptr, const T* field_ptr, T* residual) const {
    using std::sqrt;
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> h(hard_iron_ptr);
    const Eigen::Matrix<T, 3, 1> v = SymmetricFromUpper(a_sym_ptr) * (m_uT_.cast<T>() - h);
    const T n2 = v.squaredNorm();
    const T norm = n2 > T(0.0) ? sqrt(n2) : T(0.0);  // sqrt(0) has no derivative
    residual[0] = (norm - field_ptr[0]) * T(inv_sigma_);
    return true;
  }

  /// 1 residual; blocks h (3), A_sym (6), B (1).
  static ceres::CostFunction* Create(const Eigen::Vector3d& m_uT, double sigma_uT) {
    return new ceres::AutoDiffCostFunction<MagEllipsoid, kResiduals, kHardIronSize, kCorrectionSize, kFieldSize>(
        new MagEllipsoid(m_uT, sigma_uT));
  }

 private:
  Eigen::Vector3d m_uT_;
  double inv_sigma_;
};

}  // namespace navtwin::calibration
