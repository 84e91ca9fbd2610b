// navtwin mc: Monte Carlo of any problem's methods over seeds, with the Cramér-Rao bound
// beside them; navtwin bound: the bound alone (docs/monte-carlo.md, docs/accuracy-bound.md).
// Runs spread over threads and, under mpirun or srun, over MPI ranks (docs/cluster.md).
#include <gflags/gflags.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/folder.h"
#include "core/sim/scenario.h"
#include "problems/calibration/monte_carlo.h"
#include "problems/gnss_ins/monte_carlo.h"
#include "problems/inflight_alignment/config.h"
#include "problems/inflight_alignment/monte_carlo.h"
#include "problems/leveling/monte_carlo.h"
#include "problems/transfer_alignment/config.h"
#include "problems/transfer_alignment/monte_carlo.h"
#include "solvers/mc_distribute.h"
#include "solvers/mc_output.h"
#include "solvers/mc_statistics.h"

DEFINE_string(problem, "", "mc, bound: gnss_ins, transfer, inflight, leveling or calibration");
DEFINE_string(methods, "", "mc: comma-separated methods of the problem (default: all of them)");
DEFINE_bool(bound, true, "mc: compute the Cramer-Rao bound beside the runs (problems that have one)");
DEFINE_bool(mpi, true, "mc: spread the runs over MPI ranks when started by mpirun or srun");

namespace navtwin::app {
namespace {

constexpr const char* kMcUsage =
    "navtwin mc --problem gnss_ins|transfer|inflight|leveling|calibration [--scenario PRESET|YAML] [--runs N] [--seed S]\n"
    "           [--methods a,b] [--config YAML] [--threads T] [--bound=false] --out DIR [--format=json]\n"
    "  Run k simulates the scenario with seed S + k (leveling: stream k of seed S) and runs every method;\n"
    "  per method and quantity: RMS error over runs, mean reported sigma, their ratio, ANEES with its 95 %\n"
    "  bounds, the share within 3 sigma, against time (or distance), and the Cramer-Rao bound beside them.\n"
    "  Under `mpirun -np K` the runs spread over the ranks; the files are the same bytes for any K and T.";
constexpr const char* kBoundUsage =
    "navtwin bound --problem gnss_ins|transfer|inflight [--scenario PRESET|YAML] [--seed S] [--config YAML]\n"
    "              [--out DIR] [--format=json]\n"
    "  The Cramer-Rao bound of the scenario: the batch's covariance at the truth with the configured noise\n"
    "  (data simulated with every sensor error off), as sigma against time or distance.";

/// One problem made ready from the flags: what a run computes, and its bound.
struct McProblem {
  std::string scenario;
  int default_runs = 100;
  bool streams_of_one_seed = false;  ///< run k draws stream k of --seed (else seed --seed + k)
  std::function<mc::RunRecord(std::uint64_t seed, int run)> run;
  std::function<mc::MethodRecord()> bound;  ///< empty: the problem has none
  std::vector<std::string> notes;
};

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream s(text);
  for (std::string item; std::getline(s, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

template <typename Method, typename Parse>
std::vector<Method> MethodsFromFlag(const std::vector<Method>& all, Parse parse) {
  if (FLAGS_methods.empty()) return all;
  std::vector<Method> out;
  for (const std::string& name : SplitList(FLAGS_methods)) out.push_back(parse(name));
  return out;
}

/// The problem's configuration from --config, or its defaults.
template <typename Config>
std::shared_ptr<const Config> ConfigFromFlag(Config (*load)(const std::string&)) {
  return std::make_shared<const Config>(FLAGS_config.empty() ? Config() : load(FLAGS_config));
}

McProblem TransferProblem() {
  McProblem p;
  p.scenario = FLAGS_scenario.empty() ? "transfer-alignment-high-maneuver" : FLAGS_scenario;
  const auto scenario = std::make_shared<const sim::Scenario>(sim::LoadScenario(p.scenario));
  const auto config = ConfigFromFlag(&transfer::LoadTransferConfig);
  using transfer::Method;
  const std::vector<Method> methods = MethodsFromFlag<Method>(
      {Method::kOrder1, Method::kOrder2, Method::kHistory, Method::kBatch}, &transfer::ParseMethod);
  p.run = [=](std::uint64_t seed, int run) { return transfer::TransferMcRun(*scenario, *config, methods, seed, run); };
  p.bound = [=]() { return transfer::TransferBound(*scenario, *config, FLAGS_seed); };
  p.notes.push_back("misalignment_delay: the final joint (misalignment rad, delay s) with each method's 4 x 4 covariance");
  p.notes.push_back("attitude: the slave attitude error; the transfer methods report no sigma for it");
  return p;
}

McProblem GnssInsProblem() {
  McProblem p;
  p.scenario = FLAGS_scenario.empty() ? "mems-gps-mag-maneuver" : FLAGS_scenario;
  gnss_ins::GnssInsMcSetup setup;
  setup.scenario = p.scenario;
  if (!FLAGS_methods.empty()) setup.methods = SplitList(FLAGS_methods);
  gnss_ins::CheckGnssInsMcSetup(setup);
  if (!FLAGS_config.empty()) throw std::invalid_argument("--config: gnss_ins runs use each record's own configuration");
  p.run = [=](std::uint64_t seed, int run) { return gnss_ins::GnssInsMcRun(setup, seed, run); };
  p.bound = [=]() { return gnss_ins::GnssInsBound(setup, FLAGS_seed); };
  p.notes.push_back("batch ANEES from its standard deviations only (no cross-covariances between position, velocity and attitude)");
  p.notes.push_back("filter_adapted, rts_adapted: filter and RTS again with the noise the batch's variance components found");
  return p;
}

McProblem InflightProblem() {
  McProblem p;
  p.scenario = FLAGS_scenario.empty() ? "inflight-mach07-south" : FLAGS_scenario;
  const auto scenario = std::make_shared<const sim::Scenario>(sim::LoadScenario(p.scenario));
  const auto config = ConfigFromFlag(&inflight::LoadInflightConfig);
  using inflight::Method;
  const std::vector<Method> methods =
      MethodsFromFlag<Method>({Method::kDistance, Method::kKalman, Method::kBatch}, &inflight::ParseMethod);
  const std::vector<double> at_km = {10.0, 20.0, 50.0, 100.0};
  p.run = [=](std::uint64_t seed, int run) { return inflight::InflightMcRun(*scenario, *config, methods, at_km, seed, run); };
  p.bound = [=]() { return inflight::InflightBound(*scenario, *config, at_km, FLAGS_seed); };
  return p;
}

McProblem LevelingProblem() {
  McProblem p;
  p.scenario = "leveling Monte Carlo of seed 000 (problems/leveling/monte_carlo.h)";
  p.default_runs = 10000;
  p.streams_of_one_seed = true;
  if (!FLAGS_scenario.empty()) throw std::invalid_argument("--scenario: the leveling experiment has no scenario file");
  if (!FLAGS_methods.empty()) throw std::invalid_argument("--methods: the leveling experiment runs its four methods");
  leveling::MonteCarloConfig config;
  config.window_s = FLAGS_window_s;
  config.noise_mg = FLAGS_noise_mg;
  config.seed = FLAGS_seed;
  p.run = [=](std::uint64_t, int run) { return leveling::LevelingMcRun(config, leveling::LevelingOptions(), run); };
  p.notes.push_back("one window per run; the batch's sigma from ceres::Covariance");
  return p;
}

McProblem CalibrationProblem() {
  McProblem p;
  calibration::CalibrationMcSetup setup;
  setup.scenario_path = FLAGS_scenario;
  if (!FLAGS_methods.empty()) setup.methods = SplitList(FLAGS_methods);
  calibration::CheckCalibrationMcSetup(setup);
  p.scenario = FLAGS_scenario;
  p.run = [=](std::uint64_t seed, int run) { return calibration::CalibrationMcRun(setup, seed, run); };
  p.notes.push_back("multi-position table; no bound (the estimator takes its noise from the data)");
  return p;
}

McProblem MakeProblem(const std::string& name) {
  if (name == "calibration") return CalibrationProblem();
  if (name == "transfer") return TransferProblem();
  if (name == "gnss_ins") return GnssInsProblem();
  if (name == "inflight") return InflightProblem();
  if (name == "leveling") return LevelingProblem();
  throw std::invalid_argument("--problem: '" + name + "' is not one of gnss_ins, transfer, inflight, leveling, calibration");
}

/// "mc: 37/201 done (the last is the bound), 1.93 per s, 84 s left", at most once a second
/// and at the end.
std::function<void(int, int)> ProgressLine(bool with_bound) {
  const auto start = std::chrono::steady_clock::now();
  auto last = std::make_shared<double>(-1.0);
  const char* what = with_bound ? " done (the last is the bound)" : " runs";
  return [start, last, what](int done, int runs) {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (done < runs && t - *last < 1.0) return;
    *last = t;
    const double rate = done / std::max(t, 1e-9);
    std::fprintf(stderr, "mc: %d/%d%s, %.3g per s, %.0f s left\n", done, runs, what, rate, (runs - done) / rate);
  };
}

int McUsage(const std::string& why) {
  std::cerr << "navtwin mc: " << why << "\nusage: " << kMcUsage << "\n";
  return kExitUsage;
}

int RunMc(const std::vector<std::string>& args) {
  // Every rank parses the same command line; only rank 0 prints results and writes files.
  const mc::RankSession session(FLAGS_mpi);
  const bool lead = session.rank() == 0;
  if (!args.empty()) return lead ? McUsage("unexpected argument '" + args[0] + "'") : kExitUsage;
  if (FLAGS_out.empty()) return lead ? McUsage("--out DIR is required") : kExitUsage;
  if (FLAGS_threads < 0) return lead ? McUsage("--threads must be 0 (all cores) or positive") : kExitUsage;
  McProblem problem;
  try {
    problem = MakeProblem(FLAGS_problem);
  } catch (const std::exception& e) {
    return lead ? McUsage(e.what()) : kExitUsage;
  }
  const int runs = FlagGiven("runs") ? FLAGS_runs : problem.default_runs;
  if (runs < 1) return lead ? McUsage("--runs must be >= 1") : kExitUsage;
  const bool with_bound = FLAGS_bound && static_cast<bool>(problem.bound);
  if (lead) {
    std::cerr << "mc: " << runs << " runs of " << FLAGS_problem << " on " << problem.scenario << ", seed "
              << FLAGS_seed << (with_bound ? ", and the bound" : "") << "; "
              << session.ranks() << " rank" << (session.ranks() == 1 ? "" : "s") << " x "
              << (FLAGS_threads == 0 ? "all cores" : std::to_string(FLAGS_threads) + (FLAGS_threads == 1 ? " thread" : " threads"))
              << "\n";
  }
  // Item `runs` (the last) is the bound, so it is balanced like any run.
  const int items = runs + (with_bound ? 1 : 0);
  mc::Accumulator accumulator;
  mc::MethodRecord bound;
  const auto compute = [&](int item) {
    if (item == runs) {
      // A bound that cannot be computed is reported, not the end of the runs.
      mc::RunRecord r;
      r.run = item;
      try {
        r.methods.push_back(problem.bound());
      } catch (const std::exception& e) {
        r.methods.push_back(mc::MethodRecord{"bound", e.what(), 0.0, {}});
      }
      return mc::SerializeRunRecord(r);
    }
    return mc::SerializeRunRecord(problem.run(FLAGS_seed + static_cast<std::uint64_t>(item), item));
  };
  const auto consume = [&](int item, const std::string& bytes) {
    mc::RunRecord r = mc::DeserializeRunRecord(bytes);
    if (item == runs) {
      bound = std::move(r.methods.front());
    } else {
      accumulator.Add(r);
    }
  };
  mc::DistributeRuns(session, items, FLAGS_threads, compute, consume, lead ? ProgressLine(with_bound) : nullptr);
  if (!lead) return kExitOk;
  mc::ExperimentInfo info;
  info.problem = FLAGS_problem;
  info.scenario = problem.scenario;
  info.seed = FLAGS_seed;
  info.runs = runs;
  info.run_seeds = accumulator.seeds();
  info.seeding = problem.streams_of_one_seed
                     ? "streams 0.." + std::to_string(runs - 1) + " of seed " + std::to_string(FLAGS_seed)
                     : "seeds " + std::to_string(FLAGS_seed) + ".." + std::to_string(FLAGS_seed + runs - 1);
  info.notes = problem.notes;
  if (with_bound && !bound.failure.empty()) {
    info.notes.push_back("no bound: " + bound.failure);
    std::cerr << "mc: the bound failed: " << bound.failure << "\n";
  }
  const mc::MethodRecord* bound_ptr = with_bound && bound.failure.empty() ? &bound : nullptr;
  const std::vector<mc::MethodStatistics> stats = accumulator.Finish(bound_ptr);
  OutputFolder folder(FLAGS_out);
  folder.Make();
  mc::WriteExperimentFolder(FLAGS_out, info, stats, bound_ptr);
  folder.Keep();
  std::cout << (FLAGS_format == "json" ? mc::SummaryJson(info, stats, bound_ptr) : mc::SummaryTable(info, stats, bound_ptr));
  return kExitOk;
}

int RunBound(const std::vector<std::string>& args) {
  const auto usage = [](const std::string& why) {
    std::cerr << "navtwin bound: " << why << "\nusage: " << kBoundUsage << "\n";
    return kExitUsage;
  };
  if (!args.empty()) return usage("unexpected argument '" + args[0] + "'");
  McProblem problem;
  try {
    problem = MakeProblem(FLAGS_problem);
  } catch (const std::exception& e) {
    return usage(e.what());
  }
  if (!problem.bound) return usage("the " + FLAGS_problem + " problem has no bound");
  std::cerr << "bound: " << FLAGS_problem << " on " << problem.scenario << " (noise-free data, seed " << FLAGS_seed << ")\n";
  const mc::MethodRecord bound = problem.bound();
  mc::ExperimentInfo info;
  info.problem = FLAGS_problem;
  info.scenario = problem.scenario;
  info.seed = FLAGS_seed;
  if (!FLAGS_out.empty()) {
    OutputFolder folder(FLAGS_out);
    folder.Make();
    mc::WriteExperimentFolder(FLAGS_out, info, {}, &bound);
    folder.Keep();
  }
  std::cout << mc::BoundTable(bound, FLAGS_format == "json");
  return kExitOk;
}

}  // namespace

Command McCommand() {
  return {"mc",
          "Monte Carlo of a problem's methods over seeds: RMS, sigma, ANEES against time, beside the bound (threads, MPI)",
          kMcUsage,
          {"problem", "scenario", "runs", "seed", "methods", "config", "threads", "bound", "mpi", "out", "format",
           "window_s", "noise_mg"},
          &RunMc};
}

Command BoundCommand() {
  return {"bound", "Cramer-Rao bound of a scenario: the batch's covariance at the truth, sigma against time",
          kBoundUsage, {"problem", "scenario", "seed", "config", "methods", "out", "format"}, &RunBound};
}

}  // namespace navtwin::app
