// Barometric height measurement h_baro (m, on the same datum as the position block's
// ellipsoidal height; any baro offset is removed beforehand):
//
//   r = (h - h_baro) / sigma                                   (1 residual)
//
// Parameter block: pos {lat_rad, lon_rad, h_m} (3, PositionManifold). In the tangent
// (dp_ned_m) its Jacobian is (0, 0, -1/sigma): h = h_est - d_d.
#pragma once

#include <cmath>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>

namespace navtwin {

class BaroHeight {
 public:
  static constexpr int kResiduals = 1;
  static constexpr int kPositionSize = 3;  ///< block 0: {lat_rad, lon_rad, h_m}

  /// sigma_m > 0 and finite, h_baro_m finite (else std::invalid_argument).
  BaroHeight(double h_baro_m, double sigma_m) : h_baro_m_(h_baro_m), inv_sigma_(1.0 / sigma_m) {
    if (!(sigma_m > 0.0) || !std::isfinite(sigma_m)) {
      throw std::invalid_argument("BaroHeight: sigma_m must be positive and finite");
    }
    if (!std::isfinite(h_baro_m)) throw std::invalid_argument("BaroHeight: h_baro_m must be finite");
  }

  template <typename T>
  bool operator()(const T* pos, T* residual) const {
    residual[0] = (pos[2] - T(h_baro_m_)) * T(inv_sigma_);
    return true;
  }

  /// 1 residual; block pos (3).
  static ceres::CostFunction* Create(double h_baro_m, double sigma_m) {
    return new ceres::AutoDiffCostFunction<BaroHeight, kResiduals, kPositionSize>(new BaroHeight(h_baro_m, sigma_m));
  }

 private:
  double h_baro_m_;
  double inv_sigma_;
};

}  // namespace navtwin
