// Rules every aided-INS estimator applies the same way, filter and batch alike: the sigma
// of a measurement that a file may or may not give, the stillness rule (ZUPT and the
// vehicle constraints decide with it), and the motion the GNSS time-offset models take as
// known inputs.
#pragma once

#include <deque>

#include <Eigen/Core>

#include "core/types.h"

namespace navtwin::ins {

/// sigma = max(file sigma, floor) per axis, or max(fallback, floor) where the file gives
/// none (NaN).
Eigen::Vector3d MeasurementSigma(const Eigen::Vector3d& file_sigma, double floor, double fallback);

/// The stillness rule's thresholds.
struct StillnessConfig {
  double window_s = 0.5;                 ///< detection window
  double gyro_threshold_radps = 0.01;    ///< max |omega| over the window
  double accel_std_threshold_mps2 = 0.05;///< max std of |f| over the window
};

/// Zero-velocity updates where the stillness rule holds (its thresholds are the ZUPT's
/// configuration keys).
struct ZuptConfig : StillnessConfig {
  bool enabled = false;
  double std_mps = 0.02;
  double interval_s = 0.1;  ///< at most one update per this interval
};

/// Stillness detection: the vehicle is still when, over the last window_s of IMU samples
/// (bias-corrected, body axes), every |omega| = |dtheta| / dt stays at or below
/// gyro_threshold_radps and the standard deviation of |f| = |dv| / dt stays at or below
/// accel_std_threshold_mps2. Samples are added in time order.
class StillnessDetector {
 public:
  explicit StillnessDetector(const StillnessConfig& config) : config_(config) {}
  void Add(const ImuSample& s);
  /// Whether the samples cover the whole window and satisfy both thresholds.
  bool Still() const;

 private:
  struct Entry {
    double begin_s;   ///< start of the sample's interval
    double f_mps2;    ///< |f| - 9.8 (offset so that the sums of squares do not cancel)
    bool moving;      ///< |omega| above the threshold
  };
  StillnessConfig config_;
  std::deque<Entry> window_;
  int moving_ = 0;
  double sum_ = 0.0, sum_sq_ = 0.0;
  bool full_ = false;
};

/// The window of MotionWindow, in two halves of 0.1 s.
constexpr double kMotionWindow_s = 0.2;
/// MotionWindow sets an estimate to zero while its squared length is below this many times
/// its error variance summed over the axes (and shrinks it towards zero above).
constexpr double kMotionShrinkage = 2.0;

/// The IMU's motion at an epoch, as the GNSS time-offset models take it
/// (factors/gnss_installation.h BodyMotion).
struct ImuMotion {
  Eigen::Vector3d omega_ib_b_radps = Eigen::Vector3d::Zero();   ///< body angular rate
  Eigen::Vector3d alpha_ib_b_radps2 = Eigen::Vector3d::Zero();  ///< its rate of change, ~0.1 s before
  Eigen::Vector3d a_n_mps2 = Eigen::Vector3d::Zero();           ///< NED acceleration (gravity, Coriolis in)
  Eigen::Vector3d j_n_mps3 = Eigen::Vector3d::Zero();           ///< its rate of change
};

/// The mechanized IMU's motion at the end of the last kMotionWindow_s, from the velocity
/// changes of the mechanization's steps (pieces of IMU samples) and their angle increments.
/// From the mean accelerations of the halves (a1 newer, a0 older, centres c1, c0) it takes
/// the jerk j = (a1 - a0) / (c1 - c0) and the acceleration at the end t, a1 + (t - c1) j
/// (i.e. 1.5 a1 - 0.5 a0); from the mean rates likewise the angular acceleration (at the
/// midpoint, ~0.1 s before t) and the rate at t.
///
/// These are the known inputs of a regression on the time offset and the lever arm: their
/// errors would tell the estimators something about the unknowns where the motion has
/// nothing to tell (errors in variables: on a steady 60 s flight with a 0.1 m/s/sqrt(h)
/// accelerometer the time offset's sigma fell from its prior 0.2 s to 0.09 s with no
/// acceleration at all). Each estimate x with error variance s^2 per axis is therefore
/// shrunk, x (1 - kMotionShrinkage 3 s^2 / |x|^2), and zero below |x| = sqrt(3
/// kMotionShrinkage) s: noise alone passes in 11 % of the epochs (chi-square, 3 dof, above
/// 6), at a fraction of its size. s^2 is the IMU's white noise (VRW and ARW: VRW^2 / 0.1 s for
/// a half's mean) and, for the acceleration, g^2 times the variance of the mechanization's
/// tilt (a tilt error is an acceleration g times it). A true motion of that size is lost, tau
/// times it in the velocity model (a MEMS 0.849 m/s/sqrt(h): s = 0.045 m/s^2, the
/// acceleration's 0.07 m/s^2, at most 2.6 cm/s at tau = 0.15 s, where the regression learns
/// little anyway). Steps are added in time order; until both halves have steps the rates of
/// change are zero (and the rate and acceleration the newer half's mean).
class MotionWindow {
 public:
  /// White noise of the IMU (ImuNoise's ARW, rad/sqrt(s), and VRW, m/s/sqrt(s)); 0: no
  /// shrinkage.
  MotionWindow(double gyro_arw_rad_per_sqrt_s, double accel_vrw_mps_per_sqrt_s)
      : arw_(gyro_arw_rad_per_sqrt_s), vrw_(accel_vrw_mps_per_sqrt_s) {}
  /// One mechanization step: the bias-corrected IMU piece and the change of v_n over it.
  void Add(const ImuSample& corrected, const Eigen::Vector3d& dv_n_mps);
  /// The motion at the last step's end; tilt_var_rad2: the variance of the mechanization's
  /// horizontal attitude error (the larger axis).
  ImuMotion Get(double tilt_var_rad2) const;

 private:
  struct Step {
    double mid_s;
    double dt_s;
    Eigen::Vector3d dtheta_b_rad;
    Eigen::Vector3d dv_n_mps;
  };
  double arw_, vrw_;
  std::deque<Step> steps_;
  double end_s_ = 0.0;
};

}  // namespace navtwin::ins
