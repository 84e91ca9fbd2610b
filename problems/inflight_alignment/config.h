// Configuration of the in-flight heading alignment (seed 003, issue 7): the sensor
// specification that sets the filter's process noise and the priors of the Schuler
// terms, the GPS smoother, the distance-method policy and the batch's robust loss.
// YAML keys (docs/inflight-alignment.md, "Configuration") carry their people units (deg/h,
// ug, arcmin, km), converted to the SI members below as the file is read; unknown keys
// are errors naming the file, line and key path. Defaults are the seed's 1 NM/h INS.
#pragma once

#include <string>

#include "core/units.h"
#include "problems/inflight_alignment/gps_smoother.h"

namespace navtwin::inflight {

/// Sensor specification (1 sigma), IMU axes = body FRD.
struct InflightSensorSpec {
  double gyro_bias_radps = 0.01 * kDegPerHour_radps;                   ///< key gyro_bias_deg_h
  double gyro_arw_rad_per_sqrt_s = 0.005 * kDegPerSqrtHour_radpsqrts;  ///< key gyro_arw_deg_sqrt_h
  double accel_bias_mps2 = 100.0 * kMicroG_mps2;                       ///< key accel_bias_ug
  /// Velocity random walk (nav grade: negligible); key accel_vrw_m_s_sqrt_h.
  double accel_vrw_mps_per_sqrt_s = 0.0;
  /// Position sigma of the raw GPS fixes per horizontal axis (m); 0: estimated from the
  /// data (third differences, a robust median form; see EstimateGpsSigma).
  double gps_sigma_m = 0.0;
};

/// What is known of the initial state the INS was given (1 sigma).
struct InflightInitialSigma {
  double position_m = 17.0;         ///< horizontal, per axis
  /// Horizontal, per axis. On a straight flight an initial velocity error dV cannot be
  /// told from the heading (both grow the cross-track error linearly), so it costs
  /// dV / V_gained of heading: 0.01 m/s at the preset's 238 m/s gained is 0.14 arcmin,
  /// 0.1 m/s is 1.4 arcmin. The default assumes the INS velocity was set from a reference
  /// (launcher at rest, master INS) to about 1 cm/s.
  double velocity_mps = 0.01;
  /// Roll and pitch (aligned on the accelerometers: bias / g); key level_arcmin.
  double level_rad = 0.34 * kArcmin_rad;
  /// The error in-flight alignment is there to remove; key heading_arcmin.
  double heading_rad = 30.0 * kArcmin_rad;
};

/// Barometric vertical channel: a second-order loop pulls the INS height to the
/// barometric altitude with this time constant (critically damped).
struct BaroLoopOptions {
  double time_constant_s = 20.0;
};

/// The distance method (seed 003, figure 2) and its re-computation policy.
struct DistanceMethodOptions {
  double threshold_m = 10e3;  ///< first heading computation after this distance flown (key threshold_km)
  /// After the first, recompute with every sample since the start each time the distance
  /// flown has grown by this much (0: compute once, as the seed does); key recompute_every_km.
  double recompute_every_m = 10e3;
};

enum class RobustLoss { kNone, kHuber, kCauchy };

struct BatchOptions {
  RobustLoss loss = RobustLoss::kCauchy;
  /// Scale of the robust loss in units of the GPS sigma (residuals are whitened).
  double loss_scale_sigma = 3.0;
  int max_iterations = 50;
  /// Length of the segments the level random walk is cut into, s (0: off, the level error
  /// is a constant). The gyro angle random walk (sensors.gyro_arw_deg_sqrt_h) walks the
  /// level; the batch gives each segment boundary a 2-vector tilt step with prior sigma
  /// ARW sqrt(tilt_segment_s) (batch.h). Shorter segments model the walk more finely at a
  /// cost growing with the square of the number of steps; 30 s leaves under 1 m of
  /// position error at 545 s for a 0.005 deg/sqrt(h) gyro.
  double tilt_segment_s = 30.0;
};

struct InflightConfig {
  InflightSensorSpec sensors;
  InflightInitialSigma initial;
  BaroLoopOptions baro;
  GpsSmootherOptions smoother;
  /// The filters' GPS input, per method (YAML smoother.use_in_distance,
  /// smoother.use_in_kalman): true, smoothed fixes (the smoother's gate rejects
  /// outliers); false, the raw fixes with the sigma of sensors.gps_sigma_m (or
  /// EstimateGpsSigma) and a chi-square gate on the 2-dof innovation at
  /// smoother.gate_probability. The distance method smooths, as the seed's figure 2
  /// does; the conventional Kalman-only baseline takes the raw fixes: smoothed fixes are
  /// correlated from one second to the next, which its white-noise update does not
  /// model, and over 50 seeds its heading sigma was then optimistic by a factor of 1.6
  /// when the launch velocity is poorly known (docs/inflight-alignment.md, "Results").
  bool smooth_gps_distance = true;
  bool smooth_gps_kalman = false;
  DistanceMethodOptions distance;
  BatchOptions batch;
};

/// Reads a configuration YAML (every key optional; docs list them). Throws InputError
/// naming file, line and key for unknown keys, wrong types and values out of range
/// (a zero or negative sigma where one is needed, a threshold <= 0).
InflightConfig LoadInflightConfig(const std::string& path);
/// The same from YAML text (`file` names it in messages).
InflightConfig ParseInflightConfig(const std::string& yaml_text, const std::string& file);

const char* RobustLossName(RobustLoss loss);  ///< "none", "huber", "cauchy"

}  // namespace navtwin::inflight
