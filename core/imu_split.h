// Splitting an IMU sample at a time inside its interval, so that states and measurements
// can sit at times between IMU samples (GNSS epochs rarely fall on IMU time tags).
// Assumes constant angular rate and specific force over the sample (the increments split
// in proportion to time), which is the best a single increment allows.
#pragma once

#include <stdexcept>
#include <utility>

#include "core/types.h"

namespace navtwin {

/// Splits `s` (interval (s.t_s - s.dt_s, s.t_s]) at t_split_s strictly inside it into
/// (first, second): first ends at t_split_s, second at s.t_s. Throws std::invalid_argument
/// when t_split_s is not strictly inside the interval.
inline std::pair<ImuSample, ImuSample> SplitImuSample(const ImuSample& s, double t_split_s) {
  const double t0 = s.t_s - s.dt_s;
  if (!(t_split_s > t0 && t_split_s < s.t_s)) {
    throw std::invalid_argument("SplitImuSample: split time outside the sample interval");
  }
  const double a = (t_split_s - t0) / s.dt_s;
  ImuSample first = s, second = s;
  first.t_s = t_split_s;
  first.dt_s = t_split_s - t0;
  first.dtheta_b_rad = a * s.dtheta_b_rad;
  first.dv_b_mps = a * s.dv_b_mps;
  second.dt_s = s.t_s - t_split_s;
  second.dtheta_b_rad = s.dtheta_b_rad - first.dtheta_b_rad;
  second.dv_b_mps = s.dv_b_mps - first.dv_b_mps;
  return {first, second};
}

}  // namespace navtwin
