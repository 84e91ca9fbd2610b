// Where the batch smoother puts its states (RunBatch, problems/gnss_ins/batch.h): at the
// first epoch, at the samples of the aiding source that anchors the states (the GNSS fixes,
// thinned to batch.state_interval_s), at the end of the record, and in between at most
// batch.max_state_interval_s apart.
#pragma once

#include <cstddef>
#include <vector>

#include "problems/gnss_ins/config.h"
#include "problems/ins/aiding.h"

namespace navtwin::gnss_ins {

/// A state epoch and, when the anchoring source placed it, the index of its sample (-1 if none).
struct PlannedState {
  double t_s;
  long anchor;
};

struct Plan {
  std::vector<PlannedState> states;
  std::vector<std::size_t> thinned;  ///< anchor samples in the span left out by state_interval_s
};

/// The sample times of the source that anchors the states (at most one; none: empty).
/// std::invalid_argument when two sources anchor them.
std::vector<double> AnchorTimes(const ins::AidingSources& sources);

/// The states over [t0_s, t_end_s]. std::invalid_argument for a non-positive or non-finite
/// batch.max_state_interval_s.
Plan PlanStates(const std::vector<double>& anchor_times, const GnssInsConfig& config, double t0_s, double t_end_s);

}  // namespace navtwin::gnss_ins
