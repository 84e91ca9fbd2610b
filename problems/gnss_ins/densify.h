// Dense output from an estimator's sparse states ("knots": the RTS smoother's stored
// epochs, the batch smoother's parameter epochs), at every IMU epoch (a writer decimates
// to the output rate with OutputDecimator, while the scorer sees every epoch).
//
// Between knots k and k+1 (times t_k < t_{k+1}) the IMU samples are mechanized from knot k
// with knot k's IMU-error estimates (CorrectImu), giving x_m(t); at t_{k+1} the mismatch
// to the knot, d = x_{k+1} - x_m(t_{k+1}) (latitude, longitude, height, velocity, and the
// attitude error phi = AttitudeError(q_{k+1}, q_m)), is spread linearly over the interval:
//   x(t) = x_m(t) + w d,  q(t) = Exp(w phi) q_m(t),  w = (t - t_k) / (t_{k+1} - t_k),
// so the output is continuous and passes through every knot. IMU errors and standard
// deviations are interpolated linearly between the knots. IMU samples that straddle a knot
// are split at it (core/imu_split.h). After the last knot the mechanization continues with
// the last knot's IMU errors and standard deviations to the end of the IMU record (no
// later knot to correct it); before the first knot there is no output.
#pragma once

#include <functional>

#include "problems/gnss_ins/solution.h"  // first: inputs.h -> config.h needs InsState
#include "problems/gnss_ins/inputs.h"

namespace navtwin::gnss_ins {

/// Chooses output epochs among IMU epochs: every epoch (rate 0), or the first IMU epoch at
/// or after each multiple of 1/rate_hz (plus the first epoch offered).
class OutputDecimator {
 public:
  explicit OutputDecimator(double rate_hz) : rate_hz_(rate_hz) {}
  /// Call once per IMU epoch, in time order; true when the epoch is an output epoch.
  bool Take(double t_s);

 private:
  double rate_hz_;
  bool first_ = true;
  long long last_tick_ = 0;
};

/// States at every IMU epoch after the first knot from a smoother's knots (see above).
/// Calls `output` in time order; the epoch passed is reused between calls (copy what you
/// keep).
void Densify(const Solution& knots, const Inputs& inputs, const std::function<void(const NavEpoch&)>& output);

}  // namespace navtwin::gnss_ins
