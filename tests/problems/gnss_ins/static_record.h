// A tiny GNSS/INS record for the run and command tests: 20 s of a level, north-facing,
// static IMU at 100 Hz (gravity and Earth rate, no errors) at 30 N 114 E, 20 m, 1 Hz GNSS
// at its position, and a navtwin configuration starting from the known state; and the
// listing of an output folder (a failed run must leave nothing).
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <dirent.h>

#include "core/earth.h"
#include "core/units.h"

namespace navtwin::static_record {

constexpr double kLatDeg = 30.0, kLonDeg = 114.0, kH_m = 20.0;
constexpr int kImuSamples = 2000;  ///< 100 Hz for 20 s

/// IMU line k (t = k / 100 s), KF-GINS increments.
inline std::string ImuLine(int k) {
  const double lat_rad = kLatDeg * kDegToRad, dt_s = 0.01;
  const double g_mps2 = wgs84::NormalGravity(lat_rad, kH_m);
  char buf[200];
  std::snprintf(buf, sizeof buf, "%.2f %.12e 0 %.12e 0 0 %.12e\n", k * dt_s,
                wgs84::kOmegaIe_radps * std::cos(lat_rad) * dt_s, -wgs84::kOmegaIe_radps * std::sin(lat_rad) * dt_s,
                -g_mps2 * dt_s);
  return buf;
}

/// GNSS line at t (KF-GINS, 1 m / 1 m / 2 m sigmas unless given).
inline std::string GnssLine(double t_s, double lat_deg = kLatDeg, const char* sigma_n_m = "1.0") {
  char buf[200];
  std::snprintf(buf, sizeof buf, "%.1f %.9f %.9f %.3f %s 1.0 2.0\n", t_s, lat_deg, kLonDeg, kH_m, sigma_n_m);
  return buf;
}

/// The navtwin configuration of the record (IMU noise and the known initial state).
inline std::string ConfigYaml() {
  return "imu_noise:\n"
         "  gyro_arw_deg_sqrt_h: 0.2\n"
         "  accel_vrw_m_s_sqrt_h: 0.1\n"
         "  gyro_bias_std_deg_h: 10\n"
         "  accel_bias_std_ug: 1000\n"
         "init:\n"
         "  source: given\n"
         "  time_s: 0\n"
         "  position_deg_m: [30, 114, 20]\n"
         "  velocity_mps: [0, 0, 0]\n"
         "  attitude_deg: [0, 0, 0]\n"
         "  attitude_std_deg: [0.5, 0.5, 2]\n";
}

/// Entries of a folder other than . and .. (none when it does not exist).
inline std::vector<std::string> Entries(const std::string& dir) {
  std::vector<std::string> names;
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return names;
  while (const dirent* e = ::readdir(d)) {
    const std::string n = e->d_name;
    if (n != "." && n != "..") names.push_back(n);
  }
  ::closedir(d);
  return names;
}

}  // namespace navtwin::static_record
