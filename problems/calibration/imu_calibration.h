// IMU calibration (issue 8, seed 001 section 3): what every rig's calibration returns, the
// parameter names used in reports and JSON, and the record files `navtwin calibrate-imu
// --data F --rig multiposition|pendulum|temperature` reads. The error model is
// core/imu_error_model.h; the file written is core/calibration_file.h.
//
// Calibration records (YAML; relative paths are relative to the record file; schemas in
// docs/calibration-imu.md):
//   multiposition: {imu: FILE, latitude_deg, height_m, trajectory: {kind: multiposition,...}}
//                  the table schedule in the simulator's schema (core/sim/calibration_rig.h),
//                  its times on the IMU's time scale; optional settle_s,
//                  accel_saturation_mps2, gyro_saturation_deg_s, g_sensitivity.
//   pendulum:      {latitude_deg, height_m, runs: [{imu: FILE, angle: FILE, length_m,
//                  mounting | mounting_deg}, ...]}; angle files t_s,theta_rad|theta_deg.
//   temperature:   {order (default 2), latitude_deg, height_m, reference_degC (optional),
//                  runs: [{temperature_degC, imu: FILE, trajectory: {kind: multiposition,
//                  ...}}, ...]} for chamber soaks; a warm-up run gives `temperature: FILE`
//                  (t_s,temperature_degC) instead of temperature_degC, with segment_s
//                  (docs/calibration-temperature.md).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/calibration_file.h"

namespace navtwin::calibration {

/// Names of the parameters, in block order: "accel.scale_factor.x",
/// "accel.misalignment.xy", "accel.bias.z", "gyro....", "g_sensitivity.xy" (row x, col y).
std::string TriadParameterName(const std::string& triad, int index);
std::string GSensitivityParameterName(int index);

struct ImuCalibrationResult {
  /// The estimates; parameters not estimated (or unobservable) are 0 with sigma NaN.
  ImuCalibration calibration;
  /// Full covariance of the estimated parameters, in the order of `estimated`.
  Eigen::MatrixXd covariance;
  std::vector<std::string> estimated;     ///< names, in covariance order
  /// Parameters the data cannot observe (with why), left at 0 instead of reported.
  std::vector<std::string> unobservable;
  double accel_residual_rms_mps2 = 0.0;
  double gyro_residual_rms_rad_per_s = 0.0;
  int positions = 0;  ///< static positions (multi-position, temperature) or runs (pendulum)
  std::vector<std::string> notes;  ///< e.g. samples left out as saturated
};

/// Writes {"rig":..,"parameters":{name:{"value":..,"sigma":..},..},"unobservable":[..],
/// "accel_residual_rms_mps2":..,...} (for --format=json).
std::string ImuCalibrationJson(const ImuCalibrationResult& result, const std::string& rig);
/// A human-readable table: name, value, sigma with units (ppm, mrad, mg, deg/h, deg/h/g).
std::string ImuCalibrationText(const ImuCalibrationResult& result, const std::string& rig);

/// Reads a record file and calibrates. Throw InputError (file, line, key) for bad records
/// and std::runtime_error naming what is missing for data that cannot calibrate (too few
/// positions, a temperature span too small for the order, ...). Defined in
/// multiposition.cc, pendulum.cc and temperature.cc.
ImuCalibrationResult CalibrateMultiPositionRecord(const std::string& record_path);
ImuCalibrationResult CalibratePendulumRecord(const std::string& record_path);
ImuCalibrationResult CalibrateTemperatureRecord(const std::string& record_path);

}  // namespace navtwin::calibration
