// Scoring a navigation solution against a reference (docs/gnss-ins.md "Scoring").
//
// The solution (a stream of states with their error-state std, ins::NavEpoch, in time
// order; RunGnssIns gives every IMU epoch whatever the output rate) is interpolated to each
// REFERENCE epoch inside its span (linear in position and velocity, spherical in attitude:
// InterpolateNav; the std linear like position), and the errors (estimate minus
// reference) are accumulated at the reference epochs. Reference epochs that fall on
// solution epochs are compared without interpolation.
//
// Two kinds of reference:
//  - navigation (truth, e.g. the simulator's truth.nav or any NavReader): position,
//    velocity and roll/pitch/yaw are compared, all at the IMU (body reference point);
//  - GNSS solutions (e.g. an RTK .pos file or a KF-GINS GNSS file): the reference is at
//    the antenna, so the solution's antenna position p + R_n_b l_b is compared (l_b the
//    antenna lever arm); velocity, where the file has it, is compared as v_n of the
//    solution (the lever-arm term R_n_b (omega x l_b), a few cm/s at most for a lever arm
//    under a metre, is neglected); no attitude.
// With injected outages, the errors are also split into outside / inside the outages,
// and each outage gets its maximum horizontal and vertical error ("drift"); the drifts'
// RMS over the outages summarises them.
//
// Each compared epoch also gets the sigma of its errors (ScoredEpoch):
//  - position N, E, D and velocity N, E, D: the solution's error-state std (ins_state.h);
//    for a GNSS reference the antenna position's sigma is taken as the IMU position's
//    (the lever-arm term of the attitude sigma, |l_b| sigma_phi, is below a millimetre
//    for the lever arms and attitude sigmas of interest, and is neglected);
//  - roll, pitch, yaw: from the std of phi_n (sigma_N, sigma_E, sigma_D) with the
//    solution's heading psi: yaw sigma = sigma_D; roll about the body x axis projected to
//    level, (cos psi, sin psi, 0): sigma_roll^2 = cos^2 psi sigma_N^2 + sin^2 psi sigma_E^2;
//    pitch about (-sin psi, cos psi, 0): sigma_pitch^2 = sin^2 psi sigma_N^2 + cos^2 psi
//    sigma_E^2 (diagonal std only, the N-E covariance is not kept; first order in roll
//    and pitch, so a fair mapping for a near-level attitude);
//  - the reference's own sigma where it has one (GNSS files: position, and velocity
//    when given); err/sigma uses sigma^2 = sigma_est^2 + sigma_ref^2 (a reference
//    without sigma, e.g. simulated truth, counts as exact).
// ConsistencyStats accumulates RMS(err/sigma) per component (1 for honest sigmas) and the
// mean position NEES from the diagonal sigmas only, sum_i (e_i / sigma_i)^2 over N, E, D
// (expected value 3; the N-E-D covariances are not kept). An epoch whose sigma of a
// component is NaN (not computed) or zero is left out of that component and counted as
// such (ConsistencyStats::missing).
// Every compared epoch goes to the OnEpoch sink; RunGnssIns writes them to
// <out_dir>/<method>/errors.csv, one row each: t_s, the nine errors (estimate minus
// reference; m, m/s, deg), their nine solution sigmas, in_outage, and for a GNSS reference
// the reference's position and velocity sigmas (layout in output.h, ErrorsCsvWriter).
#pragma once

#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/io/sample_reader.h"
#include "problems/gnss_ins/ins_vocabulary.h"
#include "problems/ins/nav_error.h"

namespace navtwin::gnss_ins {

struct OutageDrift {
  double start_s = 0.0;
  double end_s = 0.0;
  std::size_t epochs = 0;         ///< reference epochs compared inside the outage
  double max_horizontal_m = 0.0;  ///< max |error N, E| over the outage
  double max_vertical_m = 0.0;    ///< max |error D|
};

/// Number of compared components: position N, E, D; velocity N, E, D; roll, pitch, yaw.
constexpr int kScoredComponents = 9;

/// One compared reference epoch: the errors (estimate minus reference) and their sigmas,
/// SI units (m, m/s, rad), component order as NavErrorStats. NaN where there is none:
/// err where the reference lacks the component (GNSS: attitude, velocity when absent),
/// sol_std where the estimator computed none, ref_std where the reference has none.
struct ScoredEpoch {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  double t_s = 0.0;
  std::array<double, kScoredComponents> err;
  std::array<double, kScoredComponents> sol_std;  ///< the solution's sigma (see above)
  std::array<double, kScoredComponents> ref_std;  ///< the reference's sigma
  bool in_outage = false;
  ScoredEpoch() {
    err.fill(kNaN);
    sol_std.fill(kNaN);
    ref_std.fill(kNaN);
  }
  /// sqrt(sol_std^2 + ref_std^2), the reference's part taken as 0 where it has none;
  /// NaN when sol_std is NaN.
  double CombinedStd(int c) const;
};

/// err/sigma per component and the diagonal position NEES over the epochs added.
class ConsistencyStats {
 public:
  void Add(const ScoredEpoch& e);
  std::size_t epochs() const { return epochs_; }
  /// Epochs that entered component c's ratio (finite error, combined sigma > 0).
  std::size_t count(int c) const { return count_[c]; }
  /// Epochs with an error of component c but no usable sigma (NaN or 0): left out.
  std::size_t missing(int c) const { return missing_[c]; }
  /// sqrt(mean((err / sigma)^2)) over count(c) epochs; NaN when none.
  double RmsRatio(int c) const;
  /// Epochs with finite position errors and sigmas in all of N, E, D.
  std::size_t nees_count() const { return nees_count_; }
  /// Mean of sum_{N,E,D} (e_i / sigma_i)^2 (diagonal only); 3 when consistent; NaN when none.
  double PosNeesMean() const;
  static constexpr double kPosNeesExpected = 3.0;

 private:
  std::size_t epochs_ = 0;
  std::array<std::size_t, kScoredComponents> count_{};
  std::array<std::size_t, kScoredComponents> missing_{};
  std::array<double, kScoredComponents> sum_sq_{};
  std::size_t nees_count_ = 0;
  double nees_sum_ = 0.0;
};

struct ScoreReport {
  bool has_velocity = true;  ///< false: the reference has no velocity (entries 3-5 are 0)
  bool has_attitude = true;  ///< false: GNSS reference (entries 6-8 are 0)
  NavErrorStats all;         ///< every compared reference epoch
  NavErrorStats outside;     ///< outside the outages (== all without outages)
  NavErrorStats inside;      ///< inside the outages
  /// The reference carries its own sigma (a GNSS file); ScoredEpoch::ref_std is filled.
  bool reference_has_std = false;
  ConsistencyStats consistency_all;      ///< err/sigma over every compared epoch
  ConsistencyStats consistency_outside;  ///< outside the outages
  ConsistencyStats consistency_inside;   ///< inside the outages
  std::vector<OutageDrift> outages;  ///< outages with at least one compared epoch
  double outage_horizontal_rms_m = std::numeric_limits<double>::quiet_NaN();  ///< RMS of max_horizontal_m
  double outage_vertical_rms_m = std::numeric_limits<double>::quiet_NaN();    ///< RMS of max_vertical_m
};

class TrajectoryScorer {
 public:
  using Intervals = std::vector<std::pair<double, double>>;  ///< [start, end) outages

  /// Navigation reference (truth).
  TrajectoryScorer(std::unique_ptr<NavReader> reference, Intervals outages);
  /// GNSS reference at the antenna, lever arm l_b from the IMU in body axes.
  TrajectoryScorer(std::unique_ptr<GnssReader> reference, Intervals outages,
                   const Eigen::Vector3d& lever_arm_b_m);
  ~TrajectoryScorer();
  TrajectoryScorer(const TrajectoryScorer&) = delete;
  TrajectoryScorer& operator=(const TrajectoryScorer&) = delete;

  /// The next solution state with its error-state std (empty or NaN entries: not
  /// computed); times must increase (throws std::invalid_argument).
  void Add(const NavEpoch& solution);
  /// Called with every compared reference epoch, in time order (e.g. errors.csv).
  void OnEpoch(std::function<void(const ScoredEpoch&)> sink);
  /// True for a GNSS reference (its files carry sigmas): ScoredEpoch::ref_std is filled.
  bool reference_has_std() const;
  /// The report so far (after the last Add).
  ScoreReport Report() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Opens `path` as a reference by its detected format: RTKLIB .pos and KF-GINS GNSS
/// files are GNSS references (with lever_arm_b_m), anything else a navigation reference.
std::unique_ptr<TrajectoryScorer> OpenReference(const std::string& path,
                                                TrajectoryScorer::Intervals outages,
                                                const Eigen::Vector3d& lever_arm_b_m);

}  // namespace navtwin::gnss_ins
