// The outputs of `navtwin mc` (docs/monte-carlo.md): summary.json, per method and quantity
// a CSV against the axis, the final values of every run, histograms of the final values,
// and the table printed on stdout. Nothing in them depends on the threads, ranks or
// timing, so the files of one experiment are the same bytes however it was run.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "solvers/mc_statistics.h"

namespace navtwin::mc {

struct ExperimentInfo {
  std::string problem;   ///< "gnss_ins", "transfer", ...
  std::string scenario;  ///< preset name or YAML path
  std::uint64_t seed = 1;  ///< run k uses seed + k
  int runs = 0;
  std::vector<std::uint64_t> run_seeds;  ///< per run (Accumulator::seeds); empty: seed + run
  /// How the runs draw, e.g. "seeds 1..200" or "streams 0..9999 of seed 1" (the summary's
  /// "seeding" and the table's first line).
  std::string seeding;
  std::vector<std::string> notes;  ///< e.g. what the bound covers, what a method leaves out
};

/// Bins of a histogram of the final values: 20 bins over [-4, 4] x the RMS of the errors
/// (kind "error", display units) and over [-5, 5] for error / sigma ("normalised"), plus the
/// counts below and above.
struct Histogram {
  std::string kind;
  double lo = 0.0, hi = 0.0;
  std::vector<int> counts;
  int below = 0, above = 0;
};
Histogram ErrorHistogram(const std::vector<double>& values, double half_width);

/// summary.json: the experiment, and per method and quantity the final point's statistics
/// (rms, sigma_mean, ratio, bound, rms_over_bound, within_3sigma per component; anees with
/// its 95 % bounds) and over the axis the mean ANEES and the share of points inside the
/// bounds; the bound's final sigma; failures with the first reason.
std::string SummaryJson(const ExperimentInfo& info, const std::vector<MethodStatistics>& stats,
                        const MethodRecord* bound);

/// The table on stdout: per method and quantity the final RMS, mean sigma, their ratio, the
/// bound and ANEES with its bounds (display units).
std::string SummaryTable(const ExperimentInfo& info, const std::vector<MethodStatistics>& stats,
                         const MethodRecord* bound);

/// The bound alone (`navtwin bound`): per quantity its sigma per component at up to 6 axis
/// points (all of them when few, else evenly spaced, the last always), display units; as
/// JSON {"bound": {quantity: {"unit", "axis", "components", "points": [{"at", "sigma"}]}}}.
std::string BoundTable(const MethodRecord& bound, bool json);

/// Writes DIR/summary.json, DIR/<method>/<quantity>.csv (axis, runs, per component rms,
/// sigma, ratio, bound; anees, anees_lo, anees_hi), DIR/finals.csv (run, seed, method,
/// quantity, component, error, sigma), DIR/histograms.csv and, with a bound,
/// DIR/bound/<quantity>.csv. All files or none (a failure removes those written).
void WriteExperimentFolder(const std::string& dir, const ExperimentInfo& info,
                           const std::vector<MethodStatistics>& stats, const MethodRecord* bound);

}  // namespace navtwin::mc
