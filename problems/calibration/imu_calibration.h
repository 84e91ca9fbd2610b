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

#include <functional>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/calibration_file.h"

namespace navtwin::calibration {

// Parameter names: TriadParameterName, GSensitivityParameterName (core/imu_error_model.h).

/// A static position of a record (a table hold, a warm-up segment): the true and the mean
/// measured specific force and rate in body axes.
struct StaticPosition {
  double t0_s = 0.0, t1_s = 0.0;  ///< the window the means are over
  int run = 0;                    ///< chamber or warm-up run (0 for one record)
  double temperature_degC = std::numeric_limits<double>::quiet_NaN();  ///< NaN: no temperature
  Eigen::Vector3d f_true_b_mps2 = Eigen::Vector3d::Zero(), f_mean_b_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega_true_b_radps = Eigen::Vector3d::Zero(), omega_mean_b_radps = Eigen::Vector3d::Zero();
};

/// The residual (measured minus modelled) of a static position without calibration (every
/// parameter 0: the raw sensor against the truth) and with the estimate; for the pendulum,
/// which has no static positions, the RMS over one run's samples per axis instead (`rms`).
struct CalibrationResidual {
  double t0_s = 0.0, t1_s = 0.0;
  int run = 0;
  double temperature_degC = std::numeric_limits<double>::quiet_NaN();
  bool rms = false;
  Eigen::Vector3d accel_before_mps2 = Eigen::Vector3d::Zero(), accel_after_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_before_radps = Eigen::Vector3d::Zero(), gyro_after_radps = Eigen::Vector3d::Zero();
};

/// The residuals of static positions: mean measured minus the error model of `c` (at the
/// position's temperature when `c` has temperature terms) applied to the truth, before
/// (c = 0) and after.
std::vector<CalibrationResidual> StaticResiduals(const ImuCalibration& c, const std::vector<StaticPosition>& positions);

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
  /// The static positions the estimate rests on (multi-position, chamber, warm-up; empty for
  /// the pendulum) and the residuals before and after calibration, in record order.
  std::vector<StaticPosition> static_positions;
  std::vector<CalibrationResidual> residuals;
};

/// Writes {"rig":..,"parameters":{name:{"value":..,"sigma":..},..},"unobservable":[..],
/// "accel_residual_rms_mps2":..,...} (for --format=json).
/// With `command` (a run folder's summary.json) the object starts with "command": command.
std::string ImuCalibrationJson(const ImuCalibrationResult& result, const std::string& rig,
                               const std::string& command = "");
/// A human-readable table: name, value, sigma with units (ppm, mrad, mg, deg/h, deg/h/g).
std::string ImuCalibrationText(const ImuCalibrationResult& result, const std::string& rig);

/// parameters.csv of the run folder (docs/run-folder.md): `name,value,sigma,unit`, the rows of
/// the text report, value and σ in `unit` (ppm, mrad, mg, deg/h, …); σ nan where not estimated.
void WriteImuParametersCsv(std::ostream& out, const ImuCalibrationResult& result);
/// residuals.csv of the run folder: one row per CalibrationResidual, `t0_s,t1_s,run,
/// temperature_degC,rms,accel_before_{x,y,z}_mg,accel_after_{x,y,z}_mg,gyro_before_{x,y,z}_deg_h,
/// gyro_after_{x,y,z}_deg_h` (rms 1: a pendulum run's RMS, 0: a static position's mean residual).
void WriteImuResidualsCsv(std::ostream& out, const ImuCalibrationResult& result);

/// The recursive estimates, one per static position, as the terminal shows them: a header
/// (with `header`), then per estimate its positions, the end of its last position and the
/// accelerometer and gyro biases and scale factors with 1σ ("-" while not observable).
std::string RecursiveStepText(const ImuCalibrationResult& estimate, bool header);
/// convergence.csv of the run folder: one row per recursive estimate, `positions,t_s`, then
/// per parameter (the rows of parameters.csv) `<name>_<unit>` and `<name>_sigma_<unit>`
/// (unit with '/' as '_': mg, deg_h, ppm, mrad, deg_h_g), nan while not estimated.
void WriteImuConvergenceCsv(std::ostream& out, const std::vector<ImuCalibrationResult>& estimates);

/// Reads a record file and calibrates. Throw InputError (file, line, key) for bad records
/// and std::runtime_error naming what is missing for data that cannot calibrate (too few
/// positions, a temperature span too small for the order, ...). Defined in
/// multiposition.cc, pendulum.cc and temperature.cc.
ImuCalibrationResult CalibrateMultiPositionRecord(const std::string& record_path);
/// The recursive form of the multi-position record (RecursiveMultiPosition): the estimate
/// after every static position goes to `on_position`; returns the last one.
ImuCalibrationResult CalibrateMultiPositionRecordRecursive(
    const std::string& record_path, const std::function<void(const ImuCalibrationResult&)>& on_position);
ImuCalibrationResult CalibratePendulumRecord(const std::string& record_path);
ImuCalibrationResult CalibrateTemperatureRecord(const std::string& record_path);

}  // namespace navtwin::calibration
