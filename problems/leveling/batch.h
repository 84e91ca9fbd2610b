// Batch leveling: a Ceres least-squares problem over every sample of a window with roll,
// pitch, (optionally) an accelerometer bias and the vibration estimated jointly, so that
// no part-period of the vibration is lost. The batch twin of seed 000; docs/leveling.md.
//
// Model for sample k at time t_k (relative to the window centre):
//   f_k = SpecificForceAtRest(roll, pitch, g) + b
//         + sum_{h=1..H} [ c_h cos(2 pi h f t_k) + s_h sin(2 pi h f t_k) ] + n_k
// with c_h, s_h in R^3 (zero and held constant on axes without vibration), n_k white
// with 1 sigma per axis. Tone h on an axis is A sin(2 pi h f t + phi) with
// A = hypot(c, s), phi = atan2(c, s).
#pragma once

#include <string>
#include <vector>

#include "core/signal.h"
#include "problems/leveling/leveling.h"

namespace navtwin::leveling {

struct VibrationToneEstimate {
  int axis = 0;       ///< 0, 1, 2 = body x, y, z
  int harmonic = 1;   ///< frequency = harmonic x fundamental
  double amplitude_mps2 = 0.0;
  double phase_rad = 0.0;
};

struct BatchLevelingResult {
  LevelEstimate estimate;  ///< method "batch"
  std::vector<VibrationToneEstimate> tones;
  double vib_freq_sigma_hz = 0.0;
  Eigen::Vector3d accel_bias_mps2 = Eigen::Vector3d::Zero();
  double residual_rms_mps2 = 0.0;  ///< per axis and sample
  int iterations = 0;
  bool converged = false;
  std::string covariance_note;     ///< why sigmas are missing, if they are
};

/// Solves the batch problem started from `period` (the autocorrelation period of the
/// window); without a period the model has no tones (the fallback says so).
BatchLevelingResult SolveLevelingBatch(const AccelWindow& window, const LevelingOptions& options,
                                       const signal::PeriodEstimate& period);

/// EstimateWindowPeriod, then SolveLevelingBatch; returns the estimate.
LevelEstimate RunBatch(const AccelWindow& window, const LevelingOptions& options);

}  // namespace navtwin::leveling
