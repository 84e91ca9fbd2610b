// Distance-based heading residual of one GPS fix (seed 003, equation 8 in its exact form,
// with the Schuler part of the free INS's error; problems/inflight_alignment/batch.h):
//
//   r = ( err - (Rz(dH) - I) D - s(t) ) / sigma_gps                 (2 residuals: N, E; -)
//
// err = (err_N, err_E): distance error of the fix, free INS minus GPS (m);
// D = (D_N, D_E): gained displacement of the free INS (m, free_ins.h);
// Rz(dH): rotation of (N, E) by the heading error dH = yaw_ins - yaw_true, clockwise seen
// from above (an INS heading dH too large turns north towards east):
//   Rz(dH) D = ( cos dH D_N - sin dH D_E,  sin dH D_N + cos dH D_E ),
// so to first order err_E = dH D_N, err_N = -dH D_E (distance_heading.h). cos dH - 1 is
// evaluated as -2 sin^2(dH / 2), without cancellation at small dH.
// s(t): Schuler part of the error (distance_heading.h, SchulerBasis b_k at t since the start):
//   s_N = dp0_N + dv0_N b1 + (df_N + g eps_E) b2 + g dw_E b3
//   s_E = dp0_E + dv0_E b1 + (df_E - g eps_N) b2 - g dw_N b3
// eps = (eps_N, eps_E) level attitude error at the start (rad), df / dw accelerometer (m/s^2)
// and gyro (rad/s) bias projected on north and east, dp0 / dv0 initial position (m) and
// velocity (m/s) error, g gravity (m/s^2).
//
// Parameter blocks (all Euclidean, SI): heading {dH} (1), level {eps_N, eps_E} (2),
// accel bias {df_N, df_E} (2), gyro bias {dw_N, dw_E} (2), position0 {dp0_N, dp0_E} (2),
// velocity0 {dv0_N, dv0_E} (2).
//
// DistanceHeadingTiltWalkResidual: the same residual with the level attitude random-walking
// (gyro angle random walk). The walk is cut into steps d_eps_k = (d_eps_N, d_eps_E)_k at times
// tau_k; a step at tau is the level error eps starting at tau, so it adds the tilt column of
// the Schuler part shifted in time, c_k = SchulerBasis(t - tau_k)[2] = (1 - cos w(t - tau_k)) / w^2:
//   r = ( err - (Rz(dH) - I) D - s(t) - sum_k c_k (g d_eps_E,k, -g d_eps_N,k) ) / sigma_gps
// over the steps with tau_k < t (c_k = 0 at t = tau_k, and a later step has no effect yet).
// The steps enter linearly: the constant part is DistanceHeadingResidual (AutoDiff, blocks
// 0-5 as above) and the steps add their analytic terms, one 2-block per step after those:
//   d r / d d_eps_k = (c_k g / sigma_gps) [[0, -1], [1, 0]]        (rows N, E; columns N, E)
//
// VectorPrior2: r = (x - x0) / sigma (2 residuals), block x (2): the zero-mean
// sensor-specification priors of the 2-blocks above (factors/state_prior.h has the
// 3-vector form).
#pragma once

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <ceres/autodiff_cost_function.h>
#include <ceres/cost_function.h>
#include <Eigen/Core>

namespace navtwin::inflight {

class DistanceHeadingResidual {
 public:
  static constexpr int kResiduals = 2;      ///< north, east (whitened)
  static constexpr int kHeadingSize = 1;    ///< block 0: dH (rad)
  static constexpr int kLevelSize = 2;      ///< block 1: eps_N, eps_E (rad)
  static constexpr int kAccelBiasSize = 2;  ///< block 2: df_N, df_E (m/s^2)
  static constexpr int kGyroBiasSize = 2;   ///< block 3: dw_N, dw_E (rad/s)
  static constexpr int kPositionSize = 2;   ///< block 4: dp0_N, dp0_E (m)
  static constexpr int kVelocitySize = 2;   ///< block 5: dv0_N, dv0_E (m/s)

  /// basis_b1_s, basis_b2_s2, basis_b3_s3: SchulerBasis(t)[1..3] (s, s^2, s^3);
  /// gained_ne_m: D; error_ne_m: err; sigma_m > 0; gravity_mps2 > 0. All finite, else
  /// std::invalid_argument.
  DistanceHeadingResidual(double basis_b1_s, double basis_b2_s2, double basis_b3_s3,
                          const Eigen::Vector2d& gained_ne_m, const Eigen::Vector2d& error_ne_m,
                          double sigma_m, double gravity_mps2)
      : b1_(basis_b1_s), b2_(basis_b2_s2), b3_(basis_b3_s3), gained_ne_m_(gained_ne_m),
        error_ne_m_(error_ne_m), inv_sigma_(1.0 / sigma_m), g_(gravity_mps2) {
    if (!std::isfinite(basis_b1_s) || !std::isfinite(basis_b2_s2) || !std::isfinite(basis_b3_s3)) {
      throw std::invalid_argument("DistanceHeadingResidual: Schuler basis values must be finite");
    }
    if (!gained_ne_m.allFinite() || !error_ne_m.allFinite()) {
      throw std::invalid_argument("DistanceHeadingResidual: gained displacement and error must be finite");
    }
    if (!(sigma_m > 0.0) || !std::isfinite(sigma_m)) {
      throw std::invalid_argument("DistanceHeadingResidual: sigma_m must be positive and finite");
    }
    if (!(gravity_mps2 > 0.0) || !std::isfinite(gravity_mps2)) {
      throw std::invalid_argument("DistanceHeadingResidual: gravity_mps2 must be positive and finite");
    }
  }

  template <typename T>
  bool operator()(const T* heading_rad, const T* level_rad, const T* accel_bias_mps2, const T* gyro_bias_radps,
                  const T* position0_m, const T* velocity0_mps, T* residual_ptr) const {
    using Vec2 = Eigen::Matrix<T, 2, 1>;
    using std::sin;
    const Eigen::Map<const Vec2> eps(level_rad), df(accel_bias_mps2), dw(gyro_bias_radps);
    const Eigen::Map<const Vec2> dp0(position0_m), dv0(velocity0_mps);
    const T g(g_);

    // (Rz(dH) - I) D with cos dH - 1 = -2 sin^2(dH/2).
    const T sin_half = sin(heading_rad[0] / T(2));
    const T cos_minus_one = T(-2) * sin_half * sin_half;
    const T sin_h = sin(heading_rad[0]);
    const T dn(gained_ne_m_[0]), de(gained_ne_m_[1]);
    const Vec2 rotation(cos_minus_one * dn - sin_h * de, sin_h * dn + cos_minus_one * de);

    // Schuler part: offset, velocity, tilt (accelerometer and level) and gyro terms.
    const Vec2 tilt(df[0] + g * eps[1], df[1] - g * eps[0]);
    const Vec2 gyro(g * dw[1], -g * dw[0]);
    const Vec2 schuler = dp0 + dv0 * T(b1_) + tilt * T(b2_) + gyro * T(b3_);

    Eigen::Map<Vec2> residual(residual_ptr);
    residual = (error_ne_m_.cast<T>() - rotation - schuler) * T(inv_sigma_);
    return true;
  }

  /// 2 residuals; blocks heading (1), level (2), accel bias (2), gyro bias (2),
  /// position0 (2), velocity0 (2).
  static ceres::CostFunction* Create(double basis_b1_s, double basis_b2_s2, double basis_b3_s3,
                                     const Eigen::Vector2d& gained_ne_m, const Eigen::Vector2d& error_ne_m,
                                     double sigma_m, double gravity_mps2) {
    return new ceres::AutoDiffCostFunction<DistanceHeadingResidual, kResiduals, kHeadingSize, kLevelSize,
                                           kAccelBiasSize, kGyroBiasSize, kPositionSize, kVelocitySize>(
        new DistanceHeadingResidual(basis_b1_s, basis_b2_s2, basis_b3_s3, gained_ne_m, error_ne_m, sigma_m,
                                    gravity_mps2));
  }

 private:
  double b1_, b2_, b3_;
  Eigen::Vector2d gained_ne_m_;
  Eigen::Vector2d error_ne_m_;
  double inv_sigma_;
  double g_;
};

class DistanceHeadingTiltWalkResidual final : public ceres::CostFunction {
 public:
  static constexpr int kConstantBlocks = 6;  ///< blocks 0-5: those of DistanceHeadingResidual
  static constexpr int kStepSize = 2;        ///< blocks 6, 7, ...: d_eps_N, d_eps_E of a step (rad)

  /// The DistanceHeadingResidual arguments, then step_basis_s2: c_k = SchulerBasis(t -
  /// tau_k)[2] (s^2) of each step the fix depends on, in block order (may be empty). All
  /// finite, else std::invalid_argument (as the constructor of DistanceHeadingResidual).
  DistanceHeadingTiltWalkResidual(double basis_b1_s, double basis_b2_s2, double basis_b3_s3,
                                  const Eigen::Vector2d& gained_ne_m, const Eigen::Vector2d& error_ne_m,
                                  double sigma_m, double gravity_mps2, std::vector<double> step_basis_s2)
      : constant_(DistanceHeadingResidual::Create(basis_b1_s, basis_b2_s2, basis_b3_s3, gained_ne_m, error_ne_m,
                                                  sigma_m, gravity_mps2)),
        step_basis_s2_(std::move(step_basis_s2)), g_over_sigma_(gravity_mps2 / sigma_m) {
    for (std::size_t k = 0; k < step_basis_s2_.size(); ++k) {
      if (!std::isfinite(step_basis_s2_[k])) {
        throw std::invalid_argument("DistanceHeadingTiltWalkResidual: step_basis_s2[" + std::to_string(k) +
                                    "] is not finite");
      }
    }
    set_num_residuals(DistanceHeadingResidual::kResiduals);
    *mutable_parameter_block_sizes() = constant_->parameter_block_sizes();
    mutable_parameter_block_sizes()->insert(mutable_parameter_block_sizes()->end(), step_basis_s2_.size(),
                                            kStepSize);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    // Blocks 0-5 and their Jacobians: the constant part reads only the first six entries.
    if (!constant_->Evaluate(parameters, residuals, jacobians)) return false;
    for (std::size_t k = 0; k < step_basis_s2_.size(); ++k) {
      const double a = step_basis_s2_[k] * g_over_sigma_;
      const double* d_eps = parameters[kConstantBlocks + k];
      residuals[0] -= a * d_eps[1];  // s_N += c g d_eps_E
      residuals[1] += a * d_eps[0];  // s_E -= c g d_eps_N
      if (jacobians != nullptr && jacobians[kConstantBlocks + k] != nullptr) {
        double* j = jacobians[kConstantBlocks + k];  // 2 x 2, row-major
        j[0] = 0.0;
        j[1] = -a;
        j[2] = a;
        j[3] = 0.0;
      }
    }
    return true;
  }

  /// 2 residuals; the six blocks of DistanceHeadingResidual, then one 2-block per step.
  static ceres::CostFunction* Create(double basis_b1_s, double basis_b2_s2, double basis_b3_s3,
                                     const Eigen::Vector2d& gained_ne_m, const Eigen::Vector2d& error_ne_m,
                                     double sigma_m, double gravity_mps2, std::vector<double> step_basis_s2) {
    return new DistanceHeadingTiltWalkResidual(basis_b1_s, basis_b2_s2, basis_b3_s3, gained_ne_m, error_ne_m,
                                               sigma_m, gravity_mps2, std::move(step_basis_s2));
  }

 private:
  std::unique_ptr<ceres::CostFunction> constant_;
  std::vector<double> step_basis_s2_;
  double g_over_sigma_;
};

class VectorPrior2 {
 public:
  static constexpr int kResiduals = 2;
  static constexpr int kVectorSize = 2;  ///< block 0: x

  /// std per axis, each > 0 and finite; x0 finite (else std::invalid_argument).
  VectorPrior2(const Eigen::Vector2d& x0, const Eigen::Vector2d& std) : x0_(x0) {
    for (int i = 0; i < 2; ++i) {
      if (!(std[i] > 0.0) || !std::isfinite(std[i])) {
        throw std::invalid_argument("VectorPrior2: std must be positive and finite, axis " + std::to_string(i));
      }
    }
    if (!x0.allFinite()) throw std::invalid_argument("VectorPrior2: x0 must be finite");
    inv_sigma_ = std.cwiseInverse();
  }

  template <typename T>
  bool operator()(const T* x, T* residual) const {
    for (int i = 0; i < 2; ++i) residual[i] = (x[i] - T(x0_[i])) * T(inv_sigma_[i]);
    return true;
  }

  /// 2 residuals; block x (2).
  static ceres::CostFunction* Create(const Eigen::Vector2d& x0, const Eigen::Vector2d& std) {
    return new ceres::AutoDiffCostFunction<VectorPrior2, kResiduals, kVectorSize>(new VectorPrior2(x0, std));
  }

 private:
  Eigen::Vector2d x0_;
  Eigen::Vector2d inv_sigma_;
};

}  // namespace navtwin::inflight
