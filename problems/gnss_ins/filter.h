// The GNSS/INS/magnetometer navigation filter: an error-state Kalman filter with feedback
// (solvers/eskf.h) around the strapdown mechanization (core/strapdown.h), and the RTS
// smoother (solvers/rts.h) over its stored epochs ("knots").
//
// Time line (docs/gnss-ins.md):
//  - the nominal state is mechanized at every IMU sample on the sample corrected with the
//    current IMU-error estimate, dtheta_c = (dtheta - bg dt) / (1 + sg), dv_c likewise;
//  - the covariance is propagated over groups of samples at most
//    FilterConfig::covariance_interval_s long: Phi, Qd from the error dynamics at the
//    group's last sample with the group's mean corrected f_b and omega_ib_b
//    (problems/ins/error_dynamics.h);
//  - a GNSS epoch between two IMU time tags splits the IMU sample there (core/imu_split.h):
//    nominal state and covariance are propagated to exactly the GNSS time, updated, and the
//    rest of the sample follows with the corrected IMU errors. Magnetometer and barometer
//    samples are used at the first IMU epoch at or after their time, ZUPTs at IMU epochs;
//  - every measurement is the batch smoother's residual functor (factors/*.h) linearised in
//    the error-state tangent (solvers/linearize.h): y = -r, H = dr/d(dx), R = I; each
//    accepted update is fed back at once (the next one is linearised at the corrected
//    state);
//  - a knot is stored after every update epoch and at least every
//    FilterConfig::store_interval_s: the post-update state, P before and after the epoch's
//    updates, the transition since the previous knot (product of the group transitions) and
//    the sum of the corrections fed back there. The RTS smoother runs over these knots.
#pragma once

#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/initial_state.h"
#include "problems/gnss_ins/inputs.h"
#include "problems/gnss_ins/solution.h"
#include "problems/ins/aiding.h"
#include "problems/gnss_ins/ins_vocabulary.h"

namespace navtwin::gnss_ins {

/// Innovations of one measurement kind over a run, updates rejected by the gate included:
/// the terms of their Gaussian log-likelihood, -2 log L = sum (NIS + log det S + m log 2 pi),
/// S = H P H^T + I (whitened). The heading search (heading_search.h) scores with it.
struct InnovationStats {
  std::size_t updates = 0;   ///< accepted and rejected
  std::size_t rejected = 0;  ///< by the chi-square gate
  double nis = 0.0;          ///< sum of NIS over the accepted updates
  int dof = 0;               ///< sum of their dimensions m (a consistent filter: E[nis] = dof)
  double nis_capped = 0.0;   ///< sum of min(NIS, gate) over every update (a rejected one costs the gate)
  double log_det_s = 0.0;    ///< sum of log det S over every update
};

struct FilterResult {
  /// Method "filter": the knots (post-update states after every update epoch and at least
  /// every FilterConfig::store_interval_s, plus the start and the end of the run) with
  /// std = sqrt(diag P_post).
  Solution filter;
  /// Method "rts" when requested: the same knots smoothed, std = sqrt(diag P_smoothed).
  /// Its run_time_s is the filter's plus the backward pass.
  std::optional<Solution> rts;
  /// Not computed by RunFilter (it has no truth); tests/problems/gnss_ins/nees_test.cc
  /// computes the NEES from the covariances below.
  double nees_mean = std::numeric_limits<double>::quiet_NaN();
  /// Full error-state covariances (n x n, ins_state.h layout), one per knot in the order of
  /// filter.epochs (P_post) and rts->epochs (smoothed); filled only with
  /// FilterKnots::kAllWithCovariances (consistency checks).
  std::vector<Eigen::MatrixXd> filter_covariances;
  std::vector<Eigen::MatrixXd> rts_covariances;
  /// Per measurement kind (the keys of Solution::counts).
  std::map<std::string, InnovationStats> innovations;
};

/// What RunFilter keeps of its knots.
enum class FilterKnots {
  kAll,                 ///< every knot in filter.epochs (the RTS smoother needs them)
  kAllWithCovariances,  ///< and their full covariances (filter_covariances, rts_covariances)
  /// Only the last knot (filter.epochs holds one, Solution::knots_not_kept counts the
  /// others): memory independent of the record's length. Not with run_rts.
  kLast,
};

/// Runs the error-state filter over the inputs (and the RTS smoother when run_rts).
/// `output` (may be empty) is called with the real-time (causal) state and std at every
/// IMU epoch (config.output_rate_hz is the caller's: RunGnssIns decimates for its files
/// with OutputDecimator, densify.h, and scores every epoch); the epoch passed is reused
/// between calls (copy what you keep). Its std comes from the covariance at the end of
/// the last covariance group (at most covariance_interval_s old).
/// Progress (about every 5 % of the record) on `progress` if not null.
/// `knots` (FilterKnots) says what is kept besides what the RTS smoother needs;
/// std::invalid_argument for kLast with run_rts.
/// Initialisation per config.init.source (kGiven: config.init.state at its time, IMU
/// errors from config.init.imu_errors when any is non-zero, else from the state;
/// kStaticAlignment: coarse alignment over the first static_duration_s of IMU data,
/// heading per config.init.heading (kSearch: SearchHeading, heading_search.h, reporting
/// the hypotheses' scores on `progress`), position from the first GNSS fix, velocity zero;
/// kGnssVelocity: at the first GNSS fix with velocity and horizontal speed >=
/// min_speed_mps). Initial covariance diag(InitialStdVector(config, n))^2, n = 15, or 21
/// with config.filter.scale_factors.
/// Throws InputError for input the filter finds wrong (a GNSS fix farther than
/// config.gnss.max_distance_m from the INS prediction: the GNSS file and the epoch time;
/// no data to initialise from), std::invalid_argument for an unusable configuration
/// (kGiven without a state, kVector magnetometer mode without a field).
FilterResult RunFilter(const Inputs& inputs, const GnssInsConfig& config, bool run_rts,
                       const std::function<void(const NavEpoch&)>& output, std::ostream* progress,
                       FilterKnots knots = FilterKnots::kAll);

/// The filter from a given start (InitialFilterState, run before it): the same as above
/// without the alignment step.
FilterResult RunFilter(const Inputs& inputs, const GnssInsConfig& config, const FilterStart& start,
                       bool run_rts, const std::function<void(const NavEpoch&)>& output,
                       std::ostream* progress, FilterKnots knots = FilterKnots::kAll);

}  // namespace navtwin::gnss_ins
