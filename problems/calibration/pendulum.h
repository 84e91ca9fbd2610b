// Pendulum IMU calibration (issue 8 item 3, seed 001 section 3; docs/calibration-pendulum.md).
//
// The IMU is the bob of a pendulum (the simulator's rig, core/sim/calibration_rig.h: pivot
// axis east, bob frame p = NED at theta = 0, R_n_p = Ry(theta), R_n_b = Ry(theta) R_p_b,
// the IMU at length L below the pivot) whose angle theta a pivot encoder records.
//
//  1. Swing fit, per run: theta'' + c1 theta' + c2 sin(theta) = 0, unknowns (c1, c2, theta0,
//     theta'0) at the record's first time, the ODE integrated by RK4 through the samples;
//     Ceres least squares on the angle residuals (started from the zero crossings and the
//     amplitude decay, the window grown from eight periods to the whole record so that the
//     phase never slips a cycle); covariance from ceres::Covariance scaled by the residual
//     variance (the encoder noise is estimated, not assumed).
//  2. Truth from the fitted solution (never from differentiated angles): over every IMU
//     interval the exact integrals of
//       omega_ib_b = theta' a_b + R_b_p Ry(theta)^T (omega_ie_n + omega_en_n)
//       f_b        = R_b_p [ (L theta'' + g sin(theta), 0, -L theta'^2 - g cos(theta))
//                            + Ry(theta)^T (2 omega_ie_n x v_n) ]
//     (a_b = R_b_p e_y the pivot axis in IMU axes, v_n = L theta' (cos, 0, -sin)), which need
//     only the changes of theta, theta', sin and cos and the integrals of sin(theta),
//     cos(theta), theta'^2 -- integrated with the ODE by the same RK4.
//  3. The error model of core/imu_error_model.h is linear in its parameters given the truth:
//     per axis, y_k - u_k,r = x_k^T p over the mean rates of each interval (increment / dt,
//     rows weighted by dt: white increment noise has variance proportional to dt; the rows
//     are derived from the model itself, detail::AxisProblems below). Linear
//     least squares per axis (accel: s, two misalignments, bias; gyro: s, two
//     misalignments, bias, a row of G), covariance s^2 (A^T A)^-1 with the a-posteriori
//     residual variance s^2 of that axis, plus the swing fits' uncertainty propagated
//     through the solution (each run's fit covariance, central differences along its
//     Cholesky columns). Parameters whose regressor the runs never excite (no specific
//     force or rotation along an axis) or that are a combination of the others are
//     reported in `unobservable` and held at 0.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/types.h"
#include "problems/calibration/imu_calibration.h"

namespace navtwin::calibration {

/// A pivot-encoder record: strictly increasing times (s) and the angle (rad).
struct AngleRecord {
  std::vector<double> t_s;
  std::vector<double> theta_rad;
  std::string path;  ///< for messages
};

/// Reads a CSV angle file with the header t_s,theta_rad (or theta_deg; docs/formats.md).
/// Throws InputError naming the file, line and field (missing column, not a number, NaN,
/// time not increasing, no rows).
AngleRecord ReadAngleFile(const std::string& path);

/// The swing fitted to an angle record.
struct SwingFit {
  double t0_s = 0.0;  ///< the record's first time: theta0, rate0 hold there
  double c1_per_s = 0.0;
  double c2_per_s2 = 0.0;
  double theta0_rad = 0.0;
  double rate0_radps = 0.0;
  /// Covariance of (c1, c2, theta0, rate0), scaled by the residual variance.
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();
  double residual_rms_rad = 0.0;  ///< the encoder noise as the fit sees it
  int samples = 0;
  double c1_sigma() const;
  double c2_sigma() const;
};

/// Fits the swing. Throws std::runtime_error naming the file when the record holds less
/// than one full period (fewer than three zero crossings) or too few samples per period.
SwingFit FitSwing(const AngleRecord& angle);

/// The fitted solution (theta, theta', theta'') at times t >= t0 (RK4, the fit's steps).
struct SwingPoint {
  double theta_rad = 0.0;
  double rate_radps = 0.0;
  double accel_rad_s2 = 0.0;
};
std::vector<SwingPoint> EvaluateSwing(const SwingFit& fit, const std::vector<double>& t_s);

/// Where the pendulum is and how the IMU sits on it.
struct PendulumGeometry {
  double length_m = 1.0;                                       ///< pivot to IMU
  Eigen::Matrix3d mounting_p_b = Eigen::Matrix3d::Identity();  ///< R_p_b
  double latitude_rad = 0.0;
  double height_m = 0.0;
};

/// The true increments over the intervals (t - dt, t] of `intervals` (only t_s and dt_s
/// are read; intervals must lie at or after fit.t0_s, in time order) from the fitted swing:
/// step 2 above. dt_s is copied.
std::vector<ImuSample> TrueIncrements(const SwingFit& fit, const PendulumGeometry& geometry,
                                      const std::vector<ImuSample>& intervals);

struct PendulumRun {
  std::vector<ImuSample> imu;  ///< measured increments, the IMU's axes
  AngleRecord angle;           ///< on the IMU's time scale
  double length_m = 1.0;
  Eigen::Matrix3d mounting_p_b = Eigen::Matrix3d::Identity();
  std::string imu_path;  ///< for messages
};

struct PendulumData {
  std::vector<PendulumRun> runs;
  double latitude_rad = 0.0;
  double height_m = 0.0;
};

struct PendulumOptions {
  bool estimate_g_sensitivity = true;
  /// Add each run's swing-fit uncertainty to the parameter covariance (off: IMU noise only).
  bool propagate_swing_uncertainty = true;
};

/// Batch calibration over all runs (step 3). `fits`, when given, receives each run's swing.
/// Throws std::runtime_error naming what is missing (no run, a run too short to fit c1
/// and c2, no IMU samples within a run's angle record).
ImuCalibrationResult CalibratePendulum(const PendulumData& data, const PendulumOptions& options = {},
                                       std::vector<SwingFit>* fits = nullptr);

namespace detail {

/// One of the six per-axis linear problems of step 3 (accel x, y, z, gyro x, y, z), derived
/// from core/imu_error_model.h rather than written out: the model is affine in its
/// parameters and in (f, omega), so the regressor of parameter j on axis a is
///   x_j = regressors.row(i) . (f_b, omega_ib_b, 1)   (mean rates, params[i] = j)
/// with the rows the model evaluated at unit parameter vectors and unit inputs minus the
/// model at zero parameters. sum_i p(params[i]) x_i is the model (MeasuredSpecificForce /
/// MeasuredRate) at p minus the truth along axis a.
struct AxisProblem {
  std::vector<int> params;  ///< global indices (accel triad, gyro triad, G), ascending
  Eigen::Matrix<double, Eigen::Dynamic, 7, 0, 7, 7> regressors;
};

/// The six axis problems; G (the gyro rows' g-sensitivity) only when with_g.
std::vector<AxisProblem> AxisProblems(bool with_g);

}  // namespace detail

/// Reads a record {latitude_deg, height_m, runs: [{imu, angle, length_m, mounting |
/// mounting_deg}, ...]} (relative paths against the record's folder; mounting parsed as
/// the simulator's, sim::ParsePendulumMounting). Throws InputError (file, line, key).
PendulumData ReadPendulumRecord(const std::string& record_path);

}  // namespace navtwin::calibration
