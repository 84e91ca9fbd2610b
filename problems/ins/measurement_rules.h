// Rules every aided-INS estimator applies the same way, filter and batch alike: the sigma
// of a measurement that a file may or may not give, and the stillness rule (ZUPT and the
// vehicle constraints decide with it).
#pragma once

#include <deque>

#include <Eigen/Core>

#include "core/types.h"

namespace navtwin::ins {

/// sigma = max(file sigma, floor) per axis, or max(fallback, floor) where the file gives
/// none (NaN).
Eigen::Vector3d MeasurementSigma(const Eigen::Vector3d& file_sigma, double floor, double fallback);

/// The stillness rule's thresholds.
struct StillnessConfig {
  double window_s = 0.5;                 ///< detection window
  double gyro_threshold_radps = 0.01;    ///< max |omega| over the window
  double accel_std_threshold_mps2 = 0.05;///< max std of |f| over the window
};

/// Zero-velocity updates where the stillness rule holds (its thresholds are the ZUPT's
/// configuration keys).
struct ZuptConfig : StillnessConfig {
  bool enabled = false;
  double std_mps = 0.02;
  double interval_s = 0.1;  ///< at most one update per this interval
};

/// Stillness detection: the vehicle is still when, over the last window_s of IMU samples
/// (bias-corrected, body axes), every |omega| = |dtheta| / dt stays at or below
/// gyro_threshold_radps and the standard deviation of |f| = |dv| / dt stays at or below
/// accel_std_threshold_mps2. Samples are added in time order.
class StillnessDetector {
 public:
  explicit StillnessDetector(const StillnessConfig& config) : config_(config) {}
  void Add(const ImuSample& s);
  /// Whether the samples cover the whole window and satisfy both thresholds.
  bool Still() const;

 private:
  struct Entry {
    double begin_s;   ///< start of the sample's interval
    double f_mps2;    ///< |f| - 9.8 (offset so that the sums of squares do not cancel)
    bool moving;      ///< |omega| above the threshold
  };
  StillnessConfig config_;
  std::deque<Entry> window_;
  int moving_ = 0;
  double sum_ = 0.0, sum_sq_ = 0.0;
  bool full_ = false;
};

}  // namespace navtwin::ins
