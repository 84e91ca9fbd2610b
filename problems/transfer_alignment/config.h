// Configuration of transfer alignment (seed 002, issue 6). YAML keys carry people units
// (gyro_bias_deg_h, accel_bias_ug, master_attitude_mrad, ...), converted to the SI members
// below as the file is read; unknown keys are errors naming file, line and key. Defaults: the preset
// transfer-alignment-high-maneuver's slave (tactical grade) and master.
#pragma once

#include <string>

#include <Eigen/Core>

#include "core/units.h"

namespace navtwin::transfer {

struct TransferConfig {
  // Slave IMU specification (1 sigma).
  double gyro_bias_radps = 1.0 * kDegPerHour_radps;                      ///< key gyro_bias_deg_h
  double gyro_arw_rad_per_sqrt_s = 0.05 * kDegPerSqrtHour_radpsqrts;     ///< key gyro_arw_deg_sqrt_h
  double accel_bias_mps2 = 200.0 * kMicroG_mps2;                         ///< key accel_bias_ug
  double accel_vrw_mps_per_sqrt_s = 0.05 * kMpsPerSqrtHour_mpspsqrts;    ///< key accel_vrw_m_s_sqrt_h
  /// The slave triads' scale factors and axis misalignments (the six off-diagonal entries of
  /// each triad's error matrix, core/imu_errors.h): 1-sigma priors of the batch and of the
  /// history filter, which estimate them; 0 = not estimated (held at zero). The order-1
  /// and order-2 filters do not model them.
  double gyro_scale_factor = 100.0 * kPpm;                   ///< key gyro_scale_factor_ppm
  double accel_scale_factor = 100.0 * kPpm;                  ///< key accel_scale_factor_ppm
  double gyro_axis_misalignment_rad = 20.0 * kArcsec_rad;    ///< key gyro_axis_misalignment_arcsec
  double accel_axis_misalignment_rad = 20.0 * kArcsec_rad;   ///< key accel_axis_misalignment_arcsec
  // Initial uncertainty (1 sigma).
  double initial_velocity_mps = 1.0;
  double initial_attitude_rad = 2.0 * kDegToRad;  ///< key initial_attitude_deg
  double misalignment_rad = 2.0 * kDegToRad;      ///< key misalignment_deg; of the misalignment around
                                                  ///< its initial guess (0 = identity)
  double delay_s = 0.5;            ///< of the delay around its initial guess
  double delay_initial_s = 0.0;    ///< initial guess of the delay
  // Master measurement noise (1 sigma): attitude per axis and velocity per axis.
  double master_attitude_rad = 0.5 * kMrad_rad;  ///< key master_attitude_mrad
  double master_velocity_mps = 0.05;
  /// The filter's master derivatives (omega, omega_dot, a, a_dot): a causal least-squares
  /// quadratic over this window of records (master.h); 0 = first and second differences
  /// (the default). Differences pass the master's velocity noise into the order-2
  /// compensation with a gain of about (tau / dt)^2 / 2 (0.01 m/s becomes 2.3 m/s at 0.3 s
  /// and 50 Hz), which the filter's R carries; a 0.1-1 s fit lowers that gain but lags a
  /// manoeuvre that is not quadratic over the window, and on the simulated flights it made
  /// the delay and the attitude worse (docs/transfer-alignment.md), so it is an option.
  double master_fit_window_s = 0.0;
  /// Lever arm from the master's reference point to the slave IMU, master body axes (m).
  Eigen::Vector3d lever_arm_b_m = Eigen::Vector3d::Zero();
  /// Time after the start excluded from the RMS / max alignment errors (convergence), s.
  double settle_s = 20.0;
  /// Batch: slave states every this many seconds (a master record near each), s.
  double batch_state_interval_s = 0.1;
  int batch_max_iterations = 30;
  /// The history filter (history_filter.h) keeps the slave's past over this span, s: the
  /// largest delay it can match. A record whose data time (tag - tau) falls before the kept
  /// history is not used (counted and reported).
  double history_window_s = 1.0;
};

/// Reads a YAML file (keys = the member names above, or the people-unit key named beside a
/// member; lever_arm_b_m as [x, y, z]).
TransferConfig LoadTransferConfig(const std::string& path);
TransferConfig ParseTransferConfig(const std::string& yaml_text, const std::string& file);

}  // namespace navtwin::transfer
