#include "core/signal.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace navtwin::signal {
namespace {

// Equation 2 from the per-lag sums of centred products: r(t) = num(t) / num(0).
std::vector<double> Normalise(std::vector<double> num) {
  const double den = num.empty() ? 0.0 : num[0];
  if (!(den > 0.0)) return std::vector<double>(num.size(), 0.0);
  for (double& v : num) v /= den;
  return num;
}

// A number for messages: up to four significant digits, no trailing zeros.
std::string Compact(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.4g", v);
  return buffer;
}

int ClampLag(int max_lag, int n) { return std::max(0, std::min(max_lag, n - 1)); }

// Lag-normalised r(t) k / (k - t): equation 2's (k - t)/k taper would pull every
// interpolated peak towards shorter lags.
double Normalised(const std::vector<double>& r, int t, int k) { return r[t] * k / static_cast<double>(k - t); }

// Vertex of the parabola through the lag-normalised values at t - 1, t, t + 1.
double ParabolicPeak(const std::vector<double>& r, int t, int k) {
  if (t <= 0 || t + 1 >= static_cast<int>(r.size()) || t + 1 >= k) return t;
  const double a = Normalised(r, t - 1, k), b = Normalised(r, t, k), c = Normalised(r, t + 1, k);
  const double den = a - 2.0 * b + c;
  if (!(den < 0.0)) return t;
  return t + std::clamp(0.5 * (a - c) / den, -0.5, 0.5);
}

}  // namespace

std::vector<double> Autocorrelation(const std::vector<double>& x, int max_lag) {
  const int n = static_cast<int>(x.size());
  if (n == 0) return {};
  double mu = 0.0;
  for (double v : x) mu += v;
  mu /= n;
  const int lags = ClampLag(max_lag, n);
  std::vector<double> num(lags + 1, 0.0);
  for (int t = 0; t <= lags; ++t) {
    for (int j = t; j < n; ++j) num[t] += (x[j] - mu) * (x[j - t] - mu);
  }
  return Normalise(std::move(num));
}

std::vector<double> Autocorrelation(const std::vector<Eigen::Vector3d>& x, int max_lag,
                                    const std::array<bool, 3>& use) {
  RunningAutocorrelation running(max_lag, use);
  for (const Eigen::Vector3d& v : x) running.Add(v);
  return running.Evaluate();
}

RunningAutocorrelation::RunningAutocorrelation(int max_lag, const std::array<bool, 3>& use)
    : max_lag_(std::max(0, max_lag)), use_(use), prefix_(1, Eigen::Vector3d::Zero()),
      lagged_sums_(max_lag_ + 1, Eigen::Vector3d::Zero()) {}

void RunningAutocorrelation::Add(const Eigen::Vector3d& x) {
  samples_.push_back(x);
  prefix_.push_back(prefix_.back() + x);
  const int n = size();
  const int lags = std::min(max_lag_, n - 1);
  for (int t = 0; t <= lags; ++t) lagged_sums_[t] += x.cwiseProduct(samples_[n - 1 - t]);
}

// With S_t = sum_{j>t} X_j X_{j-t}, A_t = sum_{j>t} X_j (the last n - t samples) and
// B_t = sum_{j<=n-t} X_j (the first n - t samples), per axis
//   sum_{j>t} (X_j - mu)(X_{j-t} - mu) = S_t - mu (A_t + B_t) + (n - t) mu^2.
std::vector<double> RunningAutocorrelation::Evaluate() const {
  const int n = size();
  if (n == 0) return {};
  const Eigen::Vector3d total = prefix_[n];
  const Eigen::Vector3d mu = total / n;
  const int lags = std::min(max_lag_, n - 1);
  std::vector<double> num(lags + 1, 0.0);
  for (int t = 0; t <= lags; ++t) {
    const Eigen::Vector3d a = total - prefix_[t];
    const Eigen::Vector3d b = prefix_[n - t];
    const Eigen::Vector3d c =
        lagged_sums_[t] - mu.cwiseProduct(a + b) + static_cast<double>(n - t) * mu.cwiseProduct(mu);
    for (int k = 0; k < 3; ++k) {
      if (use_[k]) num[t] += c[k];
    }
  }
  return Normalise(std::move(num));
}

std::vector<int> FindPeaks(const std::vector<double>& r, int n_samples, const PeakOptions& options) {
  const int last = static_cast<int>(r.size()) - 1;
  const int w = std::max(1, options.half_width);
  std::vector<int> candidates;
  for (int t = std::max(1, options.min_lag); t <= last; ++t) {
    if (!(Normalised(r, t, n_samples) >= options.threshold)) continue;
    bool is_max = true;
    for (int d = -w; d <= w && is_max; ++d) {
      const int u = t + d;
      if (d == 0 || u < 0) continue;
      // A neighbour past the last lag is unknown: the peak must not be cut off.
      if (u > last) is_max = false;
      else if (r[u] > r[t]) is_max = false;
    }
    if (is_max) candidates.push_back(t);
  }
  if (candidates.empty()) return candidates;
  // Non-maximum suppression: one peak per half first-lag neighbourhood.
  const double min_separation = 0.5 * candidates.front();
  std::vector<int> peaks;
  for (int t : candidates) {
    if (!peaks.empty() && t - peaks.back() < min_separation) {
      if (r[t] > r[peaks.back()]) peaks.back() = t;
      continue;
    }
    peaks.push_back(t);
  }
  return peaks;
}

PeriodEstimate EstimatePeriod(const std::vector<double>& r, int n_samples, const PeakOptions& options) {
  PeriodEstimate out;
  out.peak_lags = FindPeaks(r, n_samples, options);
  if (out.peak_lags.empty()) {
    out.reason = "no autocorrelation peak reaches " + Compact(options.threshold) +
                 " (lag-normalised) within " + std::to_string(static_cast<int>(r.size()) - 1) + " lags";
    return out;
  }
  const int count = static_cast<int>(out.peak_lags.size());
  out.mean_relative_lag = static_cast<double>(out.peak_lags.back()) / count;
  out.period_samples = static_cast<int>(std::lround(out.mean_relative_lag));
  double num = 0.0, den = 0.0;
  for (int i = 0; i < count; ++i) {
    const double lag = ParabolicPeak(r, out.peak_lags[i], n_samples);
    num += (i + 1) * lag;
    den += static_cast<double>(i + 1) * (i + 1);
  }
  out.refined_period_samples = num / den;
  if (out.period_samples < 1 || 2.0 * out.refined_period_samples > n_samples) {
    out.reason = "the window of " + std::to_string(n_samples) + " samples holds fewer than two periods of " +
                 Compact(out.refined_period_samples) + " samples";
    return out;
  }
  out.found = true;
  return out;
}

WholePeriodAverage AverageWholePeriods(const std::vector<Eigen::Vector3d>& x, int period) {
  if (period < 1) throw std::invalid_argument("AverageWholePeriods: period must be at least one sample");
  WholePeriodAverage out;
  out.blocks = static_cast<int>(x.size()) / period;
  out.samples_used = out.blocks * period;
  if (out.blocks == 0) return out;
  // The mean of equal-length block means is the mean of the samples they cover.
  for (int i = 0; i < out.samples_used; ++i) out.mean += x[i];
  out.mean /= out.samples_used;
  return out;
}

Eigen::Vector3d AverageInterpolated(const std::vector<Eigen::Vector3d>& x, double start, double length) {
  const double end = start + length;
  const int n = static_cast<int>(x.size());
  if (!(length > 0.0) || !(start >= 0.0) || end > n - 1 + 1e-9) {
    throw std::invalid_argument("AverageInterpolated: [start, start + length] must lie inside the samples");
  }
  // Integral of the linear interpolant over [a, b] inside the cell [i, i + 1].
  auto value = [&](double s) {
    const int i = std::min(static_cast<int>(std::floor(s)), n - 2);
    const double u = s - i;
    return Eigen::Vector3d((1.0 - u) * x[i] + u * x[i + 1]);
  };
  Eigen::Vector3d integral = Eigen::Vector3d::Zero();
  double a = start;
  while (a < end) {
    const double b = std::min(end, std::floor(a) + 1.0);
    integral += 0.5 * (b - a) * (value(a) + value(b));
    a = b;
  }
  return integral / length;
}

}  // namespace navtwin::signal
