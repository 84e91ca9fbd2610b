// The built-in demonstration record: the analytic demo flight (core/sim) sampled with
// exact increments and written as KF-GINS files, so that `navtwin ins --demo` runs the
// whole path (writers, readers, mechanization, truth comparison) with nothing to bring.
#pragma once

#include <string>

namespace navtwin {

struct DemoFiles {
  std::string imu_path;    ///< KF-GINS IMU increments
  std::string truth_path;  ///< KF-GINS navigation format, at the IMU rate
};

/// Writes <dir>/imu.txt and <dir>/truth.nav (the folder must exist). The flight starts at
/// 37.5 N, 127 E, 500 m, at GPS second of week 0 of week 0.
DemoFiles WriteDemoFlight(const std::string& dir, double rate_hz, double duration_s);

}  // namespace navtwin
