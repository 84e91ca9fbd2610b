// A wheel odometer as an aiding source (factors/odometer_speed.h): the forward speed of the
// vehicle reference point (VehicleConfig, problems/ins/sources/nhc.h) with a scale-factor
// error estimated as an auxiliary state ("odometer_scale": a filter state, a batch
// parameter). Filter: at the samples' times (the IMU sample is split there); batch: the
// speed interpolated linearly to each state between the samples around it.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/io/csv_odometer.h"
#include "problems/ins/aiding.h"
#include "problems/ins/sources/nhc.h"

namespace navtwin::ins {

struct OdometerConfig {
  /// t_s,speed_mps or t_s,distance_m (core/io/csv_odometer.h), or an OB_GINS IMU file
  /// with the odometer column (core/io/kfgins.h); empty: off unless from_imu_file.
  std::string file;
  /// The odometer is the column of the run's IMU file (OB_GINS), whatever file says.
  bool from_imu_file = false;
  double std_mps = 0.1;     ///< speed noise
  double scale_std = 0.01;  ///< prior std of the scale-factor error (0: held at 0)

  bool enabled() const { return from_imu_file || !file.empty(); }
};

/// Count key "odometer"; samples: the record's speeds, read once with the other inputs.
std::unique_ptr<AidingSource> MakeOdometerSource(const std::vector<OdometerSample>& samples,
                                                 const OdometerConfig& config, const VehicleConfig& vehicle);

}  // namespace navtwin::ins
