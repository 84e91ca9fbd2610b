// GNSS/INS under `navtwin mc --problem gnss_ins` and `navtwin bound --problem gnss_ins`
// (docs/monte-carlo.md, docs/accuracy-bound.md).
//
// A run simulates the scenario with its seed, writes the configuration a user of that
// record would write (ConfigYamlForSimulation) and runs the filter, its RTS smoother and
// the batch smoother (started from RTS) as `navtwin smooth` does, then the filter and RTS
// again with the noise the batch's variance components found ("filter_adapted",
// "rts_adapted"; the plain ones when nothing changed). Quantities per method,
// estimate - truth at whole seconds after the first IMU epoch (the method's knot at that
// time, or its latest before it):
//   position  NED, m;  velocity  NED, m/s;  attitude  Log(R_n_b_est R_n_b_true^T), NED, mrad;
// with the filter's and RTS's full 3 x 3 covariance blocks, and the batch's standard
// deviations (it keeps no cross-covariances between the three).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "solvers/mc_record.h"

namespace navtwin::gnss_ins {

struct GnssInsMcSetup {
  std::string scenario;             ///< a preset name or a scenario YAML with GNSS
  std::string mag_mode = "vector";  ///< off, vector, heading, heading_2axis
  std::vector<std::string> methods = {"filter", "rts", "batch", "filter_adapted", "rts_adapted"};
};

/// Throws std::invalid_argument naming the bad method (filter, rts, batch, filter_adapted,
/// rts_adapted) or mode.
void CheckGnssInsMcSetup(const GnssInsMcSetup& setup);

/// Run `run` with `seed`. A failing estimator is recorded as failed, not passed on (the
/// RTS and batch fail with the filter they start from).
mc::RunRecord GnssInsMcRun(const GnssInsMcSetup& setup, std::uint64_t seed, int run);

/// The Cramér-Rao bound (docs/accuracy-bound.md): the batch's standard deviations at the
/// truth: the scenario simulated with every sensor error off, the configured noise, no
/// variance-component rescaling. Quantities position, velocity, attitude on the run grid.
mc::MethodRecord GnssInsBound(const GnssInsMcSetup& setup, std::uint64_t seed);

}  // namespace navtwin::gnss_ins
