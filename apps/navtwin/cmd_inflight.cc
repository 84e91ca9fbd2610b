// navtwin inflight-align / inflight-mc: in-flight heading alignment from the distance
// flown (seed 003, issue 7; problems/inflight_alignment). inflight-align runs one method
// (distance, kalman, batch) or all three on recorded files or on a simulated scenario and
// prints the heading error against the distance flown; inflight-mc repeats the three
// methods over seeds of a scenario and prints the statistics of the errors.
#include <gflags/gflags.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/atomic_file.h"
#include "core/io/json_writer.h"
#include "core/rotation.h"
#include "core/sim/scenario.h"
#include "problems/inflight_alignment/config.h"
#include "problems/inflight_alignment/inputs.h"
#include "problems/inflight_alignment/run.h"
#include "solvers/monte_carlo.h"

DEFINE_string(track_csv, "",
              "inflight-align: write the heading track (t_s,path_length_km,yaw_deg,sigma_arcmin,error_arcmin) "
              "to this CSV; with --method all one file per method, the method's name before the extension");
DEFINE_double(outlier_fraction, -1.0,
              "inflight-align, inflight-mc with --scenario: probability of a GNSS outlier per fix, overriding the "
              "scenario's (e.g. 0.01); negative: keep the scenario's");
DEFINE_double(outlier_m, 200.0, "inflight-align, inflight-mc: size of a GNSS outlier's position offset, m (with --outlier_fraction)");

namespace navtwin::app {
namespace {

using inflight::InflightConfig;
using inflight::InflightInputs;
using inflight::Method;
using inflight::MethodResult;

constexpr double kRadToArcmin = kRadToDeg * 60.0;
constexpr const char* kDefaultMcScenario = "inflight-mach07-south";
constexpr int kDefaultMcRuns = 50;
const std::vector<double> kAtKm = {10.0, 20.0, 50.0, 100.0};
const std::vector<Method> kAllMethods = {Method::kDistance, Method::kKalman, Method::kBatch};

int Usage(const std::string& command, const std::string& usage, const std::string& why) {
  std::cerr << "navtwin " << command << ": " << why << "\nusage: " << usage << "\n";
  return kExitUsage;
}

/// The configuration file, or the defaults (the seed's 1 NM/h INS).
InflightConfig ConfigFromFlag() {
  return FLAGS_config.empty() ? InflightConfig() : inflight::LoadInflightConfig(FLAGS_config);
}

/// Checks --outlier_fraction / --outlier_m; empty, or what is wrong.
std::string CheckOutlierFlags(bool have_scenario) {
  const bool fraction = FlagGiven("outlier_fraction"), size = FlagGiven("outlier_m");
  if ((fraction || size) && !have_scenario) return "--outlier_fraction and --outlier_m go with --scenario";
  if (size && !fraction) return "--outlier_m needs --outlier_fraction";
  if (fraction && !(FLAGS_outlier_fraction >= 0.0 && FLAGS_outlier_fraction <= 1.0)) {
    return "--outlier_fraction must be in [0, 1]";
  }
  if (fraction && !(FLAGS_outlier_m >= 0.0 && std::isfinite(FLAGS_outlier_m))) return "--outlier_m must be >= 0";
  return "";
}

/// The scenario of --scenario with the outlier flags applied.
sim::Scenario ScenarioFromFlags(const std::string& name) {
  sim::Scenario s = sim::LoadScenario(name);
  if (!s.gnss) throw std::invalid_argument("scenario " + name + " has no gnss section (in-flight alignment needs GPS)");
  if (FlagGiven("outlier_fraction")) {
    s.gnss->outlier_probability = FLAGS_outlier_fraction;
    s.gnss->outlier_size_m = FLAGS_outlier_m;
  }
  return s;
}

std::string OutlierText(const sim::Scenario& s) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "GNSS outliers %g %% of fixes, %g m", 100.0 * s.gnss->outlier_probability,
                s.gnss->outlier_size_m);
  return buf;
}

// ---------------------------------------------------------------------------------------
// inflight-align

const char* kAlignUsage =
    "navtwin inflight-align --imu F --gnss F [--baro F] --init_from NAV [--start_s T] [--truth NAV] "
    "[--calibration FILE [--imu_temperature_degC T]] [--config YAML] --method distance|kalman|batch|all [--track_csv F] [--format=json]\n"
    "       navtwin inflight-align --scenario PRESET|YAML [--seed S] [--outlier_fraction P --outlier_m M] "
    "[--config YAML] --method distance|kalman|batch|all [--track_csv F] [--format=json]\n"
    "  The initial state is the record of --init_from at or after --start_s (default its first record);\n"
    "  heading errors need --truth (a scenario brings its own). Configuration keys: data/configs/\n"
    "  inflight-mach07-south.yaml. --method all runs the three (JSON: an array of the three objects).";

/// `path` with `tag` before its extension: track.csv -> track_batch.csv.
std::string TaggedPath(const std::string& path, const std::string& tag) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return path + "_" + tag;
  return path.substr(0, dot) + "_" + tag + path.substr(dot);
}

int RunInflightAlign(const std::vector<std::string>& args) {
  const auto usage = [](const std::string& why) { return Usage("inflight-align", kAlignUsage, why); };
  if (!args.empty()) return usage("unexpected argument '" + args[0] + "'");
  if (FLAGS_method.empty()) return usage("--method is required (distance, kalman, batch or all)");
  std::vector<Method> methods;
  if (FLAGS_method == "all") {
    methods = kAllMethods;
  } else {
    try {
      methods = {inflight::ParseMethod(FLAGS_method)};
    } catch (const std::invalid_argument&) {
      return usage("--method must be distance, kalman, batch or all, got '" + FLAGS_method + "'");
    }
  }
  const bool scenario = !FLAGS_scenario.empty();
  if (scenario) {
    for (const char* flag : {"imu", "gnss", "baro", "init_from", "start_s", "truth", "calibration", "imu_temperature_degC"}) {
      if (FlagGiven(flag)) return usage(std::string("--scenario simulates its own files: drop --") + flag);
    }
  } else {
    if (FLAGS_imu.empty() || FLAGS_gnss.empty()) return usage("--imu and --gnss are required (or --scenario)");
    if (FLAGS_init_from.empty()) return usage("--init_from NAV is required: the INS's initial state");
    if (FlagGiven("seed")) return usage("--seed goes with --scenario");
    if (!std::isnan(FLAGS_start_s) && !std::isfinite(FLAGS_start_s)) return usage("--start_s must be a time, s");
    if (FLAGS_calibration.empty() && FlagGiven("imu_temperature_degC")) {
      return usage("--imu_temperature_degC goes with --calibration");
    }
  }
  const std::string outlier_error = CheckOutlierFlags(scenario);
  if (!outlier_error.empty()) return usage(outlier_error);

  const InflightConfig config = ConfigFromFlag();
  InflightInputs inputs;
  if (scenario) {
    const sim::Scenario s = ScenarioFromFlags(FLAGS_scenario);
    std::cerr << "inflight-align: simulating " << s.name << " (seed " << FLAGS_seed << ", " << OutlierText(s)
              << ")\n";
    inputs = inflight::SimulateInflightInputs(s, FLAGS_seed);
  } else {
    inflight::InflightFiles files;
    files.imu = FLAGS_imu;
    files.gnss = FLAGS_gnss;
    files.baro = FLAGS_baro;
    files.init = FLAGS_init_from;
    files.init_time_s = std::isnan(FLAGS_start_s) ? -1.0 : FLAGS_start_s;
    files.truth = FLAGS_truth;
    files.calibration = FLAGS_calibration;
    files.imu_temperature_degC = FLAGS_imu_temperature_degC;
    inputs = inflight::LoadInflightInputs(files);
  }
  if (inputs.truth.empty()) std::cerr << "inflight-align: no --truth: heading errors are not known (printed as -)\n";

  std::vector<MethodResult> results;
  for (const Method m : methods) {
    std::cerr << "inflight-align: running " << inflight::MethodName(m) << " ...\n";
    results.push_back(inflight::RunMethod(inputs, config, m, kAtKm));
    std::fprintf(stderr, "inflight-align: %s done in %.2f s\n", inflight::MethodName(m), results.back().run_time_s);
  }

  // Every result exists before anything is written: no partial output on failure.
  if (!FLAGS_track_csv.empty()) {
    for (const MethodResult& r : results) {
      const std::string path =
          results.size() == 1 ? FLAGS_track_csv : TaggedPath(FLAGS_track_csv, inflight::MethodName(r.method));
      inflight::WriteTrackCsv(r, path);
    }
  }
  if (FLAGS_format == "json") {
    if (results.size() == 1) {
      std::cout << inflight::MethodResultJson(results.front()) << "\n";
    } else {
      std::cout << "[";
      for (std::size_t i = 0; i < results.size(); ++i) {
        std::cout << (i ? "," : "") << inflight::MethodResultJson(results[i]);
      }
      std::cout << "]\n";
    }
  } else {
    for (std::size_t i = 0; i < results.size(); ++i) {
      std::cout << (i ? "\n" : "") << inflight::MethodResultTable(results[i]);
    }
  }
  return kExitOk;
}

// ---------------------------------------------------------------------------------------
// inflight-mc

const char* kMcUsage =
    "navtwin inflight-mc [--scenario inflight-mach07-south] [--runs 50] [--seed 1] [--threads 2] "
    "[--outlier_fraction P --outlier_m M] [--config YAML] [--errors_csv F] [--format=json]\n"
    "  Run r simulates the scenario with seed S + r and runs distance, kalman and batch on it; per method\n"
    "  the mean, sigma (sample standard deviation) and RMS over the runs of the heading error at 10, 20,\n"
    "  50, 100 km and at the end (arcmin), and the mean reported final sigma. --runs defaults to 50 here.";

/// One method's numbers of one run (NaN where the method failed or the distance was not reached).
struct RunNumbers {
  std::array<double, 4> at_km_arcmin{};
  double final_arcmin = NAN;
  double sigma_arcmin = NAN;
  double run_time_s = NAN;
  std::string failure;  ///< empty unless the method threw
};

struct Moments {
  double mean = NAN, sigma = NAN, rms = NAN;
  int count = 0;  ///< runs with a finite value
};

/// Mean, sample standard deviation (n - 1) and RMS of the finite values, in run order.
Moments MomentsOf(const std::vector<double>& values) {
  Moments m;
  double sum = 0.0, sum2 = 0.0;
  for (const double v : values) {
    if (!std::isfinite(v)) continue;
    ++m.count;
    sum += v;
    sum2 += v * v;
  }
  if (m.count == 0) return m;
  m.mean = sum / m.count;
  m.rms = std::sqrt(sum2 / m.count);
  if (m.count > 1) {
    double dev2 = 0.0;
    for (const double v : values) {
      if (std::isfinite(v)) dev2 += (v - m.mean) * (v - m.mean);
    }
    m.sigma = std::sqrt(dev2 / (m.count - 1));
  }
  return m;
}

struct MethodStats {
  Method method;
  std::array<Moments, 4> at_km;
  Moments final_error;
  Moments sigma;  ///< of the reported final sigma (mean used)
  Moments run_time;
  int failures = 0;
  std::string first_failure;
};

MethodStats StatsOf(Method method, int index, const std::vector<std::array<RunNumbers, 3>>& runs) {
  MethodStats s;
  s.method = method;
  const auto column = [&](auto get) {
    std::vector<double> v;
    for (const auto& run : runs) v.push_back(get(run[index]));
    return MomentsOf(v);
  };
  for (int k = 0; k < 4; ++k) s.at_km[k] = column([k](const RunNumbers& r) { return r.at_km_arcmin[k]; });
  s.final_error = column([](const RunNumbers& r) { return r.final_arcmin; });
  s.sigma = column([](const RunNumbers& r) { return r.sigma_arcmin; });
  s.run_time = column([](const RunNumbers& r) { return r.run_time_s; });
  for (const auto& run : runs) {
    if (run[index].failure.empty()) continue;
    if (s.failures++ == 0) s.first_failure = run[index].failure;
  }
  return s;
}

RunNumbers NumbersOf(const MethodResult& r) {
  RunNumbers n;
  for (int k = 0; k < 4; ++k) n.at_km_arcmin[k] = r.error_at_km_rad[k] * kRadToArcmin;
  n.final_arcmin = r.final_error_rad * kRadToArcmin;
  n.sigma_arcmin = r.final_sigma_rad * kRadToArcmin;
  n.run_time_s = r.run_time_s;
  return n;
}

void WriteMcErrorsCsv(const std::string& path, std::uint64_t seed,
                      const std::vector<std::array<RunNumbers, 3>>& runs) {
  AtomicFile f(path);
  std::ostream& o = f.stream();
  o << "run,seed,method,error_10km_arcmin,error_20km_arcmin,error_50km_arcmin,error_100km_arcmin,"
       "final_error_arcmin,final_sigma_arcmin,run_time_s\n";
  for (std::size_t run = 0; run < runs.size(); ++run) {
    for (int m = 0; m < 3; ++m) {
      const RunNumbers& n = runs[run][m];
      o << run << "," << seed + run << "," << inflight::MethodName(kAllMethods[m]);
      for (const double x : n.at_km_arcmin) o << "," << x;
      o << "," << n.final_arcmin << "," << n.sigma_arcmin << "," << n.run_time_s << "\n";
    }
  }
  f.Commit();
}

void PrintMcText(const std::string& header, const std::vector<MethodStats>& stats, double wall_s) {
  std::cout << header << "\n";
  char line[256];
  std::snprintf(line, sizeof line, "%-9s %-9s %10s %10s %10s %6s\n", "method", "error at", "mean", "sigma", "rms",
                "runs");
  std::cout << line;
  std::snprintf(line, sizeof line, "%-9s %-9s %10s %10s %10s %6s\n", "", "", "(arcmin)", "(arcmin)", "(arcmin)", "");
  std::cout << line;
  const auto cell = [](double x) {
    if (std::isnan(x)) return std::string("-");
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3f", x);
    return std::string(buf);
  };
  for (const MethodStats& s : stats) {
    for (int k = 0; k <= 4; ++k) {
      const Moments& m = k < 4 ? s.at_km[k] : s.final_error;
      const std::string label = k < 4 ? std::to_string(static_cast<int>(kAtKm[k])) + " km" : "final";
      std::snprintf(line, sizeof line, "%-9s %-9s %10s %10s %10s %6d\n", inflight::MethodName(s.method),
                    label.c_str(), cell(m.mean).c_str(), cell(m.sigma).c_str(), cell(m.rms).c_str(), m.count);
      std::cout << line;
    }
    std::snprintf(line, sizeof line, "%-9s mean reported final sigma %s arcmin, mean run time %s s%s\n",
                  inflight::MethodName(s.method), cell(s.sigma.mean).c_str(), cell(s.run_time.mean).c_str(),
                  s.failures ? (", " + std::to_string(s.failures) + " runs failed").c_str() : "");
    std::cout << line;
    if (s.failures) std::cout << "  first failure: " << s.first_failure << "\n";
  }
  std::snprintf(line, sizeof line, "wall time %.1f s ('-': no run reached the distance)\n", wall_s);
  std::cout << line;
}

void PrintMcJson(const std::string& scenario, const sim::Scenario& s, int runs, std::uint64_t seed,
                 const std::vector<MethodStats>& stats, double wall_s) {
  JsonWriter w(std::cout);
  w.BeginObject()
      .Field("scenario", scenario)
      .Field("runs", runs)
      .Field("seed", static_cast<long long>(seed))
      .Field("outlier_fraction", s.gnss->outlier_probability)
      .Field("outlier_m", s.gnss->outlier_size_m)
      .Field("run_time_s", wall_s);
  const auto moments = [&](const Moments& m) {
    w.BeginObject().Field("mean", m.mean).Field("sigma", m.sigma).Field("rms", m.rms).Field("runs", m.count).EndObject();
  };
  w.Key("methods").BeginObject();
  for (const MethodStats& st : stats) {
    w.Key(inflight::MethodName(st.method)).BeginObject();
    w.Key("final_heading_error_arcmin");
    moments(st.final_error);
    w.Key("heading_error_arcmin_at_km").BeginObject();
    for (int k = 0; k < 4; ++k) {
      w.Key(std::to_string(static_cast<int>(kAtKm[k])));
      moments(st.at_km[k]);
    }
    w.EndObject();
    w.Field("mean_heading_sigma_arcmin", st.sigma.mean)
        .Field("mean_run_time_s", st.run_time.mean)
        .Field("failures", st.failures)
        .Field("first_failure", st.first_failure)
        .EndObject();
  }
  w.EndObject().EndObject();
  std::cout << "\n";
}

int RunInflightMc(const std::vector<std::string>& args) {
  const auto usage = [](const std::string& why) { return Usage("inflight-mc", kMcUsage, why); };
  if (!args.empty()) return usage("unexpected argument '" + args[0] + "'");
  const int runs = FlagGiven("runs") ? FLAGS_runs : kDefaultMcRuns;
  if (runs < 1) return usage("--runs must be >= 1");
  if (FLAGS_threads < 0) return usage("--threads must be 0 (all cores) or positive");
  const std::string outlier_error = CheckOutlierFlags(true);
  if (!outlier_error.empty()) return usage(outlier_error);
  const std::string scenario_name = FLAGS_scenario.empty() ? kDefaultMcScenario : FLAGS_scenario;
  const InflightConfig config = ConfigFromFlag();
  const sim::Scenario scenario = ScenarioFromFlags(scenario_name);
  const std::uint64_t seed = FLAGS_seed;

  std::cerr << "inflight-mc: " << runs << " runs of " << scenario.name << ", seeds " << seed << ".."
            << seed + runs - 1 << ", " << OutlierText(scenario) << "\n";
  const auto start = std::chrono::steady_clock::now();
  // Each run writes only its own slot; statistics are taken in run order afterwards, so
  // the output does not depend on the thread count.
  std::vector<std::array<RunNumbers, 3>> slots(runs);
  RunParallel(
      runs, FLAGS_threads,
      [&](int run, int /*worker*/) {
        const InflightInputs inputs = inflight::SimulateInflightInputs(scenario, seed + run);
        for (int m = 0; m < 3; ++m) {
          try {
            slots[run][m] = NumbersOf(inflight::RunMethod(inputs, config, kAllMethods[m], kAtKm));
          } catch (const std::exception& e) {
            // A method failing on one seed is a result (counted, first reason printed), not
            // the end of the experiment.
            slots[run][m] = RunNumbers();
            slots[run][m].at_km_arcmin.fill(NAN);
            slots[run][m].failure = "seed " + std::to_string(seed + run) + ": " + e.what();
          }
        }
      },
      [](int done, int total) { std::fprintf(stderr, "inflight-mc: %d/%d runs\n", done, total); });
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<MethodStats> stats;
  for (int m = 0; m < 3; ++m) stats.push_back(StatsOf(kAllMethods[m], m, slots));
  if (!FLAGS_errors_csv.empty()) WriteMcErrorsCsv(FLAGS_errors_csv, seed, slots);
  if (FLAGS_format == "json") {
    PrintMcJson(scenario_name, scenario, runs, seed, stats, wall_s);
  } else {
    char header[256];
    std::snprintf(header, sizeof header, "inflight-mc: %d runs of %s, seeds %llu..%llu, %s, %d thread%s", runs,
                  scenario.name.c_str(), static_cast<unsigned long long>(seed),
                  static_cast<unsigned long long>(seed + runs - 1), OutlierText(scenario).c_str(),
                  MonteCarloWorkers(runs, FLAGS_threads), MonteCarloWorkers(runs, FLAGS_threads) == 1 ? "" : "s");
    PrintMcText(header, stats, wall_s);
  }
  return kExitOk;
}

}  // namespace

Command InflightAlignCommand() {
  return {"inflight-align",
          "In-flight heading alignment from the distance flown (seed 003): distance, kalman or batch",
          kAlignUsage,
          {"imu", "gnss", "baro", "init_from", "start_s", "truth", "config", "scenario", "seed", "method",
           "track_csv", "outlier_fraction", "outlier_m", "calibration", "imu_temperature_degC"},
          &RunInflightAlign};
}

Command InflightMcCommand() {
  return {"inflight-mc",
          "Monte Carlo of the in-flight heading alignment: every method's heading error over seeds",
          kMcUsage,
          {"scenario", "runs", "seed", "threads", "outlier_fraction", "outlier_m", "config", "errors_csv"},
          &RunInflightMc};
}

}  // namespace navtwin::app
