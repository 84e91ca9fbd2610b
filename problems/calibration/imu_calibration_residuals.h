// Residuals of the multi-position IMU calibration (problems/calibration/multiposition.h),
// in the error model of core/imu_error_model.h (blocks: accel triad 12, gyro triad 12,
// g-sensitivity 9). Every residual is already weighted (divided by its sigma).
//
//  - StaticAccelResidual (3): at a static position with true specific force f_b,
//      r = (K_a f_b + b_a - mean f_m) / sigma                     (linear in the accel block)
//  - StaticGyroResidual (3): with the true rate omega_ib_b = R_b_n omega_ie_n,
//      r = (K_g omega + G f_b + b_g - mean omega_m) / sigma      (linear in gyro and G)
//  - GyroMoveResidual (3): the increments of a move between two static positions a and b,
//    compensated with the parameters, u_k = K_g^-1 (dtheta_k - G dv_k - b_g dt_k), with the
//    two-sample coning correction phi_k = u_k + u_{k-1} x u_k / 12 (phi_0 = u_0), integrated
//    R = Exp(phi_0) Exp(phi_1) ... Exp(phi_{N-1}), must equal the true rotation of the body
//    over the move, R_true = R_b_n(a) Exp(omega_ie_n (t_b - t_a)) R_n_b(b) (NED turns with
//    the Earth at omega_ie_n):
//      r = Log(R_true^T R) / sigma                               (rad / rad)
//    G multiplies the true specific-force increment dv_k = f_b dt of the table attitude
//    (GyroMove::samples carry it in dv_b_mps), as in the static residual.
//    GyroMoveCost is the same residual with the analytic Jacobian (a move has hundreds of
//    samples; autodiff with 21-wide Jets would dominate the solve):
//      R -> R Exp(eps),  eps = R^T sum_k R_k Jr(phi_k) dphi_k     (R_k = Exp(phi_0)...Exp(phi_k))
//      dphi_k = (I + [u_{k-1}]x / 12) du_k - [u_k]x / 12 du_{k-1}
//      du_k = -K_g^-1 B_k dp,  B_k = d(K_g u_k + G dv_k + b_g dt_k)/dp at fixed u_k
//      dr = Jr^-1(r) eps / sigma
//    tests/problems/calibration/imu_calibration_residuals_test.cc checks it against autodiff of
//    GyroMoveResidual.
#pragma once

#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include <ceres/sized_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/imu_error_model.h"
#include "core/rotation.h"
#include "core/types.h"

namespace navtwin::calibration {

class StaticAccelResidual {
 public:
  /// f_true_b: true specific force; f_mean_b: mean measured; sigma_mps2: per axis (> 0).
  StaticAccelResidual(const Eigen::Vector3d& f_true_b, const Eigen::Vector3d& f_mean_b, const Eigen::Vector3d& sigma_mps2)
      : f_true_b_(f_true_b), f_mean_b_(f_mean_b), inv_sigma_(sigma_mps2.cwiseInverse()) {
    if (!(sigma_mps2.minCoeff() > 0.0) || !sigma_mps2.allFinite()) {
      throw std::invalid_argument("StaticAccelResidual: sigma must be positive and finite");
    }
  }
  template <typename T>
  bool operator()(const T* accel, T* residual) const {
    const Eigen::Matrix<T, 3, 1> f = f_true_b_.cast<T>();
    const Eigen::Matrix<T, 3, 1> r = MeasuredSpecificForce(accel, f) - f_mean_b_.cast<T>();
    for (int i = 0; i < 3; ++i) residual[i] = r(i) * T(inv_sigma_(i));
    return true;
  }

 private:
  Eigen::Vector3d f_true_b_, f_mean_b_, inv_sigma_;
};

class StaticGyroResidual {
 public:
  StaticGyroResidual(const Eigen::Vector3d& omega_true_b, const Eigen::Vector3d& f_true_b,
                     const Eigen::Vector3d& omega_mean_b, const Eigen::Vector3d& sigma_radps)
      : omega_true_b_(omega_true_b), f_true_b_(f_true_b), omega_mean_b_(omega_mean_b),
        inv_sigma_(sigma_radps.cwiseInverse()) {
    if (!(sigma_radps.minCoeff() > 0.0) || !sigma_radps.allFinite()) {
      throw std::invalid_argument("StaticGyroResidual: sigma must be positive and finite");
    }
  }
  template <typename T>
  bool operator()(const T* gyro, const T* g9, T* residual) const {
    const Eigen::Matrix<T, 3, 1> omega = omega_true_b_.cast<T>(), f = f_true_b_.cast<T>();
    const Eigen::Matrix<T, 3, 1> r = MeasuredRate(gyro, g9, omega, f) - omega_mean_b_.cast<T>();
    for (int i = 0; i < 3; ++i) residual[i] = r(i) * T(inv_sigma_(i));
    return true;
  }

 private:
  Eigen::Vector3d omega_true_b_, f_true_b_, omega_mean_b_, inv_sigma_;
};

/// The data of one move: the samples over (t_a, t_b] and the true rotation R_true.
struct GyroMove {
  std::vector<ImuSample> samples;  ///< measured dtheta, TRUE dv (f_b dt), dt
  Eigen::Matrix3d R_true = Eigen::Matrix3d::Identity();  ///< body at t_a -> body at t_b
  double sigma_rad = 1.0;                                ///< of each component of r
};

/// The rotation of the body over `samples` from the gyro increments compensated with the
/// parameters (u_k above), two-sample coning corrected: R = Exp(phi_0) ... Exp(phi_{N-1}),
/// body at the first sample's start -> body at the last's end. G may be zero.
template <typename T>
Eigen::Matrix<T, 3, 3> IntegrateCompensatedGyro(const std::vector<ImuSample>& samples, const T* gyro,
                                                const Eigen::Matrix<T, 3, 3>& G) {
  using V3 = Eigen::Matrix<T, 3, 1>;
  const Eigen::Matrix<T, 3, 3> K_inv = TriadMatrix(gyro).inverse();
  const V3 b = TriadBias(gyro);
  Eigen::Quaternion<T> q = Eigen::Quaternion<T>::Identity();
  V3 u_prev = V3::Zero();
  bool first = true;
  for (const ImuSample& s : samples) {
    const V3 u = K_inv * (s.dtheta_b_rad.cast<T>() - G * s.dv_b_mps.cast<T>() - b * T(s.dt_s));
    const V3 phi = first ? u : V3(u + u_prev.cross(u) / T(12.0));
    q = q * QuatFromRotVec(phi);
    u_prev = u;
    first = false;
  }
  return DcmFromQuat(q);
}

class GyroMoveResidual {
 public:
  explicit GyroMoveResidual(const GyroMove* move) : move_(move) {}
  template <typename T>
  bool operator()(const T* gyro, const T* g9, T* residual) const {
    using V3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Matrix<T, 3, 3> R = IntegrateCompensatedGyro(move_->samples, gyro, GSensitivityMatrix(g9));
    const V3 r = LogSO3(Eigen::Matrix<T, 3, 3>(move_->R_true.cast<T>().transpose() * R));
    for (int i = 0; i < 3; ++i) residual[i] = r(i) / T(move_->sigma_rad);
    return true;
  }

 private:
  const GyroMove* move_;
};

class GyroMoveCost : public ceres::SizedCostFunction<3, kTriadParameters, kGSensitivityParameters> {
 public:
  explicit GyroMoveCost(const GyroMove* move) : move_(move) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    using Mat3x21 = Eigen::Matrix<double, 3, kTriadParameters + kGSensitivityParameters>;
    const double* gyro = parameters[0];
    const double* g9 = parameters[1];
    const Eigen::Matrix3d K_inv = TriadMatrix(gyro).inverse();
    const Eigen::Matrix3d G = GSensitivityMatrix(g9);
    const Eigen::Vector3d b = TriadBias(gyro);
    const bool want = jacobians != nullptr && (jacobians[0] != nullptr || jacobians[1] != nullptr);
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    Eigen::Vector3d u_prev = Eigen::Vector3d::Zero();
    Mat3x21 du_prev = Mat3x21::Zero();
    Mat3x21 S = Mat3x21::Zero();  // sum_k R_k Jr(phi_k) dphi_k/dp
    bool first = true;
    for (const ImuSample& s : move_->samples) {
      const Eigen::Vector3d u = K_inv * (s.dtheta_b_rad - G * s.dv_b_mps - b * s.dt_s);
      const Eigen::Vector3d phi = first ? u : Eigen::Vector3d(u + u_prev.cross(u) / 12.0);
      q = q * QuatFromRotVec(phi);
      q.normalize();
      if (want) {
        Mat3x21 B = Mat3x21::Zero();
        for (int r = 0; r < 3; ++r) {
          B(r, r) = u(r);
          for (int c = 0; c < 3; ++c) {
            if (c != r) B(r, MisalignmentIndex(r, c)) = u(c);
            B(r, kTriadParameters + 3 * r + c) = s.dv_b_mps(c);
          }
          B(r, 9 + r) = s.dt_s;
        }
        const Mat3x21 du = -K_inv * B;
        Mat3x21 dphi = du;
        if (!first) dphi = (Eigen::Matrix3d::Identity() + Skew(u_prev) / 12.0) * du - Skew(u) / 12.0 * du_prev;
        S.noalias() += (q.toRotationMatrix() * RightJacobianSO3(phi)) * dphi;
        du_prev = du;
      }
      u_prev = u;
      first = false;
    }
    const Eigen::Matrix3d R = q.toRotationMatrix();
    const Eigen::Vector3d r = LogSO3(Eigen::Matrix3d(move_->R_true.transpose() * R));
    const double w = 1.0 / move_->sigma_rad;
    Eigen::Map<Eigen::Vector3d> residual_map(residuals);
    residual_map = r * w;
    if (want) {
      const Mat3x21 J = w * RightJacobianInverseSO3(r) * R.transpose() * S;
      if (jacobians[0] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, 3, kTriadParameters, Eigen::RowMajor>> J_gyro(jacobians[0]);
        J_gyro = J.leftCols<kTriadParameters>();
      }
      if (jacobians[1] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, 3, kGSensitivityParameters, Eigen::RowMajor>> J_g(jacobians[1]);
        J_g = J.rightCols<kGSensitivityParameters>();
      }
    }
    return true;
  }

 private:
  const GyroMove* move_;
};

}  // namespace navtwin::calibration
