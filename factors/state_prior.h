// Priors on single state blocks (initial conditions of a batch problem):
//
// PositionPrior: r = PositionMinus(pos, p0) / sigma_ned        (3 residuals, NED metres;
//   radii at p0). Block pos {lat_rad, lon_rad, h_m} (3, PositionManifold).
// VectorPrior3:  r = (x - x0) / sigma                          (3 residuals)
//   Block x (3, Euclidean): velocity, a bias, scale factors.
// IsotropicPrior<N>: r = (x - x0) / sigma, one sigma          (N residuals)
//   Block x (N, Euclidean): e.g. the six axis misalignments of a triad.
// ScalarPrior:   r = (x - x0) / sigma                          (1 residual)
//   Block x (1): an installation or sensor parameter (e.g. an odometer scale factor).
// sigma per axis (Vector3d) or one for all axes (double); each > 0 and finite.
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Core>

#include "factors/position_manifold.h"

namespace navtwin {

namespace state_prior_detail {
inline Eigen::Vector3d InverseSigma(const Eigen::Vector3d& sigma, const char* what) {
  for (int i = 0; i < 3; ++i) {
    if (!(sigma[i] > 0.0) || !std::isfinite(sigma[i])) {
      throw std::invalid_argument(std::string(what) + ": std must be positive and finite");
    }
  }
  return sigma.cwiseInverse();
}
}  // namespace state_prior_detail

class PositionPrior {
 public:
  static constexpr int kResiduals = 3;
  static constexpr int kPositionSize = 3;  ///< block 0: {lat_rad, lon_rad, h_m}

  PositionPrior(const Eigen::Vector3d& p0, const Eigen::Vector3d& std_ned_m)
      : p0_(p0), inv_sigma_(state_prior_detail::InverseSigma(std_ned_m, "PositionPrior")) {
    if (!p0.allFinite()) throw std::invalid_argument("PositionPrior: p0 must be finite");
  }
  PositionPrior(const Eigen::Vector3d& p0, double std_m) : PositionPrior(p0, Eigen::Vector3d::Constant(std_m)) {}

  template <typename T>
  bool operator()(const T* pos, T* residual) const {
    const T p0[3] = {T(p0_[0]), T(p0_[1]), T(p0_[2])};
    PositionMinus(pos, p0, residual);
    for (int i = 0; i < 3; ++i) residual[i] *= T(inv_sigma_[i]);
    return true;
  }

  /// 3 residuals; block pos (3).
  static ceres::CostFunction* Create(const Eigen::Vector3d& p0, const Eigen::Vector3d& std_ned_m) {
    return new ceres::AutoDiffCostFunction<PositionPrior, kResiduals, kPositionSize>(new PositionPrior(p0, std_ned_m));
  }
  static ceres::CostFunction* Create(const Eigen::Vector3d& p0, double std_m) {
    return Create(p0, Eigen::Vector3d::Constant(std_m));
  }

 private:
  Eigen::Vector3d p0_;
  Eigen::Vector3d inv_sigma_;
};

class VectorPrior3 {
 public:
  static constexpr int kResiduals = 3;
  static constexpr int kVectorSize = 3;  ///< block 0: x

  VectorPrior3(const Eigen::Vector3d& x0, const Eigen::Vector3d& std)
      : x0_(x0), inv_sigma_(state_prior_detail::InverseSigma(std, "VectorPrior3")) {
    if (!x0.allFinite()) throw std::invalid_argument("VectorPrior3: x0 must be finite");
  }
  VectorPrior3(const Eigen::Vector3d& x0, double std) : VectorPrior3(x0, Eigen::Vector3d::Constant(std)) {}

  template <typename T>
  bool operator()(const T* x, T* residual) const {
    for (int i = 0; i < 3; ++i) residual[i] = (x[i] - T(x0_[i])) * T(inv_sigma_[i]);
    return true;
  }

  /// 3 residuals; block x (3).
  static ceres::CostFunction* Create(const Eigen::Vector3d& x0, const Eigen::Vector3d& std) {
    return new ceres::AutoDiffCostFunction<VectorPrior3, kResiduals, kVectorSize>(new VectorPrior3(x0, std));
  }
  static ceres::CostFunction* Create(const Eigen::Vector3d& x0, double std) {
    return Create(x0, Eigen::Vector3d::Constant(std));
  }

 private:
  Eigen::Vector3d x0_;
  Eigen::Vector3d inv_sigma_;
};

template <int N>
class IsotropicPrior {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;
  IsotropicPrior(const Vector& x0, double std) : x0_(x0), inv_sigma_(1.0 / std) {
    if (!(std > 0.0) || !std::isfinite(std)) throw std::invalid_argument("IsotropicPrior: std must be positive and finite");
    if (!x0.allFinite()) throw std::invalid_argument("IsotropicPrior: x0 must be finite");
  }

  template <typename T>
  bool operator()(const T* x, T* residual) const {
    for (int i = 0; i < N; ++i) residual[i] = (x[i] - T(x0_[i])) * T(inv_sigma_);
    return true;
  }

  /// N residuals; block x (N).
  static ceres::CostFunction* Create(const Vector& x0, double std) {
    return new ceres::AutoDiffCostFunction<IsotropicPrior, N, N>(new IsotropicPrior(x0, std));
  }

 private:
  Vector x0_;
  double inv_sigma_;
};

class ScalarPrior {
 public:
  static constexpr int kResiduals = 1;
  static constexpr int kValueSize = 1;  ///< block 0: x

  ScalarPrior(double x0, double std) : x0_(x0), inv_sigma_(1.0 / std) {
    if (!(std > 0.0) || !std::isfinite(std)) throw std::invalid_argument("ScalarPrior: std must be positive and finite");
    if (!std::isfinite(x0)) throw std::invalid_argument("ScalarPrior: x0 must be finite");
  }

  template <typename T>
  bool operator()(const T* x, T* residual) const {
    residual[0] = (x[0] - T(x0_)) * T(inv_sigma_);
    return true;
  }

  /// 1 residual; block x (1).
  static ceres::CostFunction* Create(double x0, double std) {
    return new ceres::AutoDiffCostFunction<ScalarPrior, kResiduals, kValueSize>(new ScalarPrior(x0, std));
  }

 private:
  double x0_;
  double inv_sigma_;
};

}  // namespace navtwin
