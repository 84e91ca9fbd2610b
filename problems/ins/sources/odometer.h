// A wheel odometer as an aiding source (factors/odometer_speed.h): the forward speed of the
// vehicle reference point (VehicleConfig, problems/ins/sources/nhc.h) with a scale-factor
// error estimated as an auxiliary state ("odometer_scale": a filter state, a batch
// parameter). Filter: at the samples' times (the IMU sample is split there); batch: the
// speed interpolated linearly to each state between the samples around it.
#pragma once

#include <memory>
#include <string>

#include "problems/ins/aiding.h"
#include "problems/ins/sources/nhc.h"

namespace navtwin::ins {

struct OdometerConfig {
  /// t_s,speed_mps or t_s,distance_m (core/io/csv_odometer.h), or an OB_GINS IMU file
  /// with the odometer column (core/io/kfgins.h); empty: off.
  std::string file;
  double std_mps = 0.1;     ///< speed noise
  double scale_std = 0.01;  ///< prior std of the scale-factor error (0: held at 0)
};

/// Count key "odometer". Reads config.file (InputError naming file, line and field).
std::unique_ptr<AidingSource> MakeOdometerSource(const OdometerConfig& config, const VehicleConfig& vehicle);

}  // namespace navtwin::ins
