#include "problems/ins/nav_error.h"

#include <algorithm>
#include <cmath>

#include "core/earth.h"
#include "core/rotation.h"

namespace navtwin {

NavError CompareNav(const NavState& estimate, const NavState& truth) {
  NavError e;
  e.t_s = estimate.t_s;
  e.pos_ned_m = wgs84::GeodeticToNed({estimate.lat_rad, estimate.lon_rad, estimate.h_m},
                                     {truth.lat_rad, truth.lon_rad, truth.h_m});
  e.vel_ned_mps = estimate.v_n_mps - truth.v_n_mps;
  const Eigen::Vector3d rpy_est = EulerFromQuat(estimate.q_n_b);
  const Eigen::Vector3d rpy_true = EulerFromQuat(truth.q_n_b);
  for (int i = 0; i < 3; ++i) e.rpy_rad[i] = WrapPi(rpy_est[i] - rpy_true[i]);
  return e;
}

void NavErrorStats::Add(const NavError& e) {
  const double v[9] = {e.pos_ned_m.x(),   e.pos_ned_m.y(),   e.pos_ned_m.z(),
                       e.vel_ned_mps.x(), e.vel_ned_mps.y(), e.vel_ned_mps.z(),
                       e.rpy_rad.x(),     e.rpy_rad.y(),     e.rpy_rad.z()};
  for (int i = 0; i < 9; ++i) {
    sum_sq_[i] += v[i] * v[i];
    max_abs_[i] = std::max(max_abs_[i], std::abs(v[i]));
  }
  const double horizontal = e.pos_ned_m.head<2>().norm();
  sum_sq_horizontal_ += horizontal * horizontal;
  max_horizontal_ = std::max(max_horizontal_, horizontal);
  last_ = e;
  ++count_;
}

double NavErrorStats::Rms(int c) const { return count_ ? std::sqrt(sum_sq_[c] / count_) : 0.0; }
double NavErrorStats::Max(int c) const { return max_abs_[c]; }

double NavErrorStats::Final(int c) const {
  if (c < 3) return last_.pos_ned_m[c];
  if (c < 6) return last_.vel_ned_mps[c - 3];
  return last_.rpy_rad[c - 6];
}

double NavErrorStats::HorizontalRms_m() const {
  return count_ ? std::sqrt(sum_sq_horizontal_ / count_) : 0.0;
}
double NavErrorStats::HorizontalMax_m() const { return max_horizontal_; }

NavState InterpolateNav(const NavState& a, const NavState& b, double t_s) {
  const double span = b.t_s - a.t_s;
  const double w = span > 0.0 ? (t_s - a.t_s) / span : 0.0;
  NavState s = a;
  s.t_s = t_s;
  s.lat_rad = a.lat_rad + w * (b.lat_rad - a.lat_rad);
  s.lon_rad = a.lon_rad + w * WrapPi(b.lon_rad - a.lon_rad);
  s.h_m = a.h_m + w * (b.h_m - a.h_m);
  s.v_n_mps = a.v_n_mps + w * (b.v_n_mps - a.v_n_mps);
  s.q_n_b = a.q_n_b.slerp(w, b.q_n_b);
  return s;
}

std::optional<NavState> NavAt(const std::vector<NavState>& nav, double t_s, double tolerance_s) {
  if (nav.empty() || !(t_s >= nav.front().t_s - tolerance_s) || !(t_s <= nav.back().t_s + tolerance_s)) {
    return std::nullopt;
  }
  const auto hi = std::lower_bound(nav.begin(), nav.end(), t_s, [](const NavState& s, double t) { return s.t_s < t; });
  if (hi == nav.end()) return nav.back();
  if (hi == nav.begin() || hi->t_s == t_s) return *hi;
  return InterpolateNav(*(hi - 1), *hi, t_s);
}

}  // namespace navtwin
