// Reading the in-flight alignment configuration (config.h). Every key is optional and
// keeps the default of config.h when absent; keys carry their units in their names, as in
// the simulator's scenarios (core/config/yaml_config.h). Unknown keys, wrong types and values
// out of range are InputError naming the file, the line and the key path.
#include "problems/inflight_alignment/config.h"

#include <cstdio>
#include <string>

#include "core/io/input_error.h"
#include "core/config/yaml_config.h"

namespace navtwin::inflight {
namespace {


InflightSensorSpec ParseSensors(const ConfigNode& n) {
  n.RequireKeys({"gyro_bias_deg_h", "gyro_arw_deg_sqrt_h", "accel_bias_ug", "accel_vrw_m_s_sqrt_h",
                 "gps_sigma_m"});
  InflightSensorSpec s;
  // Biases and noise densities may be zero (a sensor without that error); the filter's
  // process noise and the Schuler priors then leave the term out.
  s.gyro_bias_radps = n.NonNegativeSi("gyro_bias_deg_h", kDegPerHour_radps, s.gyro_bias_radps);
  s.gyro_arw_rad_per_sqrt_s =
      n.NonNegativeSi("gyro_arw_deg_sqrt_h", kDegPerSqrtHour_radpsqrts, s.gyro_arw_rad_per_sqrt_s);
  s.accel_bias_mps2 = n.NonNegativeSi("accel_bias_ug", kMicroG_mps2, s.accel_bias_mps2);
  s.accel_vrw_mps_per_sqrt_s =
      n.NonNegativeSi("accel_vrw_m_s_sqrt_h", kMpsPerSqrtHour_mpspsqrts, s.accel_vrw_mps_per_sqrt_s);
  // 0 asks for the estimate from the data (EstimateGpsSigma).
  s.gps_sigma_m = n.NonNegative("gps_sigma_m", s.gps_sigma_m);
  return s;
}

InflightInitialSigma ParseInitial(const ConfigNode& n) {
  n.RequireKeys({"position_m", "velocity_mps", "level_arcmin", "heading_arcmin"});
  InflightInitialSigma s;
  // The filter's initial covariance: every diagonal entry must be positive.
  s.position_m = n.Positive("position_m", s.position_m);
  s.velocity_mps = n.Positive("velocity_mps", s.velocity_mps);
  s.level_rad = n.PositiveSi("level_arcmin", kArcmin_rad, s.level_rad);
  s.heading_rad = n.PositiveSi("heading_arcmin", kArcmin_rad, s.heading_rad);
  return s;
}

BaroLoopOptions ParseBaro(const ConfigNode& n) {
  n.RequireKeys({"time_constant_s"});
  BaroLoopOptions b;
  b.time_constant_s = n.Positive("time_constant_s", b.time_constant_s);
  return b;
}

/// The smoother's options, with the ranges GpsSmoother checks (gps_smoother.cc), here with
/// the file and line.
GpsSmootherOptions ParseSmoother(const ConfigNode& n) {
  n.RequireKeys({"use_in_distance", "use_in_kalman", "quiet_accel_noise_mps2_sqrt_hz", "maneuver_accel_noise_mps2_sqrt_hz",
                 "maneuver_mean_interval_s", "maneuver_mean_duration_s", "initial_position_sigma_ned_m",
                 "initial_speed_sigma_mps", "noise_window_fixes", "noise_min_fixes", "min_position_sigma_m",
                 "max_position_sigma_m", "gate_probability", "reset_after_rejections"});
  GpsSmootherOptions o;
  o.quiet_accel_noise_mps2_sqrt_hz = n.Positive("quiet_accel_noise_mps2_sqrt_hz", o.quiet_accel_noise_mps2_sqrt_hz);
  o.maneuver_accel_noise_mps2_sqrt_hz =
      n.Positive("maneuver_accel_noise_mps2_sqrt_hz", o.maneuver_accel_noise_mps2_sqrt_hz);
  o.maneuver_mean_interval_s = n.Positive("maneuver_mean_interval_s", o.maneuver_mean_interval_s);
  o.maneuver_mean_duration_s = n.Positive("maneuver_mean_duration_s", o.maneuver_mean_duration_s);
  const std::string sigma_key = "initial_position_sigma_ned_m";
  if (n.Has(sigma_key)) {
    // One value for every axis, or [n, e, d].
    if (n.yaml()[sigma_key].IsScalar()) {
      o.initial_position_sigma_ned_m = Eigen::Vector3d::Constant(n.Double(sigma_key, 0.0));
    } else {
      o.initial_position_sigma_ned_m = n.Vector(sigma_key, o.initial_position_sigma_ned_m);
    }
    if (!(o.initial_position_sigma_ned_m.array() > 0.0).all()) {
      n.Fail(sigma_key, "every entry must be > 0 (standard deviations, m)");
    }
  }
  o.initial_speed_sigma_mps = n.Positive("initial_speed_sigma_mps", o.initial_speed_sigma_mps);
  constexpr int kMaxFixes = 1000000;
  o.noise_window_fixes = n.Int("noise_window_fixes", o.noise_window_fixes, 1, kMaxFixes);
  o.noise_min_fixes = n.Int("noise_min_fixes", o.noise_min_fixes, 1, kMaxFixes);
  if (o.noise_min_fixes > o.noise_window_fixes) {
    n.Fail(n.Has("noise_min_fixes") ? "noise_min_fixes" : "noise_window_fixes",
           "noise_min_fixes (" + std::to_string(o.noise_min_fixes) + ") must not exceed noise_window_fixes (" +
               std::to_string(o.noise_window_fixes) + ")");
  }
  o.min_position_sigma_m = n.Positive("min_position_sigma_m", o.min_position_sigma_m);
  o.max_position_sigma_m = n.Positive("max_position_sigma_m", o.max_position_sigma_m);
  if (o.max_position_sigma_m < o.min_position_sigma_m) {
    n.Fail(n.Has("max_position_sigma_m") ? "max_position_sigma_m" : "min_position_sigma_m",
           "max_position_sigma_m must be >= min_position_sigma_m");
  }
  o.gate_probability = n.Double("gate_probability", o.gate_probability);
  if (!(o.gate_probability > 0.0 && o.gate_probability <= 1.0)) {
    n.Fail("gate_probability", "must be in (0, 1] (1: no gate)");
  }
  o.reset_after_rejections = n.Int("reset_after_rejections", o.reset_after_rejections, 1, kMaxFixes);
  return o;
}

DistanceMethodOptions ParseDistance(const ConfigNode& n) {
  n.RequireKeys({"threshold_km", "recompute_every_km"});
  DistanceMethodOptions d;
  constexpr double kKm_m = 1e3;
  d.threshold_m = n.PositiveSi("threshold_km", kKm_m, d.threshold_m);
  d.recompute_every_m = n.NonNegativeSi("recompute_every_km", kKm_m, d.recompute_every_m);  // 0: once
  return d;
}

BatchOptions ParseBatch(const ConfigNode& n) {
  n.RequireKeys({"loss", "loss_scale_sigma", "max_iterations", "tilt_segment_s"});
  BatchOptions b;
  const std::string loss = n.String("loss", RobustLossName(b.loss));
  if (loss == "none") {
    b.loss = RobustLoss::kNone;
  } else if (loss == "huber") {
    b.loss = RobustLoss::kHuber;
  } else if (loss == "cauchy") {
    b.loss = RobustLoss::kCauchy;
  } else {
    n.Fail("loss", "expected none, huber or cauchy, got '" + loss + "'");
  }
  b.loss_scale_sigma = n.Positive("loss_scale_sigma", b.loss_scale_sigma);
  b.max_iterations = n.Int("max_iterations", b.max_iterations, 1, 100000);
  b.tilt_segment_s = n.NonNegative("tilt_segment_s", b.tilt_segment_s);  // 0: no level random walk
  return b;
}

InflightConfig ParseRoot(const ConfigNode& root) {
  root.RequireKeys({"sensors", "initial", "baro", "smoother", "distance", "batch"});
  InflightConfig c;
  c.sensors = ParseSensors(root.Child("sensors"));
  c.initial = ParseInitial(root.Child("initial"));
  c.baro = ParseBaro(root.Child("baro"));
  c.smoother = ParseSmoother(root.Child("smoother"));
  c.smooth_gps_distance = root.Child("smoother").Bool("use_in_distance", c.smooth_gps_distance);
  c.smooth_gps_kalman = root.Child("smoother").Bool("use_in_kalman", c.smooth_gps_kalman);
  c.distance = ParseDistance(root.Child("distance"));
  c.batch = ParseBatch(root.Child("batch"));
  return c;
}

}  // namespace

InflightConfig LoadInflightConfig(const std::string& path) { return ParseRoot(LoadYamlFile(path)); }

InflightConfig ParseInflightConfig(const std::string& yaml_text, const std::string& file) {
  return ParseRoot(ParseYaml(yaml_text, file));
}

const char* RobustLossName(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::kNone:
      return "none";
    case RobustLoss::kHuber:
      return "huber";
    case RobustLoss::kCauchy:
      return "cauchy";
  }
  return "unknown";
}

}  // namespace navtwin::inflight
