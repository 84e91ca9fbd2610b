// Signal tools for periodic disturbances (seed 000, docs/leveling.md): the normalised
// autocorrelation of equation 2, local-peak detection, the period of the disturbance in
// samples from the peak lags, and averages over whole periods that cancel a sinusoid.
//
// Equation 2, for samples X_1..X_k with mean mu:
//   r(t) = sum_{j=t+1..k} (X_j - mu)(X_{j-t} - mu) / sum_{j=1..k} (X_j - mu)^2
// For several channels (the three accelerometer axes) the numerators and the denominators
// are summed over the channels first, so a vibrating axis dominates and a quiet one adds
// little; with one channel this is equation 2 exactly.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace navtwin::signal {

/// r(0..max_lag) of equation 2 (r(0) = 1; max_lag is clamped to k - 1). A constant signal
/// (zero denominator) gives all zeros: it has no period.
std::vector<double> Autocorrelation(const std::vector<double>& x, int max_lag);

/// Multi-channel equation 2 over the channels marked in `use` (x, y, z).
std::vector<double> Autocorrelation(const std::vector<Eigen::Vector3d>& x, int max_lag,
                                    const std::array<bool, 3>& use = {{true, true, true}});

/// Equation 2 kept up to date as samples arrive: O(max_lag) per sample, O(max_lag) per
/// evaluation (sums of lagged products, running sums and prefix sums). Used by the online
/// leveling filter, which re-estimates the period as data arrive.
class RunningAutocorrelation {
 public:
  explicit RunningAutocorrelation(int max_lag, const std::array<bool, 3>& use = {{true, true, true}});
  void Add(const Eigen::Vector3d& x);
  int size() const { return static_cast<int>(samples_.size()); }
  int max_lag() const { return max_lag_; }
  /// r(0..min(max_lag, size - 1)), equal to Autocorrelation(samples, max_lag, use).
  std::vector<double> Evaluate() const;

 private:
  int max_lag_;
  std::array<bool, 3> use_;
  std::vector<Eigen::Vector3d> samples_;
  std::vector<Eigen::Vector3d> prefix_;       ///< prefix_[i] = sum of the first i samples
  std::vector<Eigen::Vector3d> lagged_sums_;  ///< lagged_sums_[t] = sum_j X_j X_{j-t} (per axis)
};

/// Local-peak detection on an autocorrelation of a k-sample sequence.
struct PeakOptions {
  /// A peak must reach this value of the lag-normalised autocorrelation r(t) k / (k - t)
  /// (equation 2 shrinks by (k - t)/k at long lags; the normalised value of a clean
  /// sinusoid is 1 at every multiple of its period, signal/(signal + noise) with noise).
  double threshold = 0.5;
  /// A peak is at least every value within +-half_width lags (the seed compares lag 5
  /// with lags 3, 4, 6 and 7).
  int half_width = 2;
  /// Shortest lag considered (lag 1 of a smooth signal is always high).
  int min_lag = 2;
};

/// Lags of the local peaks of r (r[t] for lag t) in increasing order. Peaks closer than
/// half the first peak's lag to a higher one are dropped (noise on a broad peak can make
/// two maxima; the mean relative lag must count one per period).
std::vector<int> FindPeaks(const std::vector<double>& r, int n_samples, const PeakOptions& options);

/// The disturbance period from the peak lags L1 < L2 < ...: the mean of the relative lags
/// L1, L2 - L1, L3 - L2, ... (= L_last / count), rounded to whole samples as the seed does,
/// and a refined fractional period from parabolic interpolation of each peak (on the
/// lag-normalised values, which equation 2's taper would bias short) and a
/// least-squares line through (i, L_i) and the origin.
struct PeriodEstimate {
  bool found = false;
  std::string reason;                ///< why no period was found
  std::vector<int> peak_lags;
  double mean_relative_lag = 0.0;    ///< the seed's mean (e.g. 5.75)
  int period_samples = 0;            ///< rounded (e.g. 6)
  double refined_period_samples = 0.0;
};

/// Estimates the period from r (of a k = n_samples sequence). Not found, with a reason,
/// when there is no peak, or when the window holds fewer than two periods.
PeriodEstimate EstimatePeriod(const std::vector<double>& r, int n_samples, const PeakOptions& options);

/// The seed's averaging: split x into consecutive sub-sequences of exactly `period`
/// samples from the first, average each, and average the averages (the leftover
/// n mod period samples are dropped).
struct WholePeriodAverage {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  int blocks = 0;
  int samples_used = 0;
};
WholePeriodAverage AverageWholePeriods(const std::vector<Eigen::Vector3d>& x, int period);

/// Mean of the piecewise-linear interpolant of x (sample i at index i) over the index
/// interval [start, start + length], start >= 0, start + length <= n - 1: a fractional
/// number of samples, so that a non-integer period can be averaged over exactly.
Eigen::Vector3d AverageInterpolated(const std::vector<Eigen::Vector3d>& x, double start, double length);

}  // namespace navtwin::signal
