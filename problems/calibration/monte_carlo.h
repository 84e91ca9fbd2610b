// IMU calibration on the multi-position table under `navtwin mc --problem calibration`
// (docs/monte-carlo.md): run k simulates the scenario (a YAML whose trajectory is a
// multiposition table, e.g. data/calibration/multiposition/scenario.yaml) with seed S + k,
// writes the record a user would write for it (the table schedule, latitude, height) and
// calibrates with the batch and the recursive form. Quantities (estimate - truth, one point,
// axis "final"), with the covariance block each method reports: accel_scale_factor (ppm),
// accel_misalignment (arcsec, the six off-diagonal entries in core/imu_error_model.h's
// order), accel_bias (mg), gyro_scale_factor (ppm), gyro_misalignment (arcsec), gyro_bias
// (deg/h), g_sensitivity (deg/h/g). Parameters a method left unestimated have no sigma.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "solvers/mc_record.h"

namespace navtwin::calibration {

struct CalibrationMcSetup {
  std::string scenario_path;  ///< a scenario YAML with a multiposition trajectory
  std::vector<std::string> methods = {"batch", "recursive"};
};

/// Throws std::invalid_argument naming what is wrong (unknown method, a scenario that is
/// not a YAML file with a multiposition trajectory and a start).
void CheckCalibrationMcSetup(const CalibrationMcSetup& setup);

/// Run `run` with `seed`; a method that throws is recorded as failed.
mc::RunRecord CalibrationMcRun(const CalibrationMcSetup& setup, std::uint64_t seed, int run);

}  // namespace navtwin::calibration
