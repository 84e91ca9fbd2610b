#include "problems/ins/measurement_rules.h"

#include <algorithm>
#include <cmath>

#include "core/units.h"

namespace navtwin::ins {
namespace {

constexpr double kTimeEps_s = 1e-6;

/// x shrunk towards zero for white noise of variance var_per_axis on each axis (MotionWindow).
Eigen::Vector3d ShrinkMotion(const Eigen::Vector3d& x, double var_per_axis) {
  const double n2 = x.squaredNorm();
  if (!(var_per_axis > 0.0)) return x;
  const double keep = 1.0 - kMotionShrinkage * 3.0 * var_per_axis / n2;
  return keep > 0.0 ? Eigen::Vector3d(keep * x) : Eigen::Vector3d::Zero();
}

/// A quantity from the means of the two halves (m0 older, m1 newer; white-noise variances of
/// the means var0, var1 per axis) at the window's end (`end`, with `end_var` more error
/// variance) and its rate of change, both shrunk; `span` = c1 - c0, `ahead` = end - c1.
void MotionFromHalves(const Eigen::Vector3d& m0, const Eigen::Vector3d& m1, double var0, double var1, double span,
                      double ahead, double end_var, Eigen::Vector3d* end, Eigen::Vector3d* rate) {
  const Eigen::Vector3d r = (m1 - m0) / span;
  const double e = ahead / span;
  *end = ShrinkMotion(m1 + ahead * r, (1.0 + e) * (1.0 + e) * var1 + e * e * var0 + end_var);
  *rate = ShrinkMotion(r, (var0 + var1) / (span * span));
}

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

void MotionWindow::Add(const ImuSample& corrected, const Eigen::Vector3d& dv_n_mps) {
  const double dt = corrected.dt_s;
  steps_.push_back({corrected.t_s - 0.5 * dt, dt, corrected.dtheta_b_rad, dv_n_mps});
  end_s_ = corrected.t_s;
  // Drop the oldest steps while the rest still cover the window.
  const double window_begin_s = end_s_ - kMotionWindow_s;
  while (steps_.size() > 1 && steps_[1].mid_s - 0.5 * steps_[1].dt_s <= window_begin_s + kTimeEps_s) {
    steps_.pop_front();
  }
}

ImuMotion MotionWindow::Get(double tilt_var_rad2) const {
  // Per half (0: older, 1: newer): duration, duration-weighted centre, increments.
  double dt[2] = {0.0, 0.0}, centre[2] = {0.0, 0.0};
  Eigen::Vector3d dtheta[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  Eigen::Vector3d dv[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  const double split_s = end_s_ - 0.5 * kMotionWindow_s;
  for (const Step& s : steps_) {
    const int h = s.mid_s >= split_s ? 1 : 0;
    dt[h] += s.dt_s;
    centre[h] += s.mid_s * s.dt_s;
    dtheta[h] += s.dtheta_b_rad;
    dv[h] += s.dv_n_mps;
  }
  ImuMotion m;
  if (!(dt[1] > 0.0)) return m;
  // The variance of a half's mean: white noise density^2 / duration.
  const double gyro_var[2] = {arw_ * arw_ / dt[0], arw_ * arw_ / dt[1]};
  const double accel_var[2] = {vrw_ * vrw_ / dt[0], vrw_ * vrw_ / dt[1]};
  const double tilt_accel_var = kStandardGravity_mps2 * kStandardGravity_mps2 * std::max(0.0, tilt_var_rad2);
  const double c0 = dt[0] > 0.0 ? centre[0] / dt[0] : 0.0, c1 = centre[1] / dt[1];
  if (!(dt[0] > 0.0) || !(c1 > c0)) {
    m.omega_ib_b_radps = ShrinkMotion(dtheta[1] / dt[1], gyro_var[1]);
    m.a_n_mps2 = ShrinkMotion(dv[1] / dt[1], accel_var[1] + tilt_accel_var);
    return m;
  }
  MotionFromHalves(dtheta[0] / dt[0], dtheta[1] / dt[1], gyro_var[0], gyro_var[1], c1 - c0, end_s_ - c1, 0.0,
                   &m.omega_ib_b_radps, &m.alpha_ib_b_radps2);
  MotionFromHalves(dv[0] / dt[0], dv[1] / dt[1], accel_var[0], accel_var[1], c1 - c0, end_s_ - c1, tilt_accel_var,
                   &m.a_n_mps2, &m.j_n_mps3);
  return m;
}

}  // namespace navtwin::ins
