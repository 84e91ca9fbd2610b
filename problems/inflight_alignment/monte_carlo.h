// The Monte Carlo experiment of `navtwin inflight-mc`: run r simulates a scenario with seed
// S + r and runs every method on it; per method the mean, sample standard deviation and RMS
// over the runs of the heading error at given distances and at the end, of the reported
// final sigma and of the run time. A method failing on one seed is a result (counted, the
// first reason kept), not the end of the experiment. Each run writes only its own slot and
// the statistics are taken in run order afterwards, so they do not depend on the threads.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "core/sim/scenario.h"
#include "problems/inflight_alignment/config.h"
#include "problems/inflight_alignment/run.h"
#include "solvers/mc_record.h"

namespace navtwin::inflight {

/// One method's numbers of one run; NaN where the method failed or the distance was not
/// reached.
struct McRunNumbers {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> error_at_km_rad;  ///< one per McOptions::at_km
  double final_error_rad = kNaN;
  double final_sigma_rad = kNaN;
  double run_time_s = kNaN;
  std::string failure;  ///< empty unless the method threw
};

/// The numbers of one method's result.
McRunNumbers NumbersOf(const MethodResult& result);

struct Moments {
  double mean = McRunNumbers::kNaN;
  double sigma = McRunNumbers::kNaN;  ///< sample standard deviation (n - 1); NaN below 2 values
  double rms = McRunNumbers::kNaN;
  int count = 0;  ///< finite values
};

/// Mean, sample standard deviation and RMS of the finite values (in order).
Moments MomentsOf(const std::vector<double>& values);

struct McMethodStats {
  Method method = Method::kDistance;
  std::vector<Moments> error_at_km_rad;  ///< one per McOptions::at_km
  Moments final_error_rad;
  Moments final_sigma_rad;
  Moments run_time_s;
  int failures = 0;
  std::string first_failure;  ///< of the first failed run in run order
};

/// The statistics of one method over its runs (in run order).
McMethodStats StatsOf(Method method, const std::vector<McRunNumbers>& runs);

struct McOptions {
  int runs = 50;
  std::uint64_t seed = 1;  ///< run r uses seed + r
  int threads = 2;         ///< 0: all cores
  std::vector<Method> methods = {Method::kDistance, Method::kKalman, Method::kBatch};
  std::vector<double> at_km = {10.0, 20.0, 50.0, 100.0};
  std::function<void(int done, int runs)> progress;  ///< may be empty
};

struct McResult {
  McOptions options;
  std::vector<std::vector<McRunNumbers>> runs;  ///< [run][method]
  std::vector<McMethodStats> stats;             ///< one per method
  double wall_time_s = 0.0;
  int workers = 1;
};

/// Runs the experiment. The scenario must have GNSS. Throws std::invalid_argument for
/// runs < 1, threads < 0 or no method.
McResult RunInflightMonteCarlo(const sim::Scenario& scenario, const InflightConfig& config,
                               const McOptions& options);

/// Every run's numbers of every method as CSV: run,seed,method,error_<D>km_arcmin...,
/// final_error_arcmin,final_sigma_arcmin,run_time_s (written whole or not at all).
void WriteMcErrorsCsv(const McResult& result, const std::string& path);

/// Run `run` of `navtwin mc --problem inflight` (docs/monte-carlo.md): the scenario simulated
/// with `seed`, each method run; quantities "heading" (error estimate - truth, arcmin, with
/// the reported sigma) at the distances `at_km` (axis distance_km) and "heading_final" at
/// the end of the flight (axis "final", one point). A method that throws is recorded as
/// failed.
mc::RunRecord InflightMcRun(const sim::Scenario& scenario, const InflightConfig& config,
                            const std::vector<Method>& methods, const std::vector<double>& at_km,
                            std::uint64_t seed, int run);

/// The Cramér-Rao bound (docs/accuracy-bound.md): the batch's heading sigma, solved on the
/// fixes up to each distance, from the scenario simulated with every sensor error off and
/// the configured noise (a GPS sigma of 0, "estimate it", becomes the scenario receiver's
/// horizontal sigma). Quantities as InflightMcRun's.
mc::MethodRecord InflightBound(const sim::Scenario& scenario, const InflightConfig& config,
                               const std::vector<double>& at_km, std::uint64_t seed);

}  // namespace navtwin::inflight
