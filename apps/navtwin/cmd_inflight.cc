// navtwin inflight-align / inflight-mc: in-flight heading alignment from the distance
// flown (seed 003, issue 7; problems/inflight_alignment). inflight-align runs one method
// (distance, kalman, batch) or all three on recorded files or on a simulated scenario and
// prints the heading error against the distance flown; inflight-mc repeats the three
// methods over seeds of a scenario and prints the statistics of the errors.
#include <gflags/gflags.h>

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
#include "core/io/folder.h"
#include "core/io/json_writer.h"
#include "core/rotation.h"
#include "core/sim/scenario.h"
#include "problems/inflight_alignment/config.h"
#include "problems/inflight_alignment/inputs.h"
#include "problems/inflight_alignment/monte_carlo.h"
#include "problems/inflight_alignment/run.h"

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
    "[--calibration FILE [--imu_temperature_degC T]] [--config YAML] --method distance|kalman|batch|all [--track_csv F] [--out DIR [--report]] [--format=json]\n"
    "       navtwin inflight-align --scenario PRESET|YAML [--seed S] [--outlier_fraction P --outlier_m M] "
    "[--config YAML] --method distance|kalman|batch|all [--track_csv F] [--out DIR [--report]] [--format=json]\n"
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

/// --out DIR (docs/run-folder.md): DIR/summary.json {"command":"inflight-align","methods":
/// {"<method>":MethodResultJson,...}} and DIR/<method>/track.csv per method.
void WriteInflightRunFolder(const std::vector<MethodResult>& results) {
  EnsureFolder(FLAGS_out);
  for (const MethodResult& r : results) {
    const std::string dir = FLAGS_out + "/" + inflight::MethodName(r.method);
    EnsureFolder(dir);
    inflight::WriteTrackCsv(r, dir + "/track.csv");
  }
  AtomicFile summary(FLAGS_out + "/summary.json");
  summary.stream() << "{\"command\":\"inflight-align\",\"methods\":{";
  for (std::size_t i = 0; i < results.size(); ++i) {
    summary.stream() << (i ? "," : "") << '"' << inflight::MethodName(results[i].method)
                     << "\":" << inflight::MethodResultJson(results[i]);
  }
  summary.stream() << "}}\n";
  summary.Commit();
  std::cerr << "inflight-align: run folder " << FLAGS_out << " (summary.json, <method>/track.csv)\n";
}

int RunInflightAlign(const std::vector<std::string>& args) {
  const auto usage = [](const std::string& why) { return Usage("inflight-align", kAlignUsage, why); };
  if (!args.empty()) return usage("unexpected argument '" + args[0] + "'");
  if (FLAGS_method.empty()) return usage("--method is required (distance, kalman, batch or all)");
  if (FLAGS_report && FLAGS_out.empty()) return usage("--report needs --out DIR (it writes DIR/report.html)");
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
  if (!FLAGS_out.empty()) WriteInflightRunFolder(results);
  if (!FLAGS_out.empty() && FLAGS_report) WriteRunReport("inflight-align", FLAGS_out);
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

using inflight::McMethodStats;
using inflight::Moments;

/// Moments in the printed unit: mean, sigma and RMS times `scale`.
Moments Scaled(const Moments& m, double scale) { return {m.mean * scale, m.sigma * scale, m.rms * scale, m.count}; }

void PrintMcText(const std::string& header, const std::vector<McMethodStats>& stats, double wall_s) {
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
  for (const McMethodStats& s : stats) {
    for (int k = 0; k <= 4; ++k) {
      const Moments m = Scaled(k < 4 ? s.error_at_km_rad[k] : s.final_error_rad, kRadToArcmin);
      const std::string label = k < 4 ? std::to_string(static_cast<int>(kAtKm[k])) + " km" : "final";
      std::snprintf(line, sizeof line, "%-9s %-9s %10s %10s %10s %6d\n", inflight::MethodName(s.method),
                    label.c_str(), cell(m.mean).c_str(), cell(m.sigma).c_str(), cell(m.rms).c_str(), m.count);
      std::cout << line;
    }
    std::snprintf(line, sizeof line, "%-9s mean reported final sigma %s arcmin, mean run time %s s%s\n",
                  inflight::MethodName(s.method), cell(s.final_sigma_rad.mean * kRadToArcmin).c_str(),
                  cell(s.run_time_s.mean).c_str(),
                  s.failures ? (", " + std::to_string(s.failures) + " runs failed").c_str() : "");
    std::cout << line;
    if (s.failures) std::cout << "  first failure: " << s.first_failure << "\n";
  }
  std::snprintf(line, sizeof line, "wall time %.1f s ('-': no run reached the distance)\n", wall_s);
  std::cout << line;
}

void PrintMcJson(const std::string& scenario, const sim::Scenario& s, int runs, std::uint64_t seed,
                 const std::vector<McMethodStats>& stats, double wall_s) {
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
  for (const McMethodStats& st : stats) {
    w.Key(inflight::MethodName(st.method)).BeginObject();
    w.Key("final_heading_error_arcmin");
    moments(Scaled(st.final_error_rad, kRadToArcmin));
    w.Key("heading_error_arcmin_at_km").BeginObject();
    for (int k = 0; k < 4; ++k) {
      w.Key(std::to_string(static_cast<int>(kAtKm[k])));
      moments(Scaled(st.error_at_km_rad[k], kRadToArcmin));
    }
    w.EndObject();
    w.Field("mean_heading_sigma_arcmin", st.final_sigma_rad.mean * kRadToArcmin)
        .Field("mean_run_time_s", st.run_time_s.mean)
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
  inflight::McOptions options;
  options.runs = runs;
  options.seed = FLAGS_seed;
  options.threads = FLAGS_threads;
  options.methods = kAllMethods;
  options.at_km = kAtKm;
  options.progress = [](int done, int total) { std::fprintf(stderr, "inflight-mc: %d/%d runs\n", done, total); };
  const std::uint64_t seed = options.seed;
  std::cerr << "inflight-mc: " << runs << " runs of " << scenario.name << ", seeds " << seed << ".."
            << seed + runs - 1 << ", " << OutlierText(scenario) << "\n";
  const inflight::McResult mc = inflight::RunInflightMonteCarlo(scenario, config, options);
  const std::vector<McMethodStats>& stats = mc.stats;
  const double wall_s = mc.wall_time_s;
  if (!FLAGS_errors_csv.empty()) inflight::WriteMcErrorsCsv(mc, FLAGS_errors_csv);
  if (FLAGS_format == "json") {
    PrintMcJson(scenario_name, scenario, runs, seed, stats, wall_s);
  } else {
    char header[256];
    std::snprintf(header, sizeof header, "inflight-mc: %d runs of %s, seeds %llu..%llu, %s, %d thread%s", runs,
                  scenario.name.c_str(), static_cast<unsigned long long>(seed),
                  static_cast<unsigned long long>(seed + runs - 1), OutlierText(scenario).c_str(),
                  mc.workers, mc.workers == 1 ? "" : "s");
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
           "track_csv", "outlier_fraction", "outlier_m", "calibration", "imu_temperature_degC", "out", "report"},
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
