#include "problems/calibration/mag_heading.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/leveling_model.h"
#include "core/rotation.h"
#include "problems/ins/nav_error.h"

namespace navtwin::calibration {

std::optional<Eigen::Vector3d> EulerAt(const std::vector<NavState>& nav, double t_s) {
  const std::optional<NavState> s = NavAt(nav, t_s);
  if (!s) return std::nullopt;
  return EulerFromQuat(s->q_n_b);
}

AccelerometerLevel::AccelerometerLevel(std::vector<ImuSample> imu, double half_window_s)
    : imu_(std::move(imu)), half_window_s_(half_window_s) {
  sum_dv_mps_.push_back(Eigen::Vector3d::Zero());
  sum_dt_s_.push_back(0.0);
  for (const ImuSample& s : imu_) {
    sum_dv_mps_.push_back(sum_dv_mps_.back() + s.dv_b_mps);
    sum_dt_s_.push_back(sum_dt_s_.back() + s.dt_s);
  }
}

std::optional<Eigen::Vector2d> AccelerometerLevel::At(double t_s) const {
  if (imu_.empty() || t_s < imu_.front().t_s - imu_.front().dt_s - half_window_s_ ||
      t_s > imu_.back().t_s + half_window_s_) {
    return std::nullopt;
  }
  const auto by_time = [](const ImuSample& s, double t) { return s.t_s < t; };
  std::size_t lo = std::lower_bound(imu_.begin(), imu_.end(), t_s - half_window_s_, by_time) - imu_.begin();
  std::size_t hi = std::lower_bound(imu_.begin(), imu_.end(), t_s + half_window_s_, by_time) - imu_.begin();
  if (hi <= lo) {  // no sample inside the window: the one nearest to t
    lo = std::min(lo, imu_.size() - 1);
    hi = lo + 1;
  }
  const Eigen::Vector3d f_b_mps2 = (sum_dv_mps_[hi] - sum_dv_mps_[lo]) / (sum_dt_s_[hi] - sum_dt_s_[lo]);
  const leveling::RollPitch level = leveling::LevelFromSpecificForce(f_b_mps2);
  return Eigen::Vector2d(level.roll_rad, level.pitch_rad);
}

double MedianInterval_s(const std::vector<MagSample>& mag) {
  std::vector<double> dt;
  for (std::size_t i = 1; i < mag.size(); ++i) dt.push_back(mag[i].t_s - mag[i - 1].t_s);
  if (dt.empty()) return 0.0;
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  return dt[dt.size() / 2];
}

HeadingErrors MagHeadingErrors(const std::vector<MagSample>& mag,
                               const std::vector<std::optional<Eigen::Vector3d>>& reference_euler_rad,
                               const MagCalibration& c, bool two_axis, double declination_rad) {
  HeadingErrors e;
  double sum_before = 0.0, sum_after = 0.0;
  const auto heading = [&](const Eigen::Vector3d& m, const Eigen::Vector3d& euler) {
    return two_axis ? LevelHeading(m, declination_rad) : TiltCompensatedHeading(m, euler[0], euler[1], declination_rad);
  };
  for (std::size_t i = 0; i < mag.size(); ++i) {
    const std::optional<Eigen::Vector3d>& euler = reference_euler_rad[i];
    if (!euler || std::abs((*euler)[1]) > kMaxHeadingPitch_rad) continue;
    const double before = WrapPi(heading(mag[i].m_b_uT, *euler) - (*euler)[2]);
    Eigen::Vector3d m_c = ApplyMagCalibration(c, mag[i].m_b_uT);
    if (c.method == "planar") m_c -= c.uncalibrated_axis * c.uncalibrated_axis.dot(m_c);
    const double after = WrapPi(heading(m_c, *euler) - (*euler)[2]);
    sum_before += before * before;
    sum_after += after * after;
    ++e.samples;
  }
  if (e.samples > 0) {
    e.before_deg = std::sqrt(sum_before / e.samples) * kRadToDeg;
    e.after_deg = std::sqrt(sum_after / e.samples) * kRadToDeg;
  }
  return e;
}

MagSampleAttitudes AttitudesFromNav(const std::vector<MagSample>& mag, const std::vector<NavState>& nav) {
  MagSampleAttitudes a;
  a.source = "truth";
  a.euler_rad.resize(mag.size());
  a.roll_pitch_rad.resize(mag.size());
  for (std::size_t i = 0; i < mag.size(); ++i) {
    a.euler_rad[i] = EulerAt(nav, mag[i].t_s);
    if (a.euler_rad[i]) a.roll_pitch_rad[i] = a.euler_rad[i]->head<2>();
  }
  return a;
}

MagSampleAttitudes AttitudesFromAccelerometer(const std::vector<MagSample>& mag, std::vector<ImuSample> imu) {
  MagSampleAttitudes a;
  a.source = "imu accelerometer";
  a.euler_rad.resize(mag.size());
  const AccelerometerLevel level(std::move(imu), 0.5 * MedianInterval_s(mag));
  for (const MagSample& m : mag) a.roll_pitch_rad.push_back(level.At(m.t_s));
  return a;
}

MagSampleAttitudes LevelAttitudes(const std::vector<MagSample>& mag) {
  MagSampleAttitudes a;
  a.source = "level (assumed)";
  a.euler_rad.resize(mag.size());
  a.roll_pitch_rad.assign(mag.size(), Eigen::Vector2d::Zero());
  return a;
}

}  // namespace navtwin::calibration
