// The check every trajectory gets: the strapdown mechanization on the trajectory's exact
// increments must reproduce its truth. Returns the largest errors over the run.
#pragma once

#include <algorithm>
#include <memory>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/sim/analytic_trajectory.h"
#include "core/strapdown.h"

namespace navtwin::testing {

struct SynthesisRoundTrip {
  double max_position_m = 0.0;
  double max_velocity_mps = 0.0;
  double max_attitude_deg = 0.0;  ///< |attitude error| (rotation angle)
  double t_end_s = 0.0;           ///< time of the last truth sample
};

inline SynthesisRoundTrip MechanizeExactIncrements(const sim::AnalyticTrajectory& trajectory,
                                                   const wgs84::Geodetic& start, double rate_hz,
                                                   double duration_s) {
  std::unique_ptr<Strapdown> ins;
  SynthesisRoundTrip r;
  sim::SynthesizeImu(trajectory, start, rate_hz, duration_s,
                     [&](const ImuSample& imu, const NavState& truth) {
                       r.t_end_s = truth.t_s;
                       if (!ins) {
                         ins = std::make_unique<Strapdown>(truth);
                         return;
                       }
                       ins->Update(imu);
                       const NavState& s = ins->state();
                       const Eigen::Vector3d dp = wgs84::GeodeticToNed(
                           {s.lat_rad, s.lon_rad, s.h_m}, {truth.lat_rad, truth.lon_rad, truth.h_m});
                       r.max_position_m = std::max(r.max_position_m, dp.norm());
                       r.max_velocity_mps = std::max(r.max_velocity_mps, (s.v_n_mps - truth.v_n_mps).norm());
                       r.max_attitude_deg = std::max(
                           r.max_attitude_deg, AttitudeError(truth.q_n_b, s.q_n_b).norm() * kRadToDeg);
                     });
  return r;
}

}  // namespace navtwin::testing
