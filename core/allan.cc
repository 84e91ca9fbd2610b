#include "core/allan.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace navtwin {
namespace {

// sqrt(2 ln 2 / pi): the Allan deviation floor of flicker rate noise per unit of B.
const double kFlickerFloor = std::sqrt(2.0 * std::log(2.0) / M_PI);
constexpr double kSlopeTolerance = 0.125;  // half-way between the pure slopes -1/2, 0, +1/2

/// Distinct cluster sizes m = round(10^(i / points_per_decade)), 1 <= m <= m_max.
std::vector<std::size_t> ClusterSizes(std::size_t m_max, double points_per_decade) {
  std::vector<std::size_t> sizes;
  for (int i = 0;; ++i) {
    const double m = std::round(std::pow(10.0, i / points_per_decade));
    if (m > static_cast<double>(m_max)) break;
    const auto mi = static_cast<std::size_t>(m);
    if (sizes.empty() || mi != sizes.back()) sizes.push_back(mi);
  }
  return sizes;
}

/// Least-squares slope of log sigma against log tau over the fit points within a factor 2
/// of point i's tau (i itself is a fit point).
double LocalSlope(const std::vector<AllanPoint>& c, std::size_t n_fit, std::size_t i) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t j = 0; j < n_fit; ++j) {
    if (c[j].tau_s < 0.5 * c[i].tau_s || c[j].tau_s > 2.0 * c[i].tau_s) continue;
    const double x = std::log(c[j].tau_s), y = std::log(c[j].adev);
    sx += x, sy += y, sxx += x * x, sxy += x * y;
    ++n;
  }
  const double det = n * sxx - sx * sx;
  return n >= 2 && det > 0.0 ? (n * sxy - sx * sy) / det : std::numeric_limits<double>::quiet_NaN();
}

/// Over the first run of consecutive points with |slope - target| <= tolerance, the
/// cluster-weighted geometric mean of adev * (tau / tau_ref)^(-target), i.e. the value at
/// tau_ref of the line of slope `target` through the run. `other(tau)` is an Allan
/// variance to remove first (another noise's line; variances of independent noises add).
/// NaN when there is no such run.
template <typename Other>
double LineValueAt(const std::vector<AllanPoint>& c, const std::vector<double>& slopes, double target,
                   double tau_ref_s, Other other) {
  double sum_w = 0.0, sum_wy = 0.0;
  for (std::size_t i = 0; i < slopes.size(); ++i) {
    const bool in = std::abs(slopes[i] - target) <= kSlopeTolerance;
    if (!in && sum_w > 0.0) break;  // end of the first run
    const double avar = c[i].adev * c[i].adev - other(c[i].tau_s);
    if (!in || !(avar > 0.0)) continue;
    const double w = static_cast<double>(c[i].clusters);
    sum_w += w;
    sum_wy += w * (0.5 * std::log(avar) - target * std::log(c[i].tau_s / tau_ref_s));
  }
  return sum_w > 0.0 ? std::exp(sum_wy / sum_w) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

std::vector<AllanPoint> OverlappingAllanDeviation(const std::vector<double>& rate, double tau0_s,
                                                  const AllanOptions& options) {
  const std::size_t n = rate.size();
  if (options.min_clusters < 2) throw std::invalid_argument("Allan deviation: min_clusters must be >= 2");
  if (n < 2 * options.min_clusters) throw std::invalid_argument("Allan deviation: too few samples");
  if (!(tau0_s > 0.0) || !std::isfinite(tau0_s)) throw std::invalid_argument("Allan deviation: tau0 must be > 0");
  if (!(options.points_per_decade >= 1.0)) throw std::invalid_argument("Allan deviation: points_per_decade < 1");
  // Cumulative sums of the mean-removed rate (in rate * samples): the Allan variance
  // ignores a constant, and removing it keeps the sums small and precise.
  double mean = 0.0;
  for (const double y : rate) {
    if (!std::isfinite(y)) throw std::invalid_argument("Allan deviation: non-finite sample");
    mean += y;
  }
  mean /= static_cast<double>(n);
  std::vector<double> sum(n + 1, 0.0);
  for (std::size_t k = 0; k < n; ++k) sum[k + 1] = sum[k] + (rate[k] - mean);

  std::vector<AllanPoint> curve;
  for (const std::size_t m : ClusterSizes(n / options.min_clusters, options.points_per_decade)) {
    const std::size_t terms = n - 2 * m + 1;
    double acc = 0.0;
    for (std::size_t k = 0; k < terms; ++k) {
      const double d = sum[k + 2 * m] - 2.0 * sum[k + m] + sum[k];
      acc += d * d;
    }
    // theta differences are tau0 * d, so sigma^2 = tau0^2 acc / (2 (m tau0)^2 terms).
    const double md = static_cast<double>(m);
    curve.push_back({md * tau0_s, std::sqrt(acc / (2.0 * md * md * static_cast<double>(terms))), n / m});
  }
  return curve;
}

double AllanRelativeError(std::size_t clusters) {
  return clusters > 1 ? 1.0 / std::sqrt(2.0 * (static_cast<double>(clusters) - 1.0))
                      : std::numeric_limits<double>::infinity();
}

AllanNoiseFit FitAllanNoise(const std::vector<AllanPoint>& curve) {
  // Fit points: the leading points with enough clusters (clusters fall as tau grows).
  std::size_t n_fit = 0;
  while (n_fit < curve.size() && curve[n_fit].clusters >= kMinFitClusters && curve[n_fit].adev > 0.0) ++n_fit;
  std::vector<double> slopes(n_fit);
  for (std::size_t i = 0; i < n_fit; ++i) slopes[i] = LocalSlope(curve, n_fit, i);

  AllanNoiseFit fit;
  // Rate random walk read off its line, then white noise off its own with the random
  // walk's Allan variance K^2 tau / 3 removed, then the random walk again with N^2 / tau
  // removed: this takes out the bias of the points near the crossing of the two lines.
  const double k_raw = LineValueAt(curve, slopes, +0.5, 3.0, [](double) { return 0.0; });
  fit.white_noise = LineValueAt(curve, slopes, -0.5, 1.0, [k_raw](double tau) {
    return std::isnan(k_raw) ? 0.0 : k_raw * k_raw * tau / 3.0;
  });
  const double n = fit.white_noise;
  fit.rate_random_walk = LineValueAt(curve, slopes, +0.5, 3.0, [n](double tau) {
    return std::isnan(n) ? 0.0 : n * n / tau;
  });
  double flat_min = std::numeric_limits<double>::infinity(), any_min = flat_min;
  for (std::size_t i = 0; i < n_fit; ++i) {
    any_min = std::min(any_min, curve[i].adev);
    if (std::abs(slopes[i]) <= kSlopeTolerance) flat_min = std::min(flat_min, curve[i].adev);
  }
  if (std::isfinite(flat_min)) {
    fit.bias_instability = flat_min / kFlickerFloor;
  } else if (std::isfinite(any_min)) {
    fit.bias_instability = any_min / kFlickerFloor;
    fit.bias_instability_is_bound = true;
  }
  return fit;
}

ImuRateRecord ImuRates(const std::vector<ImuSample>& imu, const std::vector<int>& axes,
                       double irregular_fraction) {
  for (const int axis : axes) {
    if (axis < 0 || axis > 5) throw std::invalid_argument("ImuRates: axis " + std::to_string(axis) + " is not 0..5");
  }
  const std::size_t need = 2 * AllanOptions().min_clusters;
  if (imu.size() < need) {
    throw std::invalid_argument("too few IMU samples for an Allan deviation (" + std::to_string(imu.size()) +
                                ", need at least " + std::to_string(need) + ")");
  }
  ImuRateRecord r;
  r.samples = imu.size();
  r.duration_s = imu.back().t_s - (imu.front().t_s - imu.front().dt_s);
  r.tau0_s = r.duration_s / static_cast<double>(r.samples);
  for (const ImuSample& s : imu) {
    r.irregular_intervals += std::abs(s.dt_s - r.tau0_s) > irregular_fraction * r.tau0_s;
  }
  for (const int axis : axes) {
    std::vector<double> rate;
    rate.reserve(imu.size());
    for (const ImuSample& s : imu) rate.push_back((axis < 3 ? s.dtheta_b_rad : s.dv_b_mps)[axis % 3] / r.tau0_s);
    r.rates.push_back(std::move(rate));
  }
  return r;
}

}  // namespace navtwin
