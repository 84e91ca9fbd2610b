#include "problems/gnss_ins/adapted_noise.h"

#include <cstdio>

#include "core/units.h"

namespace navtwin::gnss_ins {
namespace {

/// Scales *value (in SI) by the group's sigma scale when it was adapted, and says so in
/// `unit` (value_si * to_unit).
void Scale(const std::map<std::string, ResidualStats>& residuals, const std::string& group, const char* what,
           double to_unit, const char* unit, double* value, AdaptedNoise* out) {
  const auto it = residuals.find(group);
  if (it == residuals.end() || !it->second.adapted) return;
  const double before = *value;
  *value *= it->second.sigma_scale;
  char line[256];
  std::snprintf(line, sizeof line, "%-24s %10.4g -> %10.4g %s (x%.3g, group %s)", what, before * to_unit,
                *value * to_unit, unit, it->second.sigma_scale, group.c_str());
  out->lines.push_back(line);
  out->changed = true;
}

}  // namespace

AdaptedNoise AdaptNoise(const GnssInsConfig& config, const std::map<std::string, ResidualStats>& residuals) {
  AdaptedNoise out;
  out.config = config;
  GnssInsConfig& c = out.config;
  Scale(residuals, "imu_rotation", "gyro ARW", 1.0 / kDegPerSqrtHour_radpsqrts, "deg/sqrt(h)",
        &c.imu_noise.gyro_arw_rad_per_sqrt_s, &out);
  Scale(residuals, "imu_velocity_position", "accelerometer VRW", 1.0 / kMpsPerSqrtHour_mpspsqrts, "m/s/sqrt(h)",
        &c.imu_noise.accel_vrw_mps_per_sqrt_s, &out);
  Scale(residuals, "gyro_bias_process", "gyro bias std", 1.0 / kDegPerHour_radps, "deg/h",
        &c.imu_noise.gyro_bias_std_radps, &out);
  Scale(residuals, "accel_bias_process", "accelerometer bias std", 1.0 / kMicroG_mps2, "ug",
        &c.imu_noise.accel_bias_std_mps2, &out);
  Scale(residuals, "gyro_scale_process", "gyro scale-factor std", 1.0 / kPpm, "ppm", &c.imu_noise.gyro_scale_std, &out);
  Scale(residuals, "accel_scale_process", "accelerometer scale std", 1.0 / kPpm, "ppm", &c.imu_noise.accel_scale_std,
        &out);
  Scale(residuals, "gnss_position_h", "GNSS position sigma N, E", 1.0, "x file sigma", &c.gnss.pos_sigma_scale_h, &out);
  Scale(residuals, "gnss_position_v", "GNSS position sigma D", 1.0, "x file sigma", &c.gnss.pos_sigma_scale_v, &out);
  Scale(residuals, "gnss_velocity_h", "GNSS velocity sigma N, E", 1.0, "x file sigma", &c.gnss.vel_sigma_scale_h, &out);
  Scale(residuals, "gnss_velocity_v", "GNSS velocity sigma D", 1.0, "x file sigma", &c.gnss.vel_sigma_scale_v, &out);
  Scale(residuals, "mag", "magnetometer noise", 1.0, "uT", &c.mag.noise_uT, &out);
  Scale(residuals, "baro", "barometer sigma", 1.0, "m", &c.baro.std_m, &out);
  Scale(residuals, "odometer", "odometer speed sigma", 1.0, "m/s", &c.odometer.std_mps, &out);
  return out;
}

}  // namespace navtwin::gnss_ins
