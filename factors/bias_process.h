// Process residuals linking a 3-vector bias (gyro rad/s, accel m/s^2, or a scale factor)
// at two epochs i and j = i + dt.
//
// BiasGaussMarkov: first-order Gauss-Markov process db/dt = -b/tau + w with steady-state
// standard deviation s (white-noise PSD q = 2 s^2 / tau). Its exact discretisation
//   b_j = phi b_i + w_d,  phi = exp(-dt/tau),  Var(w_d) = s^2 (1 - phi^2)
// gives
//   r = (b_j - phi b_i) / (s sqrt(1 - exp(-2 dt/tau)))          (3 residuals)
// 1 - exp(-2 dt/tau) is computed as -expm1(-2 dt/tau) (accurate for dt << tau).
// tau = +inf is rejected: use BiasRandomWalk, the tau -> inf limit with q fixed.
//
// BiasRandomWalk: db/dt = w, white noise of PSD q (units^2 / s, e.g. (rad/s)^2/s):
//   r = (b_j - b_i) / sqrt(q dt)                                (3 residuals)
//
// Parameter blocks (both): b_i (3), b_j (3), Euclidean.
#pragma once

#include <cmath>
#include <stdexcept>

#include <ceres/autodiff_cost_function.h>

namespace navtwin {

class BiasGaussMarkov {
 public:
  static constexpr int kResiduals = 3;
  static constexpr int kBiasSize = 3;  ///< blocks 0 and 1: b_i, b_j

  /// dt_s > 0, tau_s > 0, steady_std > 0, all finite (else std::invalid_argument).
  BiasGaussMarkov(double dt_s, double tau_s, double steady_std) {
    if (!(dt_s > 0.0) || !std::isfinite(dt_s)) {
      throw std::invalid_argument("BiasGaussMarkov: dt_s must be positive and finite");
    }
    if (!(tau_s > 0.0) || !std::isfinite(tau_s)) {
      throw std::invalid_argument(
          "BiasGaussMarkov: tau_s must be positive and finite (tau = inf: use BiasRandomWalk)");
    }
    if (!(steady_std > 0.0) || !std::isfinite(steady_std)) {
      throw std::invalid_argument("BiasGaussMarkov: steady_std must be positive and finite");
    }
    phi_ = std::exp(-dt_s / tau_s);
    const double sigma = steady_std * std::sqrt(-std::expm1(-2.0 * dt_s / tau_s));
    if (!(sigma > 0.0)) {  // dt/tau so small that the variance underflows
      throw std::invalid_argument("BiasGaussMarkov: dt_s / tau_s too small (zero process noise)");
    }
    inv_sigma_ = 1.0 / sigma;
  }

  /// phi = exp(-dt/tau) and the whitening 1 / sigma_d, for a filter's own use.
  double phi() const { return phi_; }
  double inv_sigma() const { return inv_sigma_; }

  template <typename T>
  bool operator()(const T* b_i, const T* b_j, T* residual) const {
    for (int k = 0; k < 3; ++k) residual[k] = (b_j[k] - T(phi_) * b_i[k]) * T(inv_sigma_);
    return true;
  }

  /// 3 residuals; blocks b_i (3), b_j (3).
  static ceres::CostFunction* Create(double dt_s, double tau_s, double steady_std) {
    return new ceres::AutoDiffCostFunction<BiasGaussMarkov, kResiduals, kBiasSize, kBiasSize>(
        new BiasGaussMarkov(dt_s, tau_s, steady_std));
  }

 private:
  double phi_ = 1.0;
  double inv_sigma_ = 1.0;
};

class BiasRandomWalk {
 public:
  static constexpr int kResiduals = 3;
  static constexpr int kBiasSize = 3;  ///< blocks 0 and 1: b_i, b_j

  /// dt_s > 0 and psd > 0 (units^2/s), finite (else std::invalid_argument).
  BiasRandomWalk(double dt_s, double psd) {
    if (!(dt_s > 0.0) || !std::isfinite(dt_s)) {
      throw std::invalid_argument("BiasRandomWalk: dt_s must be positive and finite");
    }
    if (!(psd > 0.0) || !std::isfinite(psd)) {
      throw std::invalid_argument("BiasRandomWalk: psd must be positive and finite");
    }
    inv_sigma_ = 1.0 / std::sqrt(psd * dt_s);
  }

  double inv_sigma() const { return inv_sigma_; }

  template <typename T>
  bool operator()(const T* b_i, const T* b_j, T* residual) const {
    for (int k = 0; k < 3; ++k) residual[k] = (b_j[k] - b_i[k]) * T(inv_sigma_);
    return true;
  }

  /// 3 residuals; blocks b_i (3), b_j (3).
  static ceres::CostFunction* Create(double dt_s, double psd) {
    return new ceres::AutoDiffCostFunction<BiasRandomWalk, kResiduals, kBiasSize, kBiasSize>(
        new BiasRandomWalk(dt_s, psd));
  }

 private:
  double inv_sigma_ = 1.0;
};

}  // namespace navtwin
