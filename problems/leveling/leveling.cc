#include "problems/leveling/leveling.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "problems/leveling/batch.h"
#include "problems/leveling/filter.h"
#include "core/leveling_model.h"

namespace navtwin::leveling {
namespace {

double Median3(Eigen::Vector3d v) {
  std::sort(v.data(), v.data() + 3);
  return v[1];
}

// Per-axis sample variance of the first n samples.
Eigen::Vector3d SampleVariance(const std::vector<Eigen::Vector3d>& x, int n) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) mean += x[i];
  mean /= n;
  Eigen::Vector3d var = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) var += (x[i] - mean).cwiseAbs2();
  return var / std::max(1, n - 1);
}

// Roll/pitch and their covariance from a mean specific force with per-axis variance.
LevelEstimate FromMean(const std::string& method, const Eigen::Vector3d& mean_f,
                       const Eigen::Vector3d& mean_variance, int samples_used) {
  LevelEstimate out;
  out.method = method;
  const RollPitch rp = LevelFromSpecificForce(mean_f);
  out.roll_rad = rp.roll_rad;
  out.pitch_rad = rp.pitch_rad;
  const Eigen::Matrix<double, 2, 3> j = LevelJacobian(mean_f);
  const Eigen::Matrix2d cov = j * mean_variance.asDiagonal() * j.transpose();
  out.roll_sigma_rad = std::sqrt(cov(0, 0));
  out.pitch_sigma_rad = std::sqrt(cov(1, 1));
  out.samples_used = samples_used;
  return out;
}

void RequireSamples(const AccelWindow& window, int minimum, const char* what) {
  if (window.size() < minimum) {
    throw std::invalid_argument(std::string(what) + ": the window from " + window.source + " holds " +
                                std::to_string(window.size()) + " samples, at least " +
                                std::to_string(minimum) + " are needed");
  }
}

}  // namespace

signal::PeriodEstimate EstimateWindowPeriod(const AccelWindow& window, const LevelingOptions& options) {
  const int n = window.size();
  const int max_lag = static_cast<int>(std::floor(options.max_lag_fraction * n));
  const std::vector<double> r = signal::Autocorrelation(window.f_b_mps2, max_lag);
  return signal::EstimatePeriod(r, n, options.peaks);
}

// x_j - x(j - P) cancels anything of period P; with a fractional P the delayed sample is
// linearly interpolated, x(j - P) = (1 - u) x_i + u x_{i+1}, whose noise variance is
// ((1 - u)^2 + u^2) sigma^2, so E[d^2] = (1 + (1 - u)^2 + u^2) sigma^2 per axis.
double EstimateAccelNoise(const AccelWindow& window, double period_samples) {
  const std::vector<Eigen::Vector3d>& x = window.f_b_mps2;
  const int n = window.size();
  if (n < 2) throw std::invalid_argument("EstimateAccelNoise: fewer than two samples in " + window.source);
  if (!(period_samples > 0.0) || period_samples + 2.0 > n) {
    return std::sqrt(Median3(SampleVariance(x, n)));
  }
  const int whole = static_cast<int>(std::floor(period_samples));
  const double u = 1.0 - (period_samples - whole);  // x(j - P) between x_{j-whole-1} and x_{j-whole}
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (int j = whole + 1; j < n; ++j) {
    const Eigen::Vector3d delayed = (1.0 - u) * x[j - whole - 1] + u * x[j - whole];
    sum += (x[j] - delayed).cwiseAbs2();
    ++count;
  }
  const double gain = 1.0 + (1.0 - u) * (1.0 - u) + u * u;
  return std::sqrt(Median3(sum / (count * gain)));
}

LevelEstimate PlainMean(const AccelWindow& window, const LevelingOptions& options) {
  RequireSamples(window, 2, "plain mean");
  const int n = window.size();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& f : window.f_b_mps2) mean += f;
  mean /= n;
  // Sigma: the white noise when it is known; otherwise the sample spread, which counts any
  // vibration as noise (the mean over a part-period keeps part of it).
  const Eigen::Vector3d variance = options.accel_noise_mps2 > 0.0
                                       ? Eigen::Vector3d::Constant(options.accel_noise_mps2 * options.accel_noise_mps2)
                                       : SampleVariance(window.f_b_mps2, n);
  return FromMean("plain_mean", mean, variance / n, n);
}

// The seed's method. Its sigma adds to the white noise the vibration the rounded period
// leaves: a sinusoid of amplitude A averaged over m periods of P samples when the true
// period is P - e leaves about A sin(phi) e / P whatever m, so per axis the variance
// A^2 e^2 / (2 P^2), with A^2 = 2 (variance - sigma^2) and e the rounding of the period.
LevelEstimate PeriodAverage(const AccelWindow& window, const LevelingOptions& options) {
  RequireSamples(window, 2, "period average");
  const signal::PeriodEstimate period = EstimateWindowPeriod(window, options);
  if (!period.found) {
    LevelEstimate out = PlainMean(window, options);
    out.method = "period_average";
    out.fallback = period.reason + ": plain mean";
    return out;
  }
  const signal::WholePeriodAverage avg = signal::AverageWholePeriods(window.f_b_mps2, period.period_samples);
  const double sigma = options.accel_noise_mps2 > 0.0 ? options.accel_noise_mps2
                                                      : EstimateAccelNoise(window, period.refined_period_samples);
  const double sigma2 = sigma * sigma;
  const Eigen::Vector3d spread = SampleVariance(window.f_b_mps2, window.size());
  const double e = (period.period_samples - period.refined_period_samples) / period.period_samples;
  Eigen::Vector3d variance = Eigen::Vector3d::Constant(sigma2 / avg.samples_used);
  for (int k = 0; k < 3; ++k) {
    const double amplitude2 = 2.0 * std::max(0.0, spread[k] - sigma2);
    variance[k] += 0.5 * amplitude2 * e * e;
  }
  LevelEstimate out = FromMean("period_average", avg.mean, variance, avg.samples_used);
  out.period_samples = period.period_samples;
  return out;
}

std::vector<LevelEstimate> LevelAllMethods(const AccelWindow& window, const LevelingOptions& options) {
  return {PlainMean(window, options), PeriodAverage(window, options), RunFilter(window, options),
          RunBatch(window, options)};
}

}  // namespace navtwin::leveling
