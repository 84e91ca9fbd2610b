// The initial state of the GNSS/INS estimators, a step that runs before the filter: a
// given state, a static coarse alignment (problems/ins/alignment.h; heading from
// gyrocompassing, the magnetometer or a search over hypotheses, heading_search.h), or the
// attitude from the GNSS velocity; with the standard deviations of its error state.
#pragma once

#include <ostream>

#include <Eigen/Core>

#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/inputs.h"

namespace navtwin::gnss_ins {

/// The initial error-state standard deviations (n = 15 or 21) from config.init.std, where
/// a zero bias / scale-factor entry is replaced by the ImuNoise value (*_std), and with a
/// heading search (static alignment, kSearch) the heading's (phi_D) is the search's,
/// HeadingSearchYawStd (heading_search.h).
Eigen::VectorXd InitialStdVector(const GnssInsConfig& config, int n);

/// Where the filter starts: the initial state and its error-state standard deviations.
struct FilterStart {
  InsState state;  ///< the initial nominal state at state.nav.t_s
  /// Whether measurements tagged exactly at the start time are used (kGiven), or were
  /// used to make the state (alignment, GNSS velocity) and are skipped.
  bool use_measurements_at_start = true;
  /// The initial error-state standard deviations (InitialStdVector; 15 or 21 entries).
  Eigen::VectorXd std;
};

/// The initial state per config.init.source (see RunFilter) with its std; this alignment
/// step runs before the filter; a heading search reports on
/// `progress` when not null (it is deterministic: every call picks the same heading).
/// Throws InputError when the inputs hold no data to initialise from (no IMU samples; no
/// GNSS fix for the alignment's position; no magnetometer sample for its heading; no GNSS
/// epoch after it for a heading search; no fast enough GNSS velocity; IMU data not
/// static), std::invalid_argument for kGiven without a state or a magnetometer heading
/// with mag.mode off.
FilterStart InitialFilterState(const Inputs& inputs, const GnssInsConfig& config,
                               std::ostream* progress = nullptr);

}  // namespace navtwin::gnss_ins
