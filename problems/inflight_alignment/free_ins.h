// Inputs of the in-flight alignment and the free INS that equation 8 needs.
//
// The heading error rotates the displacement an INS integrates; once a filter feeds GPS
// corrections back into the INS, its position error no longer shows that rotation. So the
// distance method and the batch both take the distance error from a FREE INS: the same
// mechanization from the same initial state, never corrected horizontally, with only the
// barometric loop on the vertical channel (whose Coriolis coupling would otherwise put
// metres into the east position). Its error against GPS is the heading's rotation of the
// gained displacement plus the Schuler part (distance_heading.h); see
// docs/inflight-alignment.md, "The free INS".
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/strapdown.h"
#include "core/types.h"
#include "problems/inflight_alignment/config.h"
#include "problems/inflight_alignment/distance_heading.h"
#include "problems/inflight_alignment/inputs.h"

namespace navtwin::inflight {

/// Second-order vertical loop (critically damped, time constant tau): after each
/// strapdown step, with e = h_baro - h_ins,
///     h += 2 e dt / tau,   v_D -= e dt / tau^2
/// (the INS's own v_D integrates the rest). Stable for dt << tau.
void ApplyBaroLoop(double baro_altitude_m, double dt_s, const BaroLoopOptions& options, NavState* nav);

/// Yaw (rad, (-pi, pi]) of a navigation state's attitude.
double YawOf(const NavState& nav);

/// The free INS and, at each GPS fix, the sample of equation 8: time since the start,
/// the GAINED displacement D(t) = integral of (v_free - v0) (v0 the initial INS velocity:
/// an INS initialised in flight rotates only the velocity it gains; an INS started at
/// rest has v0 = 0), and the distance error, free INS minus GPS, north and east metres in
/// the curvilinear frame of the start point (NorthEastFromStart). It also keeps the path
/// length flown (integral of the horizontal speed), which is what thresholds and the
/// "heading error at 10 km" figures use.
class FreeInsTrack {
 public:
  FreeInsTrack(const NavState& initial, const BaroLoopOptions& baro);

  /// One IMU sample (time-ordered, after the initial state); baro_altitude_m may be NaN
  /// (height held).
  void Update(const ImuSample& imu, double baro_altitude_m);
  /// The equation-8 sample for a GPS fix at t_fix_s (call right after the Update that
  /// reached or passed the fix's time; the INS position and the gained displacement are
  /// moved back to t_fix_s with the current velocity).
  DistanceErrorSample SampleAt(double t_fix_s, const wgs84::Geodetic& gps_position) const;

  const NavState& state() const;
  double path_length_m() const { return path_length_m_; }
  const DistanceFlown& gained() const { return gained_; }
  const wgs84::Geodetic& start() const { return start_; }

 private:
  Strapdown ins_;
  BaroLoopOptions baro_;
  wgs84::Geodetic start_;
  Eigen::Vector3d v0_n_mps_;
  DistanceFlown gained_;
  double path_length_m_ = 0.0;
  double last_t_s_ = 0.0;
  Eigen::Vector2d last_v_ne_mps_;
};

/// One GPS epoch of the free INS run: the equation-8 sample plus what reports need.
struct FreeInsEpoch {
  DistanceErrorSample sample;  ///< t_s is time since initial.t_s
  double t_s = 0.0;            ///< absolute time of the fix
  double path_length_m = 0.0;
  double yaw_free_rad = 0.0;   ///< the free INS's yaw at the fix
};

/// Runs the free INS over all inputs against the RAW GPS fixes (the batch's input): one
/// epoch per fix inside the IMU span, the INS stepped to the first IMU epoch at or after
/// the fix (IMU at 100 Hz: at most 10 ms late; a fix between IMU epochs is compared with
/// the INS position moved back by v dt).
std::vector<FreeInsEpoch> RunFreeIns(const InflightInputs& inputs, const InflightConfig& config);

/// Position sigma per horizontal axis (m) of raw GPS fixes from their third differences,
/// robust to outliers: 1.4826 * median|d| / sqrt(20) over the fixes (taken per axis,
/// the larger returned). Throws std::invalid_argument with fewer than 8 fixes.
double EstimateGpsSigma(const std::vector<GnssSample>& gnss);

}  // namespace navtwin::inflight
