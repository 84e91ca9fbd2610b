// Online leveling: roll and pitch with a covariance, updated as samples arrive from
// period-averaged accelerations, the period re-estimated from a running autocorrelation
// (equation 2) as data arrive. The filter form of seed 000; docs/leveling.md describes the
// period search (peak lags, then the period that best cancels in x_j - x(j - P)), the
// blocks averaged over exactly one fractional period, and the information-form update.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/signal.h"
#include "problems/leveling/leveling.h"

namespace navtwin::leveling {

class OnlineLeveler {
 public:
  /// rate_hz: nominal sample rate; max_lag_samples: longest autocorrelation lag kept. A
  /// period is accepted once the samples hold 2.5 of them, so the longest period the
  /// filter can find is about min(max_lag_samples - 2, samples / 2.5).
  OnlineLeveler(const LevelingOptions& options, double rate_hz, int max_lag_samples);

  /// Adds one specific-force sample (body FRD, m/s^2). Returns true when a whole-period
  /// block was completed and roll/pitch were updated.
  bool Add(const Eigen::Vector3d& f_b_mps2);

  /// At least one block update was made.
  bool initialized() const;
  /// Current estimate (method "filter"): roll, pitch, 1-sigma from the covariance, the
  /// period in use. Before the first update: the plain mean of the samples so far, with
  /// the fallback saying so.
  LevelEstimate Estimate() const;
  /// Covariance of (roll, pitch), rad^2.
  Eigen::Matrix2d covariance() const;
  /// Roll and pitch 1-sigma both below sigma_limit_rad: leveling is good enough.
  bool Converged(double sigma_limit_rad) const;

 private:
  void UpdatePeriod();
  void ProcessBlock();
  void PlainMeanSoFar(Eigen::Vector3d* mean_f_b_mps2, Eigen::Matrix2d* covariance) const;

  LevelingOptions options_;
  double rate_hz_;
  signal::RunningAutocorrelation autocorr_;
  AccelWindow window_;            ///< the samples so far (f_b_mps2 only)
  Eigen::Vector3d sum_f_ = Eigen::Vector3d::Zero();   ///< running sums of f and f^2 (per axis)
  Eigen::Vector3d sum_f2_ = Eigen::Vector3d::Zero();
  double block_start_ = 0.0;      ///< fractional sample index where the next block starts
  double period_samples_ = 0.0;   ///< fractional period in use (0: none yet)
  int blocks_ = 0;
  Eigen::Vector3d block_sum_ = Eigen::Vector3d::Zero();  ///< sum of the block means (gravity)
  Eigen::Vector2d x_ = Eigen::Vector2d::Zero();  ///< roll, pitch (rad)
  Eigen::Matrix2d p_ = Eigen::Matrix2d::Zero();
};

/// Runs OnlineLeveler over a window (max lag = options.max_lag_fraction of it) and
/// returns its final estimate.
LevelEstimate RunFilter(const AccelWindow& window, const LevelingOptions& options);

}  // namespace navtwin::leveling
