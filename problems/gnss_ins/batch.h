// The full-batch GNSS/INS/magnetometer smoother (Ceres): one nonlinear least-squares
// problem over the whole record, started from another solution (the filter's or the RTS
// smoother's knots). The model is the filter's (DESIGN.md "one model, two estimators"):
// the same measurement functors (factors/*.h), with the IMU between states by
// preintegration (factors/imu_preintegration.h, docs/imu-preintegration.md).
//
// States (parameter blocks per state, ins_state.h error-state layout in the tangent):
//   pos {lat_rad, lon_rad, h_m} (PositionManifold, tangent dp_ned_m), v_n_mps (3),
//   q_n_b (x, y, z, w; AttitudeManifold, tangent phi_n_rad), bg_radps (3), ba_mps2 (3)
// at the first knot of `start`, at every GNSS epoch after it (after outage removal), and
// in between wherever two of these are more than config.batch.max_state_interval_s apart
// (outages, a late first fix, the tail of the IMU record), equally spaced. With
// config.batch.state_interval_s > 0 the GNSS epochs are thinned to at least that spacing
// (the epochs between two states are not used; counted as rejected).
// A bias whose process has no noise (correlation time infinite, or zero steady-state std)
// is one block shared by all states (a random constant), held constant when its initial
// std is zero too.
//
// Residuals (all whitened):
//  - IMU preintegration between consecutive states, linearised at the initial biases of
//    state i; samples split at the state times (core/imu_split.h) and corrected for the
//    start solution's scale factors (the batch estimates none);
//  - BiasGaussMarkov between consecutive bias blocks (ImuNoise stds, correlation time);
//  - the aiding sources' residuals (gnss_ins/sources.h; problems/ins/sources/*.h say each
//    one's rule: GNSS at its states with the Huber loss of config.batch.huber_k sigmas,
//    magnetometer and barometer samples carried to their nearest states, ZUPT at the still
//    states, NHC at the moving ones) and priors on the sources' auxiliary parameters;
//  - priors on the first state from config.init.std (InitialStdVector), centred on the
//    filter's initial state when it starts at the same time, else on the first knot.
// Solved with sparse normal Cholesky (SuiteSparse, solvers/batch_driver.h). Where a
// solved gyro bias moved from its preintegration's linearisation point by more than the
// threshold (config.batch.relinearize_bias_radps; 0: |dbg| dt > 0.1 ARW sqrt(dt), a tenth
// of the interval's angle noise) the interval is reintegrated and the problem solved again,
// at most kMaxReintegrationRounds times. (The accelerometer bias needs none: the
// increments are linear in it, the first-order correction is exact.)
// Standard deviations: the diagonal blocks of the covariance by selected inversion
// (ComputeBlockDiagonalCovariance); entries of blocks that are not observable are NaN.
#pragma once

#include <ostream>
#include <vector>

#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/initial_state.h"
#include "problems/gnss_ins/inputs.h"
#include "problems/gnss_ins/solution.h"

namespace navtwin::gnss_ins {

/// Reintegrate-and-solve rounds after the first solve, at most.
constexpr int kMaxReintegrationRounds = 3;

/// Full-batch smoother over the whole record: states at every GNSS epoch (and at least
/// every config.batch.max_state_interval_s, e.g. in outages), started from `start` (the
/// filter's or RTS knots, increasing in time; the initial values are mechanized from the
/// latest knot at or before each state with that knot's IMU-error estimates). Method
/// "batch": epochs = the states with their 15 standard deviations (ins_state.h layout;
/// empty when config.batch.covariance is false), counts per measurement kind, per source
/// residual block its chi-square at the solution (measurement_residuals), run time
/// (setup, solve and covariance), solver_report = Ceres' brief report of every solve plus
/// the reintegration and covariance notes. Progress lines on `progress` when not null.
/// Throws std::invalid_argument for an empty or unordered start, a start outside the IMU
/// record, non-positive ARW or VRW, or kVector magnetometer mode without a field.
Solution RunBatch(const Inputs& inputs, const GnssInsConfig& config, const Solution& start,
                  std::ostream* progress);

/// The same with the filter's initial state given (InitialFilterState, run once before the
/// filter): the prior on the first state is centred on it when it starts at the same time
/// (null: computed here, as above).
Solution RunBatch(const Inputs& inputs, const GnssInsConfig& config, const Solution& start,
                  const FilterStart* initial, std::ostream* progress);

/// The state epochs RunBatch uses from t0_s (the start's first knot) to t_end_s (the end
/// of the IMU record): t0, the GNSS epochs in (t0, t_end] (thinned to
/// config.batch.state_interval_s when positive; a GNSS epoch within 1 us of t0 is t0's),
/// and equally spaced fill-in states wherever two consecutive ones, or the last one and
/// t_end, are more than config.batch.max_state_interval_s apart (the fill of the tail ends
/// at t_end). Increasing.
std::vector<double> BatchStateTimes(const Inputs& inputs, const GnssInsConfig& config, double t0_s,
                                    double t_end_s);

}  // namespace navtwin::gnss_ins
