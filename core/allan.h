// Allan deviation of a rate series and the noise coefficients read off its curve, after
// IEEE Std 952-1997 (IEEE Standard Specification Format Guide and Test Procedure for
// Single-Axis Interferometric Fiber Optic Gyros), Annex C: for angle random walk N,
// bias instability B and rate random walk K the Allan variance is
//   sigma^2(tau) = N^2 / tau  +  (2 ln 2 / pi) B^2  +  K^2 tau / 3,
// so N is the value at tau = 1 s of the line of slope -1/2, B the flat floor divided by
// sqrt(2 ln 2 / pi) = 0.664, and K the value at tau = 3 s of the line of slope +1/2.
// Units follow the input: rates in rad/s give N in rad/sqrt(s), B in rad/s, K in rad/s/sqrt(s).
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "core/types.h"

namespace navtwin {

/// One point of an Allan deviation curve.
struct AllanPoint {
  double tau_s = 0.0;        ///< cluster time m * tau0
  double adev = 0.0;         ///< Allan deviation, in the units of the input rate
  std::size_t clusters = 0;  ///< independent (non-overlapping) clusters: floor(N / m)
};

struct AllanOptions {
  double points_per_decade = 10.0;  ///< cluster times log-spaced (3 or more = octave or finer)
  std::size_t min_clusters = 2;     ///< longest tau keeps at least this many clusters (>= 2)
};

/// Overlapping Allan deviation of `rate` sampled every tau0_s, at cluster sizes
/// m = 1, ... log-spaced (distinct integers) up to N / min_clusters. With the cumulative
/// sum theta_k = tau0 (y_0 + ... + y_{k-1}),
///   sigma^2(m tau0) = sum_k (theta_{k+2m} - 2 theta_{k+m} + theta_k)^2 / (2 (m tau0)^2 (N - 2m + 1)),
/// O(N) per cluster time. Throws std::invalid_argument for fewer than 2 * min_clusters
/// samples, tau0_s <= 0, points_per_decade < 1, min_clusters < 2, or a non-finite sample.
std::vector<AllanPoint> OverlappingAllanDeviation(const std::vector<double>& rate, double tau0_s,
                                                  const AllanOptions& options = {});

/// Approximate 1-sigma relative error of an Allan deviation from K independent clusters,
/// 1 / sqrt(2 (K - 1)) (IEEE Std 952, Annex C; conservative for the overlapping estimate).
double AllanRelativeError(std::size_t clusters);

/// Noise coefficients read off a curve; NaN where the curve shows no such region.
struct AllanNoiseFit {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  double white_noise = kNaN;       ///< N: rate * sqrt(s) (ARW, VRW)
  double bias_instability = kNaN;  ///< B: rate
  /// True when the curve has no flat part: bias_instability is then the upper bound
  /// min(sigma) / 0.664 (every noise adds to the Allan variance).
  bool bias_instability_is_bound = false;
  double rate_random_walk = kNaN;  ///< K: rate / sqrt(s)
};

/// Reads N, B and K off the curve using only points with at least kMinFitClusters
/// clusters (relative error <= 25 %). The local log-log slope at each point is the
/// least-squares slope over the points within a factor 2 in tau. N: over the first run
/// of consecutive points whose slope is within 0.125 of -1/2, the cluster-weighted
/// geometric mean of sigma * sqrt(tau). K: likewise for slope +1/2 with
/// sigma * sqrt(3 / tau). Each of N and K is read with the other's Allan variance
/// (K^2 tau / 3, N^2 / tau) removed from the points, since variances of independent
/// noises add; this removes the bias of points near the crossing of the two lines. B: the lowest sigma among points whose slope is within 0.125
/// of 0, divided by 0.664 (for a curve with a bucket, its flat bottom; for a lone
/// Gauss–Markov process, the top of its hump).
AllanNoiseFit FitAllanNoise(const std::vector<AllanPoint>& curve);

constexpr std::size_t kMinFitClusters = 9;

/// IMU increments turned into rate series on one sampling interval, for the Allan deviation.
struct ImuRateRecord {
  std::size_t samples = 0;
  /// The mean interval, span / samples: the rates increment / tau0 integrate to the recorded
  /// angle and velocity even where the time tags jitter.
  double tau0_s = 0.0;
  double duration_s = 0.0;  ///< start of the first interval to the last epoch
  std::size_t irregular_intervals = 0;  ///< dt_s further than irregular_fraction * tau0 from tau0
  /// One series per requested axis: rad/s for a gyro axis, m/s^2 for an accelerometer axis.
  std::vector<std::vector<double>> rates;
};

/// The rate series of `axes` (0, 1, 2: gyro x, y, z; 3, 4, 5: accelerometer x, y, z) of a
/// record in time order. Throws std::invalid_argument for an axis outside 0..5 or fewer
/// than 2 * AllanOptions().min_clusters samples (too few for one Allan point).
ImuRateRecord ImuRates(const std::vector<ImuSample>& imu, const std::vector<int>& axes,
                       double irregular_fraction = 0.1);

}  // namespace navtwin
