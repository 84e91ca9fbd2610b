#include "problems/ins/measurement_rules.h"

#include <algorithm>
#include <cmath>

namespace navtwin::ins {
namespace {

constexpr double kTimeEps_s = 1e-6;

}  // namespace

Eigen::Vector3d MeasurementSigma(const Eigen::Vector3d& file_sigma, double floor, double fallback) {
  Eigen::Vector3d s;
  for (int i = 0; i < 3; ++i) {
    s[i] = std::isfinite(file_sigma[i]) ? std::max(file_sigma[i], floor) : std::max(fallback, floor);
  }
  return s;
}

void StillnessDetector::Add(const ImuSample& s) {
  Entry e;
  e.begin_s = s.t_s - s.dt_s;
  e.moving = s.dtheta_b_rad.norm() / s.dt_s > config_.gyro_threshold_radps;
  e.f_mps2 = s.dv_b_mps.norm() / s.dt_s - 9.8;
  window_.push_back(e);
  moving_ += e.moving;
  sum_ += e.f_mps2;
  sum_sq_ += e.f_mps2 * e.f_mps2;
  // Drop the oldest samples while the rest still cover the window.
  const double window_begin_s = s.t_s - config_.window_s;
  while (window_.size() > 1 && window_[1].begin_s <= window_begin_s + kTimeEps_s) {
    const Entry& old = window_.front();
    moving_ -= old.moving;
    sum_ -= old.f_mps2;
    sum_sq_ -= old.f_mps2 * old.f_mps2;
    window_.pop_front();
  }
  full_ = window_.front().begin_s <= window_begin_s + kTimeEps_s;
}

bool StillnessDetector::Still() const {
  if (!full_ || moving_ > 0) return false;
  const double n = static_cast<double>(window_.size());
  const double mean = sum_ / n;
  const double var = std::max(0.0, sum_sq_ / n - mean * mean);
  return std::sqrt(var) <= config_.accel_std_threshold_mps2;
}

}  // namespace navtwin::ins
