// The attitude a magnetometer calibration is judged with, and the heading error before and
// after it (`navtwin calibrate-mag`, docs/calibration-magnetometer.md): roll and pitch per
// magnetometer sample from a reference navigation record or from an IMU's accelerometer, and
// the RMS heading error of the raw and the calibrated field against the reference yaw.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/rotation.h"
#include "core/types.h"
#include "problems/calibration/mag_calibration.h"

namespace navtwin::calibration {

/// Roll, pitch and yaw (rad) of a time-sorted navigation record at t (attitude slerped
/// between the records around t); nullopt outside the record.
std::optional<Eigen::Vector3d> EulerAt(const std::vector<NavState>& nav, double t_s);

/// Roll and pitch from the mean specific force of the IMU samples whose time lies within
/// half_window_s of t (the nearest sample when none does), levelled as in
/// core/leveling_model.h; nullopt outside the IMU record.
class AccelerometerLevel {
 public:
  AccelerometerLevel(std::vector<ImuSample> imu, double half_window_s);
  std::optional<Eigen::Vector2d> At(double t_s) const;

 private:
  std::vector<ImuSample> imu_;
  double half_window_s_;
  std::vector<Eigen::Vector3d> sum_dv_mps_;  ///< prefix sums
  std::vector<double> sum_dt_s_;
};

/// Median interval between magnetometer samples (0 with fewer than two).
double MedianInterval_s(const std::vector<MagSample>& mag);

/// Heading is not scored where the x axis is within this angle of the vertical: roll and
/// heading are not separable there (and an accelerometer cannot give roll).
constexpr double kMaxHeadingPitch_rad = 80.0 * kDegToRad;

struct HeadingErrors {
  int samples = 0;
  double before_deg = std::numeric_limits<double>::quiet_NaN();  ///< RMS; NaN without a reference
  double after_deg = std::numeric_limits<double>::quiet_NaN();
};

/// RMS over the samples with a reference attitude (roll, pitch, yaw; |pitch| <= 80 deg) of
/// the wrapped heading minus the reference yaw, from the raw and from the calibrated field:
/// tilt-compensated for 3-axis fits, level (x, y only) for the 2-axis bidirectional method.
/// The planar fit leaves the component along its plane normal raw (vertical field plus that
/// axis' hard iron): its calibrated heading uses the in-plane part only, else a normal a few
/// degrees off z (soft iron tilts the plane) would leak tens of uT into x and y.
HeadingErrors MagHeadingErrors(const std::vector<MagSample>& mag,
                               const std::vector<std::optional<Eigen::Vector3d>>& reference_euler_rad,
                               const MagCalibration& c, bool two_axis, double declination_rad);

/// The reference attitude of each magnetometer sample, for the bidirectional method's tilt
/// gate and the tilt-compensated heading: from a navigation record (roll, pitch and yaw), else
/// from an IMU's accelerometer (roll and pitch), else every sample taken as level.
struct MagSampleAttitudes {
  std::string source;  ///< "truth", "imu accelerometer" or "level (assumed)"
  /// Roll, pitch, yaw per sample (nullopt outside the record); all nullopt unless from a
  /// navigation record.
  std::vector<std::optional<Eigen::Vector3d>> euler_rad;
  std::vector<std::optional<Eigen::Vector2d>> roll_pitch_rad;  ///< nullopt outside the record
};

/// EulerAt of a time-sorted navigation record at every sample.
MagSampleAttitudes AttitudesFromNav(const std::vector<MagSample>& mag, const std::vector<NavState>& nav);
/// AccelerometerLevel at every sample, averaging within half the median magnetometer interval.
MagSampleAttitudes AttitudesFromAccelerometer(const std::vector<MagSample>& mag, std::vector<ImuSample> imu);
/// Roll and pitch 0 at every sample, no yaw.
MagSampleAttitudes LevelAttitudes(const std::vector<MagSample>& mag);

}  // namespace navtwin::calibration
