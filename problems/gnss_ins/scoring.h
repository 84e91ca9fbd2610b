// Scoring a navigation solution against a reference (docs/gnss-ins.md "Scoring").
//
// The solution (a stream of states in time order, usually every IMU epoch or at the
// output rate) is interpolated to each REFERENCE epoch inside its span (linear in
// position and velocity, spherical in attitude: InterpolateNav), and the errors
// (estimate minus reference) are accumulated at the reference epochs. Reference epochs
// that fall on solution epochs are compared without interpolation.
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
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/io/sample_reader.h"
#include "problems/ins/nav_error.h"

namespace navtwin::gnss_ins {

struct OutageDrift {
  double start_s = 0.0;
  double end_s = 0.0;
  std::size_t epochs = 0;         ///< reference epochs compared inside the outage
  double max_horizontal_m = 0.0;  ///< max |error N, E| over the outage
  double max_vertical_m = 0.0;    ///< max |error D|
};

struct ScoreReport {
  bool has_velocity = true;  ///< false: the reference has no velocity (entries 3-5 are 0)
  bool has_attitude = true;  ///< false: GNSS reference (entries 6-8 are 0)
  NavErrorStats all;         ///< every compared reference epoch
  NavErrorStats outside;     ///< outside the outages (== all without outages)
  NavErrorStats inside;      ///< inside the outages
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

  /// The next solution state; times must increase (throws std::invalid_argument).
  void Add(const NavState& solution);
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
