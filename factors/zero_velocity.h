// Zero-velocity update (ZUPT) pseudo-measurement, v_meas = 0:
//
//   r = v_n / sigma                                            (3 residuals, NED)
//
// Parameter block: v_n_mps (3, Euclidean).
#pragma once

#include <cmath>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>

namespace navtwin {

class ZeroVelocity {
 public:
  static constexpr int kResiduals = 3;
  static constexpr int kVelocitySize = 3;  ///< block 0: v_n_mps

  /// sigma_mps > 0 and finite (else std::invalid_argument).
  explicit ZeroVelocity(double sigma_mps) : inv_sigma_(1.0 / sigma_mps) {
    if (!(sigma_mps > 0.0) || !std::isfinite(sigma_mps)) {
      throw std::invalid_argument("ZeroVelocity: sigma_mps must be positive and finite");
    }
  }

  template <typename T>
  bool operator()(const T* v_n, T* residual) const {
    for (int i = 0; i < 3; ++i) residual[i] = v_n[i] * T(inv_sigma_);
    return true;
  }

  /// 3 residuals; block v_n (3).
  static ceres::CostFunction* Create(double sigma_mps) {
    return new ceres::AutoDiffCostFunction<ZeroVelocity, kResiduals, kVelocitySize>(new ZeroVelocity(sigma_mps));
  }

 private:
  double inv_sigma_;
};

}  // namespace navtwin
