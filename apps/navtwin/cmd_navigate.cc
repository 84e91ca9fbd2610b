// navtwin navigate / navtwin smooth: GNSS/INS/magnetometer navigation over a record.
//   navigate  the error-state filter (optionally followed by the RTS smoother), writing the
//             filter's real-time solution (or the RTS one) into --out;
//   smooth    filter, RTS and the full-batch Ceres smoother, writing the batch solution and
//             a summary comparing the three; --demo simulates a manoeuvring flight first.
// The run itself is problems/gnss_ins/run.h; its outputs: nav.nav, nav.csv, std.csv,
// imu_errors.csv and summary.json, all or nothing. docs/gnss-ins.md describes configuration
// and outputs.
#include <gflags/gflags.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/folder.h"
#include "core/io/json_writer.h"
#include "core/io/open.h"
#include "core/io/ulog_time.h"
#include "core/units.h"
#include "problems/gnss_ins/run.h"
#include "problems/report/report.h"

DEFINE_string(kfgins_config, "", "KF-GINS YAML configuration, taken unchanged (its imupath, gnsspath, outputpath are used when --imu, --gnss, --out are not given)");
DEFINE_string(obgins_config, "", "OB_GINS YAML configuration, taken unchanged (its imufile, gnssfile, outputpath are used when --imu, --gnss, --out are not given; with odometer.isuseodo the IMU file's odometer column and the NHC)");
DEFINE_string(smoother, "", "navigate: rts = write the RTS-smoothed solution instead of the filter's");
DEFINE_double(outage_start_s, NAN, "Injected GNSS outages for scoring: first outage start, s after the first IMU epoch");
DEFINE_double(outage_len_s, 0.0, "Injected GNSS outages: length of each, s");
DEFINE_double(outage_period_s, 0.0, "Injected GNSS outages: period, s (0: a single outage)");
DEFINE_string(demo_scenario, "mems-gps-mag-maneuver", "smooth --demo: the simulated scenario (a preset name or a scenario YAML)");
DEFINE_bool(nhc, false, "Ground vehicles: the non-holonomic constraint (no lateral or vertical velocity of the vehicle reference point), on top of --config, --kfgins_config or --obgins_config");
DEFINE_double(nhc_sigma_mps, NAN, "Sigma of the non-holonomic constraint, m/s (default: the configuration's nhc.std_mps, 0.1)");
DEFINE_string(odometer, "", "Wheel-odometer file (t_s,speed_mps or t_s,distance_m): the forward speed of the vehicle reference point, its scale factor estimated (default: the configuration's odometer.file)");
DEFINE_string(vehicle_mounting_rpy_deg, "", "Roll,pitch,yaw of the IMU (body) axes in the vehicle frame, deg, e.g. 0,0,1.5 (default: the configuration's vehicle.mounting_rpy_deg)");
DEFINE_string(vehicle_lever_arm_b_m, "", "x,y,z of the vehicle reference point (where NHC holds and the odometer measures) from the IMU, body axes, m (default: the configuration's vehicle.lever_arm_b_m)");
DEFINE_double(gate_probability, NAN, "Filter: probability of the chi-square gate on each innovation, in (0, 1] (1: no gate; default: the configuration's filter.gate_probability, 0.9999, or 1 for a KF-GINS configuration)");
DEFINE_bool(variance_components, true, "smooth: estimate each residual group's noise scale in the batch (variance components); false keeps the configured noise");
DEFINE_bool(strict, false, "Exit with code 3 when the run reports warnings (rejections over 10 %, resets, chi2/dof over 3, inconsistent sigma); the outputs are written either way");
DEFINE_bool(report, false, "After a successful run, write report.html into its run folder (--out DIR; calibrate-imu, calibrate-mag: --run_dir DIR), as navtwin report DIR makes it");
DEFINE_string(demo_mag, "vector", "smooth --demo: magnetometer use, off|vector|heading|heading_2axis");

namespace navtwin::app {
namespace {

using gnss_ins::GnssInsConfig;

int Usage(const std::string& command, const std::string& why, const std::string& usage) {
  std::cerr << "navtwin " << command << ": " << why << "\nusage: " << usage << "\n";
  return kExitUsage;
}

std::string Num(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
}

/// "x,y,z" as three finite numbers (false when it is not).
bool ParseTriple(const std::string& text, Eigen::Vector3d* out) {
  std::istringstream in(text);
  for (int i = 0; i < 3; ++i) {
    std::string field;
    if (!std::getline(in, field, ',')) return false;
    std::istringstream number(field);
    double v = 0.0;
    if (!(number >> v) || !(number >> std::ws).eof() || !std::isfinite(v)) return false;
    (*out)[i] = v;
  }
  std::string rest;
  return !std::getline(in, rest);
}

/// The vehicle-constraint flags applied on top of the configuration; empty, or what is
/// wrong with their values.
std::string ApplyVehicleFlags(GnssInsConfig* config) {
  if (FLAGS_nhc) config->nhc.enabled = true;
  if (!std::isnan(FLAGS_nhc_sigma_mps)) {
    if (!(FLAGS_nhc_sigma_mps > 0.0) || !std::isfinite(FLAGS_nhc_sigma_mps)) return "--nhc_sigma_mps must be > 0";
    config->nhc.std_mps = FLAGS_nhc_sigma_mps;
  }
  if (!FLAGS_odometer.empty()) config->odometer.file = FLAGS_odometer;
  if (!FLAGS_vehicle_mounting_rpy_deg.empty()) {
    Eigen::Vector3d rpy_deg;
    if (!ParseTriple(FLAGS_vehicle_mounting_rpy_deg, &rpy_deg)) {
      return "--vehicle_mounting_rpy_deg must be three numbers roll,pitch,yaw";
    }
    config->vehicle.mounting_rpy_rad = rpy_deg * kDegToRad;
  }
  if (!FLAGS_vehicle_lever_arm_b_m.empty() &&
      !ParseTriple(FLAGS_vehicle_lever_arm_b_m, &config->vehicle.lever_arm_b_m)) {
    return "--vehicle_lever_arm_b_m must be three numbers x,y,z";
  }
  return "";
}

struct Files {
  std::string imu, gnss, mag, baro, config, kfgins_config, obgins_config, truth, out;
};

struct Options {
  std::string command;  // "navigate" or "smooth"
  std::string usage;
};

/// The flags' checks that need no file; empty, or what is wrong.
std::string CheckFlags(const Options& opt, const Files& files) {
  const bool smooth = opt.command == "smooth";
  if (FLAGS_demo) {
    if (!files.imu.empty() || !files.gnss.empty() || !files.mag.empty() || !files.baro.empty() ||
        !files.config.empty() || !files.kfgins_config.empty() || !files.obgins_config.empty() ||
        !files.truth.empty() || !FLAGS_init_from.empty()) {
      return "--demo makes its own --imu, --gnss, --mag, --config, --truth and initial state";
    }
    if (files.out.empty()) return "--out is required";
  } else if (files.config.empty() + files.kfgins_config.empty() + files.obgins_config.empty() != 2) {
    return "give exactly one of --config YAML, --kfgins_config YAML and --obgins_config YAML";
  }
  if (!smooth && !FLAGS_smoother.empty() && FLAGS_smoother != "rts") return "--smoother must be rts (or absent)";
  if (FLAGS_output_rate_hz < 0.0) return "--output_rate_hz must be >= 0";
  if (!(FLAGS_std_rate_hz >= 0.0)) return "--std_rate_hz must be >= 0";
  if (FlagGiven("gate_probability") && !(FLAGS_gate_probability > 0.0 && FLAGS_gate_probability <= 1.0)) {
    return "--gate_probability must be in (0, 1] (1: no gate)";
  }
  if (!smooth && FlagGiven("variance_components")) return "--variance_components goes with smooth (the batch)";
  if (FLAGS_calibration.empty() && !std::isnan(FLAGS_imu_temperature_degC)) {
    return "--imu_temperature_degC goes with --calibration";
  }
  if (FlagGiven("outage_start_s") || FlagGiven("outage_len_s") || FlagGiven("outage_period_s")) {
    if (std::isnan(FLAGS_outage_start_s) || !(FLAGS_outage_len_s > 0.0) || FLAGS_outage_start_s < 0.0) {
      return "outages need --outage_start_s >= 0 and --outage_len_s > 0";
    }
    if (FLAGS_outage_period_s < 0.0 || (FLAGS_outage_period_s > 0.0 && FLAGS_outage_period_s <= FLAGS_outage_len_s)) {
      return "--outage_period_s must be 0 (one outage) or longer than --outage_len_s";
    }
  }
  return "";
}

/// The configuration file with the flags applied, and the files it names where the flags
/// do not; empty error, or what is wrong with the command line.
std::string ResolveConfig(const Options& opt, Files* files, GnssInsConfig* config) {
  if (!files->config.empty()) {
    *config = gnss_ins::LoadGnssInsConfig(files->config, !FLAGS_init_from.empty());
  } else {
    *config = files->kfgins_config.empty() ? gnss_ins::LoadObginsConfig(files->obgins_config)
                                           : gnss_ins::LoadKfginsConfig(files->kfgins_config);
    if (files->imu.empty()) files->imu = config->imu_path;
    if (files->gnss.empty()) files->gnss = config->gnss_path;
    if (files->out.empty()) files->out = config->output_path;
  }
  if (files->imu.empty()) return "--imu is required";
  if (files->gnss.empty()) return "--gnss is required";
  if (files->out.empty()) return "--out is required";
  const bool mag_used = config->mag.mode != gnss_ins::MagConfig::Mode::kOff;
  if (mag_used && files->mag.empty()) return "the configuration uses a magnetometer (mag.mode): give --mag";
  if (!mag_used && !files->mag.empty()) {
    std::cerr << opt.command << ": warning: --mag is not used (the configuration has mag.mode off)\n";
    files->mag.clear();
  }
  if (config->baro.use && files->baro.empty()) return "the configuration uses a barometer (baro.use): give --baro";
  if (!config->baro.use && !files->baro.empty()) {
    std::cerr << opt.command << ": warning: --baro is not used (the configuration has no baro.use)\n";
    files->baro.clear();
  }
  if (FlagGiven("output_rate_hz")) config->output_rate_hz = FLAGS_output_rate_hz;
  if (FlagGiven("std_rate_hz")) config->std_rate_hz = FLAGS_std_rate_hz;
  if (!FLAGS_init_from.empty()) {
    // The record is picked once the inputs are read (InitConfig::nav_file_at_start): without
    // --start_s, at the start of the IMU record on the reference's time scale.
    config->init.source = gnss_ins::InitConfig::Source::kGiven;
    config->init.state.reset();
    config->init.nav_file_at_start = FLAGS_init_from;
  }
  if (!std::isnan(FLAGS_start_s)) {
    // A given initial state was picked for the configuration's start: it must agree.
    if (config->init.state && !std::isnan(config->init.state->nav.t_s) &&
        std::abs(config->init.state->nav.t_s - FLAGS_start_s) > 1e-6) {
      return "--start_s " + Num(FLAGS_start_s) + " differs from the time of the given initial state (" +
             Num(config->init.state->nav.t_s) + " s): set start_s (KF-GINS: starttime) in the configuration";
    }
    config->start_time_s = FLAGS_start_s;
  }
  if (std::isfinite(FLAGS_end_s)) config->end_time_s = FLAGS_end_s;
  if (FlagGiven("gate_probability")) config->filter.gate_probability = FLAGS_gate_probability;
  if (FlagGiven("variance_components")) config->batch.variance_components = FLAGS_variance_components;
  if (FlagGiven("outage_start_s") || FlagGiven("outage_len_s") || FlagGiven("outage_period_s")) {
    config->outages.start_s = FLAGS_outage_start_s;
    config->outages.len_s = FLAGS_outage_len_s;
    config->outages.period_s = FLAGS_outage_period_s;
  }
  return ApplyVehicleFlags(config);
}

/// For every ULog among the inputs, its time scale (GPS time or boot time) on stderr,
/// once per file: a log without GPS time cannot be compared with anything on GPS time.
void ReportULogTimes(const Options& opt, const Files& files) {
  std::set<std::string> seen;
  for (const std::string* path : {&files.imu, &files.gnss, &files.mag, &files.baro, &files.truth}) {
    if (path->empty() || !seen.insert(*path).second) continue;
    if (DetectFormat(*path) != FileFormat::kULog) continue;
    std::cerr << opt.command << ": " << *path << ": " << FindULogClock(*path).Describe() << "\n";
  }
}

gnss_ins::RunMethods MethodsFromFlags(const Options& opt) {
  if (opt.command == "smooth") return gnss_ins::RunMethods::kAll;
  return FLAGS_smoother == "rts" ? gnss_ins::RunMethods::kFilterRts : gnss_ins::RunMethods::kFilter;
}

int Run(const Options& opt, const std::vector<std::string>& args) {
  const auto usage = [&](const std::string& why) { return Usage(opt.command, why, opt.usage); };
  if (!args.empty()) return usage("unexpected argument '" + args[0] + "'");
  Files files{FLAGS_imu,           FLAGS_gnss,          FLAGS_mag,   FLAGS_baro, FLAGS_config,
              FLAGS_kfgins_config, FLAGS_obgins_config, FLAGS_truth, FLAGS_out};
  const std::string flag_error = CheckFlags(opt, files);
  if (!flag_error.empty()) return usage(flag_error);

  std::unique_ptr<OutputFolder> folder;
  if (FLAGS_demo) {
    folder = std::make_unique<OutputFolder>(files.out);
    if (!folder->Make()) return usage("cannot create the output folder " + files.out);
    folder->Keep();  // the simulated files stay
    const gnss_ins::DemoFiles demo =
        gnss_ins::SimulateDemo(FLAGS_demo_scenario, FLAGS_seed, FLAGS_demo_mag, files.out + "/sim", &std::cerr);
    files.imu = demo.imu;
    files.gnss = demo.gnss;
    files.mag = demo.mag;
    files.truth = demo.truth;
    files.config = demo.config;
  }
  GnssInsConfig config;
  const std::string config_error = ResolveConfig(opt, &files, &config);
  if (!config_error.empty()) return usage(config_error);
  ReportULogTimes(opt, files);
  if (!folder) folder = std::make_unique<OutputFolder>(files.out);
  if (!folder->Make()) return usage("cannot create the output folder " + files.out);

  gnss_ins::RunOptions run_options;
  run_options.paths = {files.imu, files.gnss, files.mag, files.baro, FLAGS_calibration, FLAGS_imu_temperature_degC};
  run_options.truth = files.truth;
  run_options.out_dir = files.out;
  run_options.config_path =
      !files.config.empty() ? files.config : (!files.kfgins_config.empty() ? files.kfgins_config : files.obgins_config);
  run_options.command = opt.command;
  run_options.methods = MethodsFromFlags(opt);
  run_options.progress = &std::cerr;
  const gnss_ins::GnssInsRun run = gnss_ins::RunGnssIns(run_options, config);
  folder->Keep();
  if (FLAGS_format == "json") {
    JsonWriter w(std::cout);
    gnss_ins::WriteRunSummary(w, run_options, run);
    std::cout << "\n";
  } else {
    std::cout << gnss_ins::RunTable(run_options, run);
  }
  if (FLAGS_report) WriteRunReport(opt.command, files.out);
  return FLAGS_strict && !run.warnings.empty() ? kExitWarnings : kExitOk;
}

const char* const kNavigateUsage =
    "navtwin navigate --imu F --gnss F [--mag F] [--baro F] (--config YAML | --kfgins_config YAML | --obgins_config YAML) "
    "--out DIR [--smoother=rts] [--truth F] [--output_rate_hz R] [--std_rate_hz R] [--outage_start_s S --outage_len_s L "
    "[--outage_period_s P]] [--start_s S] [--end_s S] [--init_from NAV] [--calibration FILE [--imu_temperature_degC T]] "
    "[--nhc [--nhc_sigma_mps S]] [--odometer F] [--vehicle_mounting_rpy_deg R,P,Y] [--vehicle_lever_arm_b_m X,Y,Z] "
    "[--gate_probability P] [--strict] [--report] [--format=json]";
const char* const kSmoothUsage =
    "navtwin smooth --imu F --gnss F [--mag F] [--baro F] (--config YAML | --kfgins_config YAML | --obgins_config YAML) "
    "--out DIR [--truth F] [--output_rate_hz R] [--std_rate_hz R] [--outage_start_s S --outage_len_s L "
    "[--outage_period_s P]] [--start_s S] [--end_s S] [--init_from NAV] [--calibration FILE [--imu_temperature_degC T]] "
    "[--nhc [--nhc_sigma_mps S]] [--odometer F] [--vehicle_mounting_rpy_deg R,P,Y] [--vehicle_lever_arm_b_m X,Y,Z] "
    "[--gate_probability P] [--variance_components=false] [--strict] [--report] [--format=json]\n"
    "       navtwin smooth --demo --out DIR [--demo_scenario NAME] [--demo_mag MODE] [--seed N] [outage flags] [--report]";

int RunNavigate(const std::vector<std::string>& args) { return Run({"navigate", kNavigateUsage}, args); }
int RunSmooth(const std::vector<std::string>& args) { return Run({"smooth", kSmoothUsage}, args); }

}  // namespace

Command NavigateCommand() {
  return {"navigate",
          "GNSS/INS/magnetometer error-state Kalman filter (and RTS smoother) over a record",
          kNavigateUsage,
          {"imu", "gnss", "mag", "baro", "config", "kfgins_config", "obgins_config", "out", "smoother", "truth",
           "output_rate_hz", "std_rate_hz", "outage_start_s", "outage_len_s", "outage_period_s", "start_s", "end_s",
           "calibration", "imu_temperature_degC", "init_from", "nhc", "nhc_sigma_mps", "odometer", "vehicle_mounting_rpy_deg",
           "vehicle_lever_arm_b_m", "gate_probability", "strict", "report"},
          &RunNavigate};
}

Command SmoothCommand() {
  return {"smooth",
          "Filter, RTS and full-batch Ceres smoother over a record; prints the comparison table",
          kSmoothUsage,
          {"imu", "gnss", "mag", "baro", "config", "kfgins_config", "obgins_config", "out", "truth", "output_rate_hz", "std_rate_hz",
           "outage_start_s", "outage_len_s", "outage_period_s", "start_s", "end_s", "demo", "seed",
           "demo_scenario", "demo_mag", "calibration", "imu_temperature_degC", "init_from", "nhc", "nhc_sigma_mps",
           "odometer", "vehicle_mounting_rpy_deg", "vehicle_lever_arm_b_m", "gate_probability",
           "variance_components", "strict", "report"},
          &RunSmooth};
}

}  // namespace navtwin::app
