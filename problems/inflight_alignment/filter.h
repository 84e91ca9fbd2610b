// The seed's in-flight alignment filter (seed 003, figure 2) and the conventional
// Kalman-only baseline, one class with one model.
//
// Error state (true minus estimate, the layout of problems/ins/ins_state.h restricted
// to the horizontal channel), 11 components:
//   [0,2) dp_NE_m   [2,4) dv_NE_mps   [4,6) phi_NE_rad (level)   [6] phi_D_rad (heading)
//   [7,9) dbg_xy_radps (gyro bias, body x, y)   [9,11) dba_xy_mps2 (accelerometer bias, body x, y)
// The dynamics are the rows and columns of ins::ErrorDynamicsF (the GNSS/INS model)
// for these states; the vertical channel is held by the barometric loop (free_ins.h).
// Measurements: smoothed GPS position (gps_smoother.h) minus INS position, north and east,
// with the smoother's measurement sigma. Every update is fed back into the INS.
//
// The two methods differ only in phi_D:
//  - kKalman: phi_D is estimated like every other state (conventional in-flight
//    alignment). The seed reports that it stalls at the limit the east gyro bias sets,
//    dbg_E / (Omega cos L) (2.84 arcmin for 0.01 deg/h at 36.5 deg). That is the limit of
//    heading from the Earth-rate coupling; an INS launched from rest with a known velocity
//    also shows the heading as the rotation of the velocity it gains, which this filter
//    uses like the distance method does (docs/inflight-alignment.md, "Results").
//  - kDistance: the seed's 10-state filter. phi_D is a CONSIDER state (Schmidt-Kalman):
//    its variance and correlations shape the gains of the other ten, but the filter never
//    updates it, so the heading-induced velocity error is corrected as velocity without
//    corrupting biases or level. The heading comes from the distance flown: a free INS
//    (free_ins.h) runs alongside; at each smoothed fix the sample (t, D, free - GPS) is
//    stored; once the path length passes DistanceMethodOptions::threshold_km (and then
//    every recompute_every_km), SeparateHeadingError with the sensor-spec priors gives
//    the free INS's heading error dH +- sigma; the INS yaw is corrected by the part not yet
//    applied, P(phi_D) is set to sigma^2 and its correlations to zero (a new, independent
//    estimate).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "problems/inflight_alignment/config.h"
#include "problems/inflight_alignment/distance_heading.h"
#include "problems/inflight_alignment/free_ins.h"

namespace navtwin::inflight {

constexpr int kFilterStates = 11;
namespace fstate {
constexpr int kPos = 0, kVel = 2, kLevel = 4, kHeading = 6, kBg = 7, kBa = 9;
}  // namespace fstate

enum class FilterMethod { kDistance, kKalman };
const char* FilterMethodName(FilterMethod method);  ///< "distance", "kalman"

/// A heading computation of the distance method.
struct HeadingComputation {
  double t_s = 0.0;
  double path_length_m = 0.0;
  double dh_rad = 0.0;           ///< the free INS's heading error (yaw_ins - yaw_true)
  double sigma_rad = 0.0;
  double correction_rad = 0.0;   ///< subtracted from the filter INS's yaw now
  HeadingSeparation separation;  ///< the fit (Schuler coefficients, condition, note)
};

/// The filter's state after one GPS fix.
struct FilterEpoch {
  double t_s = 0.0;
  double path_length_m = 0.0;
  NavState nav;                    ///< corrected INS state
  double yaw_sigma_rad = 0.0;      ///< sqrt P(phi_D)
  Eigen::Matrix<double, kFilterStates, 1> sigma;  ///< sqrt diag P after the update
  Eigen::Vector2d innovation_ne_m = Eigen::Vector2d::Zero();
  bool gps_used = false;           ///< false: the smoother rejected the fix
};

struct FilterRun {
  FilterMethod method = FilterMethod::kDistance;
  std::vector<FilterEpoch> epochs;               ///< one per GPS fix inside the IMU span
  std::vector<HeadingComputation> computations;  ///< distance method only
  std::size_t gps_rejected = 0;                  ///< fixes the smoother's gate rejected
  double run_time_s = 0.0;
};

/// Runs the filter over the inputs (ValidateInputs first). Throws InputError for bad
/// inputs and std::runtime_error if the filter diverges (non-finite state), naming the time.
FilterRun RunInflightFilter(const InflightInputs& inputs, const InflightConfig& config,
                            FilterMethod method);

}  // namespace navtwin::inflight
