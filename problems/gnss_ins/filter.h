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
//    (problems/gnss_ins/error_dynamics.h);
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

#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

// ins_state.h first: config.h uses InsState without including it.
#include "problems/gnss_ins/ins_state.h"
// (keep this order)
#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/inputs.h"
#include "problems/gnss_ins/solution.h"

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
  /// filter.epochs (P_post) and rts->epochs (smoothed); filled only when RunFilter is asked
  /// to keep them (consistency checks).
  std::vector<Eigen::MatrixXd> filter_covariances;
  std::vector<Eigen::MatrixXd> rts_covariances;
  /// Per measurement kind (the keys of Solution::counts).
  std::map<std::string, InnovationStats> innovations;
};

/// Runs the error-state filter over the inputs (and the RTS smoother when run_rts).
/// `output` (may be empty) is called with the real-time (causal) state and std at the
/// output epochs: every IMU epoch, or decimated to config.output_rate_hz (the IMU epoch
/// nearest each point of the grid k / output_rate_hz); its std comes from the covariance
/// at the end of the last covariance group (at most covariance_interval_s old).
/// Progress (about every 5 % of the record) on `progress` if not null.
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
                       bool keep_covariances = false);

/// The initial error-state standard deviations (n = 15 or 21) from config.init.std, where
/// a zero bias / scale-factor entry is replaced by the ImuNoise value (*_std), and with a
/// heading search (static alignment, kSearch) the heading's (phi_D) is the search's,
/// HeadingSearchYawStd (heading_search.h).
Eigen::VectorXd InitialStdVector(const GnssInsConfig& config, int n);

/// Where the filter starts (problems/gnss_ins/filter_support.cc).
struct FilterStart {
  InsState state;  ///< the initial nominal state at state.nav.t_s
  /// Whether measurements tagged exactly at the start time are used (kGiven), or were
  /// used to make the state (alignment, GNSS velocity) and are skipped.
  bool use_measurements_at_start = true;
};

/// The initial state per config.init.source (see RunFilter); a heading search reports on
/// `progress` when not null (it is deterministic: every call picks the same heading).
/// Throws InputError when the inputs hold no data to initialise from (no IMU samples; no
/// GNSS fix for the alignment's position; no magnetometer sample for its heading; no GNSS
/// epoch after it for a heading search; no fast enough GNSS velocity; IMU data not
/// static), std::invalid_argument for kGiven without a state or a magnetometer heading
/// with mag.mode off.
FilterStart InitialFilterState(const Inputs& inputs, const GnssInsConfig& config,
                               std::ostream* progress = nullptr);

/// Covariance propagation over one covariance group: P <- Phi P Phi^T + Qd with Phi and Qd
/// as DiscreteErrorDynamics (error_dynamics.h) defines them, Phi = I + F dt + (F dt)^2 / 2,
/// Qd = (Phi G Qc G^T Phi^T + G Qc G^T) dt / 2, F, G, Qc from ErrorDynamicsF/G/Qc at x, but
/// computed in fixed-size blocks that use the model's structure: with the error state split
/// into navigation (pos, vel, att: 9) and IMU errors (6 or 12), F = [[Fnn, Fns], [0, Fss]]
/// (IMU errors are driven by themselves only) and G Qc G^T = blockdiag(Qn, Qs) (white
/// sensor noise into the navigation rows, the bias driving noise into the IMU-error rows;
/// G's IMU-error block is I). About 10 times faster than the dense 15 x 15 products; the
/// tests check it against DiscreteErrorDynamics and ErrorStateKalmanFilter::Predict. When
/// phi_acc is not null, *phi_acc <- Phi * phi_acc (phi_acc must be block upper triangular
/// in the same split, as every product of such transitions is). n = P->rows() (15 or 21).
void PropagateCovariance(const InsState& x, const Eigen::Vector3d& f_b_mps2,
                         const Eigen::Vector3d& omega_ib_b_radps, const ImuNoise& noise, double dt_s,
                         Eigen::MatrixXd* P, Eigen::MatrixXd* phi_acc);

/// sigma = max(file sigma, floor) per axis, or max(fallback, floor) where the file gives
/// none (NaN): the GNSS sigmas the filter uses.
Eigen::Vector3d MeasurementSigma(const Eigen::Vector3d& file_sigma, double floor, double fallback);

/// ZUPT detection: the vehicle is still when, over the last window_s of IMU samples
/// (bias-corrected, body axes), every |omega| = |dtheta| / dt stays at or below
/// gyro_threshold_radps and the standard deviation of |f| = |dv| / dt stays at or below
/// accel_std_threshold_mps2. Samples are added in time order.
class StillnessDetector {
 public:
  explicit StillnessDetector(const ZuptConfig& config) : config_(config) {}
  void Add(const ImuSample& s);
  /// Whether the samples cover the whole window and satisfy both thresholds.
  bool Still() const;

 private:
  struct Entry {
    double begin_s;   ///< start of the sample's interval
    double f_mps2;    ///< |f| - 9.8 (offset so that the sums of squares do not cancel)
    bool moving;      ///< |omega| above the threshold
  };
  ZuptConfig config_;
  std::deque<Entry> window_;
  int moving_ = 0;
  double sum_ = 0.0, sum_sq_ = 0.0;
  bool full_ = false;
};

/// A magnetometer sample with the hard- and soft-iron calibration removed:
/// (I + S)^-1 (m - h) (config.h, MagConfig).
Eigen::Vector3d CalibrateMag(const Eigen::Vector3d& m_raw_uT, const MagConfig& mag);

}  // namespace navtwin::gnss_ins
