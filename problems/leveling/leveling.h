// Leveling (roll and pitch from accelerometers at rest) under rotor vibration, seed 000:
// four methods on one window of specific-force samples, all sharing the measurement
// model of core/leveling_model.h (equation 1).
//   plain_mean      the mean of all samples (what the seed compares against);
//   period_average  the seed's method: autocorrelation period, whole-period averages;
//   filter          an online estimator fed by period-averaged accelerations as samples
//                   arrive (problems/leveling/filter.h);
//   batch           a Ceres problem with roll, pitch and the vibration tones estimated
//                   jointly (problems/leveling/batch.h).
// docs/leveling.md gives the methods, the fallbacks and the measured figures.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/signal.h"
#include "core/units.h"

namespace navtwin::leveling {


/// One window of accelerometer (and optionally gyro) samples at a nominally constant rate.
struct AccelWindow {
  std::vector<double> t_s;                     ///< sample times (strictly increasing)
  std::vector<Eigen::Vector3d> f_b_mps2;       ///< specific force, body FRD
  std::vector<Eigen::Vector3d> omega_b_radps;  ///< angular rate, body FRD; empty if unknown
  double rate_hz = 0.0;                        ///< nominal sample rate
  std::string source;                          ///< file (or "simulation") for messages
  int size() const { return static_cast<int>(f_b_mps2.size()); }
};

struct LevelingOptions {
  /// Accelerometer white noise, 1 sigma per axis (m/s^2); <= 0: estimated from the data
  /// (EstimateAccelNoise; the batch uses its residuals).
  double accel_noise_mps2 = 0.0;
  /// Gravity magnitude of the batch model (m/s^2); <= 0: the mean |f| of the window.
  double gravity_mps2 = kStandardGravity_mps2;
  /// Autocorrelation: lags up to this fraction of the window, peak detection.
  double max_lag_fraction = 0.5;
  signal::PeakOptions peaks;
  /// Batch vibration model: axes with tones, tones per axis (harmonics k f, k = 1..n).
  std::array<bool, 3> vib_axes{{true, true, true}};
  int vib_tones = 1;
  /// Batch: estimate an accelerometer bias with this prior 1 sigma (m/s^2); 0: no bias.
  double accel_bias_prior_mps2 = 0.0;
  /// Batch: standard deviations from ceres::Covariance (off in Monte Carlo runs that only
  /// need the estimate).
  bool batch_covariance = true;
  /// Input checks: accelerometer full-scale range (|f| per axis at or beyond 99.5 % of it
  /// counts as saturated); motion when the mean |omega| exceeds max_rate_radps or the
  /// period-averaged |f| differs from gravity_mps2 (or 9.80665 when estimated) by more
  /// than max_gravity_mismatch_mps2.
  double accel_range_mps2 = 16.0 * kStandardGravity_mps2;
  double max_rate_radps = 0.05;
  double max_gravity_mismatch_mps2 = 0.5;
};

/// One method's result on one window.
struct LevelEstimate {
  std::string method;  ///< "plain_mean", "period_average", "filter", "batch"
  double roll_rad = 0.0;
  double pitch_rad = 0.0;
  double roll_sigma_rad = 0.0;   ///< 1 sigma, from the noise model (see each method)
  double pitch_sigma_rad = 0.0;
  int samples_used = 0;
  double period_samples = 0.0;   ///< period the method used (0: none)
  double vib_freq_hz = 0.0;      ///< batch: estimated fundamental (0: none)
  /// Empty when the method ran as designed; otherwise what it did instead and why
  /// (e.g. "no autocorrelation peak above 0.5: plain mean").
  std::string fallback;
};

/// Problems with a window that the methods cannot fix, found before leveling.
struct WindowCheck {
  int saturated_samples = 0;   ///< samples with an axis at the range limit
  bool moving = false;         ///< rotation or |f| far from gravity
  std::string message;         ///< one line per problem; empty when the window is fine
};
WindowCheck CheckWindow(const AccelWindow& window, const LevelingOptions& options);

/// The window without its saturated or clipped samples (as CheckWindow finds them), time
/// tags kept (filled from rate_hz when absent); *removed = how many were left out. The
/// batch fits its model to the rest (a clipped sample follows no sinusoid); the averaging
/// methods cannot drop samples without breaking whole periods and keep them.
AccelWindow WithoutSaturatedSamples(const AccelWindow& window, const LevelingOptions& options, int* removed);

/// The autocorrelation period of a window (multi-channel equation 2 over all axes, lags
/// up to max_lag_fraction of the window).
signal::PeriodEstimate EstimateWindowPeriod(const AccelWindow& window, const LevelingOptions& options);

/// Accelerometer white-noise 1 sigma (m/s^2) from differences of samples one period apart
/// (the periodic part cancels): sqrt(median over axes of mean (x_j - x_{j-P})^2 / 2); with
/// period_samples <= 0, the median over axes of the sample standard deviation.
double EstimateAccelNoise(const AccelWindow& window, double period_samples);

/// Plain mean of all samples; sigma = noise / (g sqrt(n)) through LevelJacobian.
LevelEstimate PlainMean(const AccelWindow& window, const LevelingOptions& options);

/// The seed's method. Falls back to the plain mean (and says so) when no period is found.
LevelEstimate PeriodAverage(const AccelWindow& window, const LevelingOptions& options);

/// All four methods in the order plain_mean, period_average, filter, batch.
std::vector<LevelEstimate> LevelAllMethods(const AccelWindow& window, const LevelingOptions& options);

}  // namespace navtwin::leveling
