// Rate samples (angular rate rad/s, specific force m/s^2 at time tags) -> IMU increments,
// and increment rows without an interval column -> increments with dt from the time tags.
//
// The increment of sample k covers (t_{k-1}, t_k] and is the trapezoid-rule integral of
// the two rate samples that bound it:
//   dtheta_k = (omega_{k-1} + omega_k) / 2 * (t_k - t_{k-1}),
//   dv_k     = (f_{k-1} + f_k) / 2 * (t_k - t_{k-1}).
// The FIRST rate sample only starts the series: nothing is known before it, so it yields
// no increment and N rate samples give N - 1 ImuSamples (the first at t_1).
// The trapezoid is exact for rates that vary linearly over the interval; it does not
// recover coning/sculling inside an interval (rate sensors sampled in time cannot).
#pragma once

#include <Eigen/Core>

#include "core/types.h"

namespace navtwin {

/// One rate sample in the sensor axes.
struct RateSample {
  double t_s = 0.0;
  Eigen::Vector3d gyro_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d acc_mps2 = Eigen::Vector3d::Zero();  ///< specific force
};

class RateToIncrement {
 public:
  /// Feeds the next rate sample. Returns false for the first one (it starts the series);
  /// afterwards fills *out with the increment over (t_prev, t] and returns true.
  /// Callers check that time increases (with file and line); a non-increasing time here
  /// is a programming error and throws std::invalid_argument.
  bool Add(const RateSample& sample, ImuSample* out);

 private:
  bool has_previous_ = false;
  RateSample previous_;
};

/// Increment rows (t, dtheta, dv; files such as KF-GINS give no interval) -> ImuSamples
/// with dt_s = t_k - t_{k-1}. The FIRST row's interval is taken to equal the second row's
/// (one-sample look-ahead), so every row becomes a sample and a file needs two rows.
class IncrementIntervals {
 public:
  /// Feeds the next row (its dt_s is ignored). Returns true when *out holds the previous
  /// row completed with its interval. Callers check that time increases.
  bool Add(const ImuSample& row, ImuSample* out);
  /// After the last row: emits the pending row; false when none is pending. With a single
  /// row fed, its interval is unknown: throws std::logic_error (readers check rows() first).
  bool Flush(ImuSample* out);
  std::size_t rows() const { return rows_; }

 private:
  bool has_pending_ = false;
  ImuSample pending_;
  double previous_t_s_ = 0.0;
  std::size_t rows_ = 0;
};

}  // namespace navtwin
