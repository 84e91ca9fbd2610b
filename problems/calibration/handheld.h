// IMU calibration without equipment: the sensor put down by hand in a dozen or more
// orientations (Tedaldi, Pretto, Menegatti, "A robust and easy to implement method for IMU
// calibration without external equipments", ICRA 2014), in navtwin's error model
// (core/imu_error_model.h) and calibration file. docs/calibration-imu.md "Without a rig".
//
// 1. Still intervals: the specific force f = dv/dt; per sample the variance of each axis
//    over a centred window of window_s, s(t) = sqrt(var_x^2 + var_y^2 + var_z^2); s_init the
//    same over the initial still period; still where s(t) < k s_init. Runs at least
//    min_still_s long, trimmed by half a window at both ends, are the still intervals.
// 2. Accelerometer: r_i = (|K_a^-1 (mean f_m,i - b_a)| - g) / sigma_i over the still
//    intervals (g: WGS84 normal gravity at the given latitude and height). The magnitude
//    cannot see a rotation of the triad: the three upper misalignments (xy, xz, yz) are held
//    at 0, i.e. the body axes are the accelerometer's, x along its x axis, y in its xy plane.
//    9 unknowns. k is chosen among threshold_multiples as the one whose fit leaves the
//    smallest residual RMS (the paper's choice), among those with enough intervals.
// 3. Gyroscope: the bias is the mean rate over the initial still period (with the Earth
//    rate in it: ~15 deg/h at most, below a MEMS gyro's bias uncertainty; its change of
//    direction over a turn of a few seconds is 1e-4 rad). For each turn between consecutive
//    still intervals a and b, the calibrated accelerometer's gravity direction at a, carried
//    through the compensated, coning-corrected gyro integration R (body a -> body b), must be
//    the direction seen at b:  r = (u_b - R^T u_a) / sigma. Scale factors and misalignments
//    of the gyro: 9 unknowns (the accelerometer fixed the body axes).
// Both fits in Ceres; sigma from ceres::Covariance times the a-posteriori variance factor.
// Unobservable: the three held accelerometer misalignments (named), the g-sensitivity (not
// estimated); too few intervals or turns are an error naming what is missing.
#pragma once

#include <string>
#include <vector>

#include "core/types.h"
#include "problems/calibration/imu_calibration.h"

namespace navtwin::calibration {

struct HandheldOptions {
  double initial_still_s = 30.0;  ///< the still period at the start (threshold, gyro bias)
  double window_s = 1.0;          ///< variance window of the still detector
  double min_still_s = 1.0;       ///< shortest still interval used (before trimming)
  std::vector<double> threshold_multiples = {2, 3, 4, 5, 6, 7, 8, 9, 10};
};

struct HandheldData {
  std::vector<ImuSample> imu;
  std::string imu_path;   ///< for messages
  double latitude_rad = 0.0;
  double height_m = 0.0;
};

/// What the still detector found, reported with the result's notes.
struct StillDetection {
  double threshold = 0.0;  ///< k s_init, (m/s^2)^2
  double multiple = 0.0;   ///< k
  int intervals = 0;
};

/// A handheld record (YAML, `calibrate-imu --rig handheld --data RECORD`; paths relative to
/// the record): {imu: FILE, latitude_deg, height_m (default 0), initial_still_s (default 30),
/// counts: {gyro_rad_s_per_count, accel_mps2_per_count} (optional)}. Without `counts` the IMU
/// file is any format navtwin reads; with it, a CSV of raw sensor counts (t_s or t_ms,
/// gyro_x_counts, gyro_y_counts, gyro_z_counts, acc_x_counts, acc_y_counts, acc_z_counts)
/// turned into rates with the nominal sensitivities (the calibration's scale factors absorb
/// their error) and into increments by the trapezoid rule. Throws InputError (file, line, key).
HandheldData ReadHandheldRecord(const std::string& record_path, HandheldOptions* options);

/// Calibrates; throws std::runtime_error naming what is missing (no initial still period,
/// too few still intervals or turns) and InputError for an IMU record that cannot be used.
ImuCalibrationResult CalibrateHandheld(const HandheldData& data, const HandheldOptions& options = {},
                                       StillDetection* detection = nullptr);

}  // namespace navtwin::calibration
