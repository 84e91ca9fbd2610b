// Multi-position IMU calibration (issue 8 item 2): static positions of a table at known
// attitudes, optional rate-table rotations between them. docs/calibration-imu.md.
//
// Static positions (each hold of the schedule, trimmed by settle_s at both ends): the true
// f_b = -R_b_n g_n and omega_ib_b = R_b_n omega_ie_n at the table attitude, so the
// position means give the accelerometer scale, misalignment and bias, the gyro bias and
// the g-sensitivity. Moves and rotations between two positions: the gyro increments,
// compensated with the current parameters and integrated, must carry the attitude of one
// position to the next (Earth rate included) -> gyro scale and misalignment.
//
// Batch: Ceres least squares over all positions and moves, sigma from ceres::Covariance
// scaled by the a-posteriori variance of the residuals; parameters whose direction the
// data do not excite (e.g. all positions in one plane, no rotation about an axis) are
// reported in `unobservable` and held at 0, not solved for.
// Recursive: a Kalman filter over the same parameter vector that takes one position (and
// the move before it) at a time; after the last position it agrees with the batch.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/sim/calibration_rig.h"
#include "core/config/yaml_config.h"
#include "core/types.h"
#include "problems/calibration/imu_calibration.h"

namespace navtwin::calibration {

struct MultiPositionData {
  std::vector<ImuSample> imu;
  sim::MultiPositionConfig schedule;  ///< times on the IMU's time scale
  double latitude_rad = 0.0;
  double height_m = 0.0;
  std::string imu_path;  ///< for messages
};

struct MultiPositionOptions {
  double settle_s = 0.5;           ///< left out at both ends of every hold
  bool estimate_g_sensitivity = true;
  /// Sensor range per axis: a sample with any axis at or beyond it counts as saturated and
  /// is left out with a note (<= 0: no limit).
  double accel_saturation_mps2 = 0.0;
  double gyro_saturation_rad_per_s = 0.0;
};

/// The truth of an IMU at rest on the table at the attitude euler_rad (roll, pitch, yaw of
/// R_n_b): f_b = -R_b_n g_n (normal gravity at the site) and omega_ib_b = R_b_n omega_ie_n.
struct StaticTruth {
  Eigen::Matrix3d R_n_b;
  Eigen::Vector3d f_b_mps2;
  Eigen::Vector3d omega_ib_b_rad_per_s;
};
StaticTruth StaticTruthAt(const Eigen::Vector3d& euler_rad, double latitude_rad, double height_m);

/// Batch calibration. Throws std::runtime_error naming what is missing (fewer than 6
/// positions, no usable samples in a hold, ...).
ImuCalibrationResult CalibrateMultiPosition(const MultiPositionData& data, const MultiPositionOptions& options = {});

/// Reads {imu, latitude_deg, height_m, trajectory} from a record node (relative paths
/// against base_dir). Throws InputError (file, line, key).
MultiPositionData ReadMultiPositionData(const ConfigNode& node, const std::string& base_dir);

/// The record's optional keys: settle_s, accel_saturation_mps2, gyro_saturation_deg_s (0: no
/// limit), g_sensitivity (bool). Throws InputError (file, line, key) for negative values.
MultiPositionOptions ReadMultiPositionOptions(const ConfigNode& node);

/// The recursive form: feed positions in schedule order.
class RecursiveMultiPosition {
 public:
  RecursiveMultiPosition(const MultiPositionData& data, const MultiPositionOptions& options = {});
  /// Processes the next static position (and the move that led to it); false when done.
  bool Step();
  int positions_done() const;
  /// The current estimate and its covariance (same layout as the batch result).
  ImuCalibrationResult Current() const;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

}  // namespace navtwin::calibration
