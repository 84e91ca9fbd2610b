// navtwin navigate / navtwin smooth: GNSS/INS/magnetometer navigation over a record.
//   navigate  the error-state filter (optionally followed by the RTS smoother), writing the
//             filter's real-time solution (or the RTS one) into --out;
//   smooth    filter, RTS and the full-batch Ceres smoother, writing the batch solution and
//             a summary comparing the three; --demo simulates a manoeuvring flight first.
// Outputs (problems/gnss_ins/output.h): nav.nav, nav.csv, std.csv, imu_errors.csv and
// summary.json, all or nothing. docs/gnss-ins.md describes configuration and outputs.
#include <gflags/gflags.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>


#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/atomic_file.h"
#include "core/io/input_error.h"
#include "core/io/json_writer.h"
#include "core/rotation.h"
#include "core/sim/presets.h"
#include "core/sim/scenario.h"
#include "core/sim/simulator.h"
// ins_state.h before config.h, which uses InsState.
#include "problems/gnss_ins/ins_state.h"
#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/batch.h"
#include "problems/gnss_ins/densify.h"
#include "problems/gnss_ins/filter.h"
#include "problems/gnss_ins/inputs.h"
#include "problems/gnss_ins/output.h"
#include "problems/gnss_ins/scoring.h"
#include "problems/gnss_ins/sim_config.h"

DEFINE_string(kfgins_config, "", "KF-GINS YAML configuration, taken unchanged (its imupath, gnsspath, outputpath are used when --imu, --gnss, --out are not given)");
DEFINE_string(smoother, "", "navigate: rts = write the RTS-smoothed solution instead of the filter's");
DEFINE_double(outage_start_s, NAN, "Injected GNSS outages for scoring: first outage start, s after the first IMU epoch");
DEFINE_double(outage_len_s, 0.0, "Injected GNSS outages: length of each, s");
DEFINE_double(outage_period_s, 0.0, "Injected GNSS outages: period, s (0: a single outage)");
DEFINE_string(demo_scenario, "mems-gps-mag-maneuver", "smooth --demo: the simulated scenario (a preset name or a scenario YAML)");
DEFINE_string(demo_mag, "vector", "smooth --demo: magnetometer use, off|vector|heading|heading_2axis");

namespace navtwin::app {
namespace {

using gnss_ins::GnssInsConfig;
using gnss_ins::Inputs;
using gnss_ins::NavEpoch;
using gnss_ins::ScoreReport;
using gnss_ins::Solution;

int Usage(const std::string& command, const std::string& why, const std::string& usage) {
  std::cerr << "navtwin " << command << ": " << why << "\nusage: " << usage << "\n";
  return kExitUsage;
}

bool IsDir(const std::string& dir) {
  struct stat st;
  return ::stat(dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

/// Whether a flag was given a value other than its default (compared as text: is_default
/// is false for a NaN default, NaN != NaN).
bool FlagSet(const char* name) {
  const gflags::CommandLineFlagInfo info = gflags::GetCommandLineFlagInfoOrDie(name);
  return info.current_value != info.default_value;
}

/// The output folder: created when missing, and removed again (if still empty) when the
/// run fails, so that a failed run leaves nothing behind.
class OutputFolder {
 public:
  explicit OutputFolder(std::string dir) : dir_(std::move(dir)) {}
  ~OutputFolder() {
    if (created_ && !keep_) ::rmdir(dir_.c_str());
  }
  bool Make() {
    if (IsDir(dir_)) return true;
    created_ = ::mkdir(dir_.c_str(), 0755) == 0;
    return created_;
  }
  void Keep() { keep_ = true; }

 private:
  std::string dir_;
  bool created_ = false;
  bool keep_ = false;
};

// ------------------------------------------------------------------------------------
// Demo: simulate the manoeuvring flight and write the configuration a user with a
// calibrated magnetometer would write.

struct RunFiles {
  std::string imu, gnss, mag, baro, config, kfgins_config, truth, out;
};

std::string Num(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
}

/// Simulates the demo scenario (--demo_scenario) into DIR/sim and writes the configuration
/// a user of it would write (gnss_ins::ConfigYamlForSimulation) to DIR/sim/navtwin.yaml.
RunFiles MakeDemo(const std::string& out) {
  const std::string sim_dir = out + "/sim";
  if (!IsDir(sim_dir) && ::mkdir(sim_dir.c_str(), 0755) != 0) {
    throw std::runtime_error("cannot create " + sim_dir);
  }
  const std::string name = FLAGS_demo_scenario;
  const sim::Scenario scenario = sim::LoadScenario(name);
  if (!scenario.gnss) throw std::runtime_error("--demo_scenario " + name + " has no GNSS");
  sim::SimulationOptions options;
  options.seed = FLAGS_seed;
  options.progress = [&name](double fraction) {
    std::fprintf(stderr, "\rsmooth --demo: simulating %s %3.0f %%", name.c_str(), 100.0 * fraction);
    if (fraction >= 1.0) std::fprintf(stderr, "\n");
  };
  sim::Simulate(scenario, options, sim_dir);
  const std::string yaml = gnss_ins::ConfigYamlForSimulation(scenario, sim_dir, FLAGS_seed, FLAGS_demo_mag);
  RunFiles f;
  f.config = sim_dir + "/navtwin.yaml";
  {
    AtomicFile file(f.config);
    file.stream() << yaml;
    file.Commit();
  }
  f.imu = sim_dir + "/imu.txt";
  f.gnss = sim_dir + "/gnss.txt";
  if (scenario.mag && FLAGS_demo_mag != "off") f.mag = sim_dir + "/mag.csv";
  f.truth = sim_dir + "/truth.nav";
  f.out = out;
  return f;
}

// ------------------------------------------------------------------------------------
// Reporting.

struct MethodResult {
  std::string name;
  const Solution* solution = nullptr;
  std::unique_ptr<gnss_ins::TrajectoryScorer> scorer;
};

void WriteStats(JsonWriter& w, const NavErrorStats& s, const ScoreReport& r) {
  static const char* const kKeys[9] = {"pos_n_m",   "pos_e_m",   "pos_d_m",   "vel_n_mps", "vel_e_mps",
                                       "vel_d_mps", "roll_deg",  "pitch_deg", "yaw_deg"};
  w.BeginObject().Field("epochs", s.count());
  for (int c = 0; c < 9; ++c) {
    if (c >= 3 && c < 6 && !r.has_velocity) continue;
    if (c >= 6 && !r.has_attitude) continue;
    const double scale = c >= 6 ? kRadToDeg : 1.0;
    w.Key(kKeys[c]).BeginObject().Field("rms", s.Rms(c) * scale).Field("max", s.Max(c) * scale).EndObject();
  }
  w.Key("horizontal_m").BeginObject().Field("rms", s.HorizontalRms_m()).Field("max", s.HorizontalMax_m()).EndObject();
  w.Key("vertical_m").BeginObject().Field("rms", s.Rms(2)).Field("max", s.Max(2)).EndObject();
  if (r.has_velocity) {
    w.Field("velocity_rms_mps", std::sqrt(s.Rms(3) * s.Rms(3) + s.Rms(4) * s.Rms(4) + s.Rms(5) * s.Rms(5)));
  }
  w.EndObject();
}

void WriteScore(JsonWriter& w, const ScoreReport& r) {
  w.BeginObject().Field("reference", r.has_attitude ? "navigation" : "gnss");
  w.Key("all");
  WriteStats(w, r.all, r);
  if (!r.outages.empty()) {
    w.Key("outside_outages");
    WriteStats(w, r.outside, r);
    w.Key("inside_outages");
    WriteStats(w, r.inside, r);
    w.Key("outages").BeginArray();
    for (const gnss_ins::OutageDrift& d : r.outages) {
      w.BeginObject()
          .Field("start_s", d.start_s)
          .Field("end_s", d.end_s)
          .Field("epochs", d.epochs)
          .Field("max_horizontal_m", d.max_horizontal_m)
          .Field("max_vertical_m", d.max_vertical_m)
          .EndObject();
    }
    w.EndArray();
    w.Field("outage_horizontal_rms_m", r.outage_horizontal_rms_m);
    w.Field("outage_vertical_rms_m", r.outage_vertical_rms_m);
  }
  w.EndObject();
}

struct RunContext {
  std::string command;
  RunFiles files;
  GnssInsConfig config;
  std::string output_method;
  std::size_t output_epochs = 0;
  double total_run_time_s = 0.0;
};

void WriteSummary(JsonWriter& w, const RunContext& ctx, const Inputs& in,
                  const std::vector<MethodResult>& methods) {
  w.BeginObject().Field("command", ctx.command).Field("output_method", ctx.output_method);
  w.Key("inputs")
      .BeginObject()
      .Field("imu", in.paths.imu)
      .Field("gnss", in.paths.gnss)
      .Field("mag", in.paths.mag)
      .Field("baro", in.paths.baro)
      .Field("config", ctx.files.config.empty() ? ctx.files.kfgins_config : ctx.files.config)
      .Field("imu_samples", in.imu.size())
      .Field("gnss_epochs", in.gnss.size())
      .Field("mag_samples", in.mag.size())
      .Field("baro_samples", in.baro.size())
      .Field("bridged_imu_gaps", in.bridged_imu_gaps)
      .Field("gnss_removed_by_outages", in.gnss_removed_by_outages)
      .Field("t_start_s", in.imu.front().t_s - in.imu.front().dt_s)
      .Field("t_end_s", in.imu.back().t_s)
      .EndObject();
  w.Key("outages").BeginArray();
  for (const auto& o : in.outages) w.BeginArray().Value(o.first).Value(o.second).EndArray();
  w.EndArray();
  w.Key("output")
      .BeginObject()
      .Field("dir", ctx.files.out)
      .Field("epochs", ctx.output_epochs)
      .Field("output_rate_hz", ctx.config.output_rate_hz)
      .EndObject();
  if (!ctx.files.truth.empty()) w.Field("truth", ctx.files.truth);
  w.Key("methods").BeginObject();
  for (const MethodResult& m : methods) {
    w.Key(m.name).BeginObject().Field("run_time_s", m.solution->run_time_s).Field("knots", m.solution->epochs.size());
    w.Key("counts").BeginObject();
    for (const auto& [key, count] : m.solution->counts) {
      w.Key(key).BeginObject().Field("used", count.used).Field("rejected", count.rejected).EndObject();
    }
    w.EndObject();
    if (!m.solution->solver_report.empty()) w.Field("solver_report", m.solution->solver_report);
    if (m.scorer) {
      w.Key("errors");
      WriteScore(w, m.scorer->Report());
    }
    w.EndObject();
  }
  w.EndObject();
  w.Field("total_run_time_s", ctx.total_run_time_s);
  w.EndObject();
}

void PrintTable(const RunContext& ctx, const Inputs& in, const std::vector<MethodResult>& methods) {
  std::printf("%s: %zu IMU samples, %zu GNSS epochs (%zu removed by %zu injected outages), "
              "%zu mag, %zu baro; %.1f .. %.1f s\n",
              ctx.command.c_str(), in.imu.size(), in.gnss.size(), in.gnss_removed_by_outages,
              in.outages.size(), in.mag.size(), in.baro.size(), in.imu.front().t_s - in.imu.front().dt_s,
              in.imu.back().t_s);
  std::printf("solution (%s): %s/{nav.nav, nav.csv, std.csv, imu_errors.csv, summary.json}, %zu epochs\n",
              ctx.output_method.c_str(), ctx.files.out.c_str(), ctx.output_epochs);
  const bool scored = !methods.empty() && methods.front().scorer != nullptr;
  if (!scored) {
    std::printf("%-7s %9s %9s\n", "method", "knots", "run [s]");
    for (const MethodResult& m : methods) {
      std::printf("%-7s %9zu %9.2f\n", m.name.c_str(), m.solution->epochs.size(), m.solution->run_time_s);
    }
    return;
  }
  const ScoreReport first = methods.front().scorer->Report();
  const bool outages = !first.outages.empty();
  std::printf("errors against %s (RMS over %zu reference epochs%s):\n", ctx.files.truth.c_str(),
              first.all.count(), outages ? "; drift = per-outage max, RMS over outages" : "");
  std::printf("%-7s %10s %10s %10s %10s %10s %10s", "method", "horiz [m]", "vert [m]", "vel [m/s]",
              "roll [deg]", "pitch[deg]", "yaw [deg]");
  if (outages) std::printf(" %10s %10s", "drift H[m]", "drift V[m]");
  std::printf(" %10s\n", "run [s]");
  for (const MethodResult& m : methods) {
    const ScoreReport r = m.scorer->Report();
    const NavErrorStats& s = r.all;
    auto cell = [](bool have, double x) {
      if (have) {
        std::printf(" %10.3f", x);
      } else {
        std::printf(" %10s", "-");
      }
    };
    std::printf("%-7s", m.name.c_str());
    cell(true, s.HorizontalRms_m());
    cell(true, s.Rms(2));
    cell(r.has_velocity, std::sqrt(s.Rms(3) * s.Rms(3) + s.Rms(4) * s.Rms(4) + s.Rms(5) * s.Rms(5)));
    cell(r.has_attitude, s.Rms(6) * kRadToDeg);
    cell(r.has_attitude, s.Rms(7) * kRadToDeg);
    cell(r.has_attitude, s.Rms(8) * kRadToDeg);
    if (outages) std::printf(" %10.3f %10.3f", r.outage_horizontal_rms_m, r.outage_vertical_rms_m);
    std::printf(" %10.2f\n", m.solution->run_time_s);
  }
}

// ------------------------------------------------------------------------------------
// The run.

struct Options {
  std::string command;  // "navigate" or "smooth"
  std::string usage;
};

int Run(const Options& opt, const std::vector<std::string>& args) {
  const auto usage = [&](const std::string& why) { return Usage(opt.command, why, opt.usage); };
  if (!args.empty()) return usage("unexpected argument '" + args[0] + "'");
  const bool smooth = opt.command == "smooth";
  RunFiles files;
  files.imu = FLAGS_imu;
  files.gnss = FLAGS_gnss;
  files.mag = FLAGS_mag;
  files.baro = FLAGS_baro;
  files.config = FLAGS_config;
  files.kfgins_config = FLAGS_kfgins_config;
  files.truth = FLAGS_truth;
  files.out = FLAGS_out;
  if (FLAGS_demo) {
    if (!files.imu.empty() || !files.gnss.empty() || !files.mag.empty() || !files.baro.empty() ||
        !files.config.empty() || !files.kfgins_config.empty() || !files.truth.empty()) {
      return usage("--demo makes its own --imu, --gnss, --mag, --config and --truth");
    }
    if (files.out.empty()) return usage("--out is required");
  } else if (files.config.empty() == files.kfgins_config.empty()) {
    return usage("give exactly one of --config YAML and --kfgins_config YAML");
  }
  if (!smooth && !FLAGS_smoother.empty() && FLAGS_smoother != "rts") {
    return usage("--smoother must be rts (or absent)");
  }
  if (FLAGS_output_rate_hz < 0.0) return usage("--output_rate_hz must be >= 0");
  if (FLAGS_calibration.empty() && !std::isnan(FLAGS_imu_temperature_degC)) {
    return usage("--imu_temperature_degC goes with --calibration");
  }
  const bool outage_flags = FlagSet("outage_start_s") || FlagSet("outage_len_s") || FlagSet("outage_period_s");
  if (outage_flags) {
    if (std::isnan(FLAGS_outage_start_s) || !(FLAGS_outage_len_s > 0.0) || FLAGS_outage_start_s < 0.0) {
      return usage("outages need --outage_start_s >= 0 and --outage_len_s > 0");
    }
    if (FLAGS_outage_period_s < 0.0 || (FLAGS_outage_period_s > 0.0 && FLAGS_outage_period_s <= FLAGS_outage_len_s)) {
      return usage("--outage_period_s must be 0 (one outage) or longer than --outage_len_s");
    }
  }

  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<OutputFolder> folder;
  if (FLAGS_demo) {
    folder = std::make_unique<OutputFolder>(files.out);
    if (!folder->Make()) return usage("cannot create the output folder " + files.out);
    folder->Keep();  // the simulated files stay
    files = MakeDemo(files.out);
  }

  RunContext ctx;
  ctx.command = opt.command;
  if (!files.config.empty()) {
    ctx.config = gnss_ins::LoadGnssInsConfig(files.config);
  } else {
    ctx.config = gnss_ins::LoadKfginsConfig(files.kfgins_config);
    if (files.imu.empty()) files.imu = ctx.config.imu_path;
    if (files.gnss.empty()) files.gnss = ctx.config.gnss_path;
    if (files.out.empty()) files.out = ctx.config.output_path;
  }
  GnssInsConfig& config = ctx.config;
  if (files.imu.empty()) return usage("--imu is required");
  if (files.gnss.empty()) return usage("--gnss is required");
  if (files.out.empty()) return usage("--out is required");
  if (config.mag.mode != gnss_ins::MagConfig::Mode::kOff && files.mag.empty()) {
    return usage("the configuration uses a magnetometer (mag.mode): give --mag");
  }
  if (config.mag.mode == gnss_ins::MagConfig::Mode::kOff && !files.mag.empty()) {
    std::cerr << opt.command << ": warning: --mag is not used (the configuration has mag.mode off)\n";
    files.mag.clear();
  }
  if (config.baro.use && files.baro.empty()) return usage("the configuration uses a barometer (baro.use): give --baro");
  if (!config.baro.use && !files.baro.empty()) {
    std::cerr << opt.command << ": warning: --baro is not used (the configuration has no baro.use)\n";
    files.baro.clear();
  }
  if (FlagSet("output_rate_hz")) config.output_rate_hz = FLAGS_output_rate_hz;
  if (!std::isnan(FLAGS_start_s)) {
    // A given initial state was picked for the configuration's start: it must agree.
    if (config.init.state && !std::isnan(config.init.state->nav.t_s) &&
        std::abs(config.init.state->nav.t_s - FLAGS_start_s) > 1e-6) {
      return usage("--start_s " + Num(FLAGS_start_s) + " differs from the time of the given initial state (" +
                   Num(config.init.state->nav.t_s) + " s): set start_s (KF-GINS: starttime) in the configuration");
    }
    config.start_time_s = FLAGS_start_s;
  }
  if (std::isfinite(FLAGS_end_s)) config.end_time_s = FLAGS_end_s;
  if (outage_flags) {
    config.outages.start_s = FLAGS_outage_start_s;
    config.outages.len_s = FLAGS_outage_len_s;
    config.outages.period_s = FLAGS_outage_period_s;
  }
  ctx.files = files;

  if (!folder) folder = std::make_unique<OutputFolder>(files.out);
  if (!folder->Make()) return usage("cannot create the output folder " + files.out);

  std::cerr << opt.command << ": reading " << files.imu << ", " << files.gnss
            << (files.mag.empty() ? "" : ", " + files.mag) << (files.baro.empty() ? "" : ", " + files.baro)
            << "\n";
  gnss_ins::InputPaths paths{files.imu, files.gnss, files.mag, files.baro, FLAGS_calibration,
                             FLAGS_imu_temperature_degC};
  const Inputs inputs = gnss_ins::LoadInputs(paths, config);
  if (config.init.state && std::isnan(config.init.state->nav.t_s)) {
    // A given initial state without a time: the start of the first IMU interval.
    config.init.state->nav.t_s = inputs.imu.front().t_s - inputs.imu.front().dt_s;
  }
  if (inputs.bridged_imu_gaps > 0) {
    std::cerr << opt.command << ": bridged " << inputs.bridged_imu_gaps << " short IMU gap(s)\n";
  }

  auto open_scorer = [&]() -> std::unique_ptr<gnss_ins::TrajectoryScorer> {
    if (files.truth.empty()) return nullptr;
    return gnss_ins::OpenReference(files.truth, inputs.outages, config.installation.antenna_lever_arm_b_m);
  };
  gnss_ins::NavOutputWriter writer(files.out, config.filter.scale_factors);
  auto write = [&](const NavEpoch& e) { writer.Write(e); };

  std::vector<MethodResult> methods;
  // The filter: its real-time output is scored (and written by plain `navigate`).
  MethodResult filter{"filter", nullptr, open_scorer()};
  const bool write_filter = !smooth && FLAGS_smoother.empty();
  const bool run_rts = smooth || FLAGS_smoother == "rts";
  std::cerr << opt.command << ": filter" << (run_rts ? " + RTS smoother" : "") << "\n";
  const gnss_ins::FilterResult fr = gnss_ins::RunFilter(
      inputs, config, run_rts,
      [&](const NavEpoch& e) {
        if (filter.scorer) filter.scorer->Add(e.state.nav);
        if (write_filter) write(e);
      },
      &std::cerr);
  filter.solution = &fr.filter;
  methods.push_back(std::move(filter));
  ctx.output_method = "filter";

  std::optional<Solution> batch;
  if (run_rts) {
    if (!fr.rts) throw std::runtime_error("the filter returned no RTS solution");
    MethodResult rts{"rts", &*fr.rts, open_scorer()};
    gnss_ins::Densify(*fr.rts, inputs, config.output_rate_hz, [&](const NavEpoch& e) {
      if (rts.scorer) rts.scorer->Add(e.state.nav);
      if (!smooth) write(e);
    });
    methods.push_back(std::move(rts));
    ctx.output_method = "rts";
  }
  if (smooth) {
    std::cerr << "smooth: batch smoother (Ceres) started from the RTS solution\n";
    batch = gnss_ins::RunBatch(inputs, config, *fr.rts, &std::cerr);
    MethodResult b{"batch", &*batch, open_scorer()};
    gnss_ins::Densify(*batch, inputs, config.output_rate_hz, [&](const NavEpoch& e) {
      if (b.scorer) b.scorer->Add(e.state.nav);
      write(e);
    });
    methods.push_back(std::move(b));
    ctx.output_method = "batch";
  }
  ctx.output_epochs = writer.count();
  if (ctx.output_epochs == 0) throw std::runtime_error("the run produced no output epoch");
  ctx.total_run_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // summary.json first (it can still fail), then the solution files.
  const std::string summary = files.out + "/summary.json";
  gnss_ins::WriteJsonFile(summary, [&](JsonWriter& w) { WriteSummary(w, ctx, inputs, methods); });
  try {
    writer.Commit();
  } catch (...) {
    std::remove(summary.c_str());
    throw;
  }
  folder->Keep();
  if (FLAGS_format == "json") {
    JsonWriter w(std::cout);
    WriteSummary(w, ctx, inputs, methods);
    std::cout << "\n";
  } else {
    PrintTable(ctx, inputs, methods);
  }
  return kExitOk;
}

const char* const kNavigateUsage =
    "navtwin navigate --imu F --gnss F [--mag F] [--baro F] (--config YAML | --kfgins_config YAML) "
    "--out DIR [--smoother=rts] [--truth F] [--output_rate_hz R] [--outage_start_s S --outage_len_s L "
    "[--outage_period_s P]] [--start_s S] [--end_s S] [--calibration FILE [--imu_temperature_degC T]] "
    "[--format=json]";
const char* const kSmoothUsage =
    "navtwin smooth --imu F --gnss F [--mag F] [--baro F] (--config YAML | --kfgins_config YAML) "
    "--out DIR [--truth F] [--output_rate_hz R] [--outage_start_s S --outage_len_s L "
    "[--outage_period_s P]] [--start_s S] [--end_s S] [--calibration FILE [--imu_temperature_degC T]] "
    "[--format=json]\n"
    "       navtwin smooth --demo --out DIR [--demo_scenario NAME] [--demo_mag MODE] [--seed N] [outage flags]";

int RunNavigate(const std::vector<std::string>& args) { return Run({"navigate", kNavigateUsage}, args); }
int RunSmooth(const std::vector<std::string>& args) { return Run({"smooth", kSmoothUsage}, args); }

}  // namespace

Command NavigateCommand() {
  return {"navigate",
          "GNSS/INS/magnetometer error-state Kalman filter (and RTS smoother) over a record",
          kNavigateUsage,
          {"imu", "gnss", "mag", "baro", "config", "kfgins_config", "out", "smoother", "truth",
           "output_rate_hz", "outage_start_s", "outage_len_s", "outage_period_s", "start_s", "end_s",
           "calibration", "imu_temperature_degC"},
          &RunNavigate};
}

Command SmoothCommand() {
  return {"smooth",
          "Filter, RTS and full-batch Ceres smoother over a record; prints the comparison table",
          kSmoothUsage,
          {"imu", "gnss", "mag", "baro", "config", "kfgins_config", "out", "truth", "output_rate_hz",
           "outage_start_s", "outage_len_s", "outage_period_s", "start_s", "end_s", "demo", "seed",
           "demo_scenario", "demo_mag", "calibration", "imu_temperature_degC"},
          &RunSmooth};
}

}  // namespace navtwin::app
