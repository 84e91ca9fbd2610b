#include "problems/leveling/window.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "core/calibration_file.h"
#include "core/io/input_error.h"
#include "core/io/open.h"
#include "core/rotation.h"

namespace navtwin::leveling {
namespace {

// Times are compared with this slack so that a window edge computed as start + width
// (e.g. 0.2 + 0.2) still takes or leaves the sample exactly on it as intended.
constexpr double kTimeSlack_s = 1e-9;
// A sample at or beyond this fraction of the full-scale range counts as saturated.
constexpr double kSaturationFraction = 0.995;
// Clipping: a run of at least this many identical values at an axis' extreme...
constexpr int kClipRun = 3;
// ...that lies at least this far from the axis median. Clipping is a symptom of large
// vibration (several g); a quiet, coarsely quantised axis can repeat its extreme LSB
// but stays far closer than 1 m/s^2 (0.1 g) to its median.
constexpr double kClipMinExcursion_mps2 = 1.0;

std::string Format(const char* fmt, double a, double b = 0.0, double c = 0.0, double d = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b, c, d);
  return buf;
}

double Median(std::vector<double> v) {
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}

std::vector<double> Axis(const std::vector<Eigen::Vector3d>& x, int axis) {
  std::vector<double> out;
  out.reserve(x.size());
  for (const Eigen::Vector3d& v : x) out.push_back(v[axis]);
  return out;
}

// Marks samples of runs of >= kClipRun identical values equal to the axis minimum or
// maximum, when that extreme lies well away from the median (see kClipMinExcursion_mps2).
void MarkClipping(const std::vector<double>& x, std::vector<bool>* marked) {
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double median = Median(x);
  for (const double extreme : {*lo, *hi}) {
    if (std::abs(extreme - median) < kClipMinExcursion_mps2) continue;
    std::size_t k = 0;
    while (k < x.size()) {
      std::size_t end = k;
      while (end < x.size() && x[end] == extreme) ++end;
      if (end - k >= static_cast<std::size_t>(kClipRun)) {
        for (std::size_t j = k; j < end; ++j) (*marked)[j] = true;
      }
      k = std::max(end, k + 1);
    }
  }
}

// Saturated samples: an axis at or beyond kSaturationFraction of the range, or clipped.
// Marks them in *saturated and adds one line to *message naming how many, the axes and the
// time span.
int CheckSaturation(const AccelWindow& w, const LevelingOptions& options, std::vector<bool>* saturated,
                    std::string* message) {
  const int n = w.size();
  const double limit = kSaturationFraction * options.accel_range_mps2;
  std::vector<bool>& any = *saturated;
  any.assign(n, false);
  std::string axes;
  for (int a = 0; a < 3; ++a) {
    std::vector<bool> marked(n, false);
    const std::vector<double> x = Axis(w.f_b_mps2, a);
    if (options.accel_range_mps2 > 0.0) {
      for (int k = 0; k < n; ++k) marked[k] = std::abs(x[k]) >= limit;
    }
    MarkClipping(x, &marked);
    if (std::find(marked.begin(), marked.end(), true) == marked.end()) continue;
    axes += std::string(axes.empty() ? "" : ", ") + "xyz"[a];
    for (int k = 0; k < n; ++k) any[k] = any[k] || marked[k];
  }
  const int count = static_cast<int>(std::count(any.begin(), any.end(), true));
  if (count == 0) return 0;
  const int first = static_cast<int>(std::find(any.begin(), any.end(), true) - any.begin());
  const int last = n - 1 - static_cast<int>(std::find(any.rbegin(), any.rend(), true) - any.rbegin());
  const double t_first = w.t_s.empty() ? first : w.t_s[first];
  const double t_last = w.t_s.empty() ? last : w.t_s[last];
  *message += std::to_string(count) + " of " + std::to_string(n) + " samples saturated on axis " + axes +
              Format(" between t = %.4f and %.4f s (|f| >= 99.5 %% of the %.1f m/s^2 range, or runs of >= 3 "
                     "equal extreme values: clipping)\n",
                     t_first, t_last, options.accel_range_mps2);
  return count;
}

// Mean specific force with the vibration cancelled as well as the data allow: over the
// whole (fractional) autocorrelation periods that fit, else over all samples.
Eigen::Vector3d PeriodMean(const AccelWindow& w, const LevelingOptions& options) {
  const int n = w.size();
  const signal::PeriodEstimate period = EstimateWindowPeriod(w, options);
  if (period.found && period.refined_period_samples > 0.0) {
    const double p = period.refined_period_samples;
    const double length = std::floor((n - 1) / p) * p;
    if (length > 0.0) return signal::AverageInterpolated(w.f_b_mps2, 0.0, length);
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& f : w.f_b_mps2) mean += f;
  return mean / n;
}

// Motion: a mean angular rate (the norm of the mean omega, in which zero-mean vibration of
// the gyros cancels) above max_rate_radps, or a mean |f| far from gravity.
bool CheckMotion(const AccelWindow& w, const LevelingOptions& options, std::string* message) {
  bool moving = false;
  if (!w.omega_b_radps.empty()) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& o : w.omega_b_radps) mean += o;
    const double rate = (mean / static_cast<double>(w.omega_b_radps.size())).norm();
    if (rate > options.max_rate_radps) {
      moving = true;
      *message += Format("moving: mean angular rate %.4f rad/s (%.2f deg/s) exceeds %.4f rad/s\n", rate,
                         rate * kRadToDeg, options.max_rate_radps);
    }
  }
  const double g = options.gravity_mps2 > 0.0 ? options.gravity_mps2 : kStandardGravity_mps2;
  const double f_norm = PeriodMean(w, options).norm();
  if (std::abs(f_norm - g) > options.max_gravity_mismatch_mps2) {
    moving = true;
    *message += Format("moving: mean |f| = %.3f m/s^2 differs from g = %.3f m/s^2 by %.3f m/s^2 (limit %.3f)\n",
                       f_norm, g, std::abs(f_norm - g), options.max_gravity_mismatch_mps2);
  }
  return moving;
}

// The window without the marked samples (at least two are kept for the motion check: if
// fewer remain, the window is returned whole).
AccelWindow WithoutMarked(const AccelWindow& w, const std::vector<bool>& marked) {
  AccelWindow out;
  out.rate_hz = w.rate_hz;
  out.source = w.source;
  for (int k = 0; k < w.size(); ++k) {
    if (marked[k]) continue;
    if (!w.t_s.empty()) out.t_s.push_back(w.t_s[k]);
    out.f_b_mps2.push_back(w.f_b_mps2[k]);
    if (!w.omega_b_radps.empty()) out.omega_b_radps.push_back(w.omega_b_radps[k]);
  }
  return out.size() >= 2 ? out : w;
}

}  // namespace

AccelWindow ReadAccelWindow(const std::string& path, double start_s, double window_s,
                            const std::string& calibration_path, double temperature_degC) {
  if (!std::isfinite(start_s) || start_s < 0.0) {
    throw std::invalid_argument(Format("start_s must be a finite number >= 0 (s after the first IMU sample), got %g",
                                       start_s));
  }
  if (!std::isfinite(window_s) || window_s <= 0.0) {
    throw std::invalid_argument(Format("window_s must be a finite number > 0, got %g", window_s));
  }
  const std::unique_ptr<ImuReader> reader = OpenImu(path, calibration_path, temperature_degC);
  AccelWindow w;
  w.source = path;
  ImuSample s;
  bool first = true;
  double t0 = 0.0, t_last = 0.0, dt_last = 0.0;
  while (reader->Next(&s)) {
    if (first) t0 = s.t_s;
    first = false;
    t_last = s.t_s;
    dt_last = s.dt_s;
    const double t_rel = s.t_s - t0;
    if (t_rel >= start_s + window_s - kTimeSlack_s) break;
    if (t_rel < start_s - kTimeSlack_s) continue;
    w.t_s.push_back(s.t_s);
    w.f_b_mps2.push_back(s.dv_b_mps / s.dt_s);
    w.omega_b_radps.push_back(s.dtheta_b_rad / s.dt_s);
  }
  if (first) throw InputError(path, 0, "t_s", "no IMU samples");
  // The window may end up to one sample interval after the last sample (the time the
  // next sample would have had); anything longer asks for data that is not there.
  const double length_s = t_last - t0;
  if (start_s + window_s > length_s + dt_last + kTimeSlack_s) {
    throw InputError(path, 0, "t_s",
                     Format("window %.4f..%.4f s (after the first IMU sample) goes beyond the end of the record, "
                            "which is %.4f s long",
                            start_s, start_s + window_s, length_s));
  }
  if (w.size() < kMinWindowSamples) {
    throw InputError(path, 0, "t_s",
                     Format("window %.4f..%.4f s holds ", start_s, start_s + window_s) + std::to_string(w.size()) +
                         " IMU samples, at least " + std::to_string(kMinWindowSamples) +
                         " are needed (make the window longer)");
  }
  std::vector<double> dt;
  for (int k = 1; k < w.size(); ++k) dt.push_back(w.t_s[k] - w.t_s[k - 1]);
  w.rate_hz = 1.0 / Median(dt);
  return w;
}

WindowCheck CheckWindow(const AccelWindow& window, const LevelingOptions& options) {
  if (window.size() < 2) {
    throw std::invalid_argument("CheckWindow: the window from " + window.source + " holds fewer than 2 samples");
  }
  WindowCheck check;
  std::vector<bool> saturated;
  check.saturated_samples = CheckSaturation(window, options, &saturated, &check.message);
  // Motion is judged on the samples that are not saturated: a clipped or saturated sample
  // says nothing about the true specific force.
  const bool all_valid = check.saturated_samples == 0;
  check.moving = CheckMotion(all_valid ? window : WithoutMarked(window, saturated), options, &check.message);
  return check;
}

AccelWindow WithoutSaturatedSamples(const AccelWindow& window, const LevelingOptions& options, int* removed) {
  std::vector<bool> saturated;
  std::string message;
  *removed = CheckSaturation(window, options, &saturated, &message);
  if (*removed == 0) return window;
  AccelWindow timed = window;
  if (timed.t_s.empty() && timed.rate_hz > 0.0) {
    for (int k = 0; k < timed.size(); ++k) timed.t_s.push_back(k / timed.rate_hz);
  }
  AccelWindow out = WithoutMarked(timed, saturated);
  if (out.size() == timed.size()) *removed = 0;  // too few would remain: kept whole
  return out;
}

}  // namespace navtwin::leveling
