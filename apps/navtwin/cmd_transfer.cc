// navtwin transfer-align: transfer alignment of a slave IMU to a master INS with the
// misalignment and the transfer delay estimated (seed 002, issue 6;
// problems/transfer_alignment). Runs order1 (delay compensated with the angular rate
// only), order2 (angular rate, angular acceleration and acceleration), history (the slave's
// own state at the record's data time, delayed-state fusion), batch (the Ceres twin) or all
// four, on recorded files or on a simulated scenario, and prints the slave
// attitude error (roll, pitch, heading RMS / max, mrad) when the truth is known, the delay
// with its sigma and the misalignment.
#include <gflags/gflags.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/sim/scenario.h"
#include "problems/transfer_alignment/config.h"
#include "problems/transfer_alignment/inputs.h"
#include "problems/transfer_alignment/run.h"

DEFINE_string(master, "", "transfer-align: master INS navigation records as received (time tag = arrival)");
DEFINE_string(slave_imu, "", "transfer-align: slave IMU file (its own axes, on the master's time scale)");
DEFINE_double(delay_s, NAN, "transfer-align --scenario: transfer delay of the simulated master, s (default: the scenario's)");

namespace navtwin::app {
namespace {

using transfer::Method;
using transfer::TransferConfig;
using transfer::TransferInputs;
using transfer::TransferResult;

const char* kUsage =
    "navtwin transfer-align --master F --slave_imu F --init_from NAV [--start_s T] [--truth NAV] "
    "[--calibration FILE [--imu_temperature_degC T]] [--config YAML] --method order1|order2|history|batch|all [--out DIR [--report]] [--format=json]\n"
    "       navtwin transfer-align --scenario PRESET|YAML [--seed S] [--delay_s X] [--config YAML] "
    "--method order1|order2|history|batch|all [--out DIR [--report]] [--format=json]\n"
    "  The slave starts from the record of --init_from at or after --start_s (default: the start of the\n"
    "  slave IMU data), its mounting unknown (identity guess). Attitude errors need --truth (a scenario\n"
    "  brings its own, with the true mounting and delay). Configuration keys: data/configs/\n"
    "  transfer-alignment-high-maneuver.yaml. --method all runs the four (JSON: an array of four objects).\n"
    "  --out DIR writes the run folder: summary.json and per method the estimates and attitude errors\n"
    "  against time (docs/run-folder.md).";

int Usage(const std::string& why) {
  std::cerr << "navtwin transfer-align: " << why << "\nusage: " << kUsage << "\n";
  return kExitUsage;
}

int RunTransferAlign(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("unexpected argument '" + args[0] + "'");
  if (FLAGS_method.empty()) return Usage("--method is required (order1, order2, history, batch or all)");
  if (FLAGS_report && FLAGS_out.empty()) return Usage("--report needs --out DIR (it writes DIR/report.html)");
  std::vector<Method> methods;
  if (FLAGS_method == "all") {
    methods = {Method::kOrder1, Method::kOrder2, Method::kHistory, Method::kBatch};
  } else {
    try {
      methods = {transfer::ParseMethod(FLAGS_method)};
    } catch (const std::invalid_argument&) {
      return Usage("--method must be order1, order2, history, batch or all, got '" + FLAGS_method + "'");
    }
  }
  const bool scenario = !FLAGS_scenario.empty();
  if (scenario) {
    for (const char* flag : {"master", "slave_imu", "init_from", "start_s", "truth", "calibration", "imu_temperature_degC"}) {
      if (FlagGiven(flag)) return Usage(std::string("--scenario simulates its own files: drop --") + flag);
    }
    if (FlagGiven("delay_s") && !(std::isfinite(FLAGS_delay_s) && FLAGS_delay_s >= 0.0)) {
      return Usage("--delay_s must be a delay >= 0, s");
    }
  } else {
    if (FLAGS_master.empty() || FLAGS_slave_imu.empty()) return Usage("--master and --slave_imu are required (or --scenario)");
    if (FLAGS_init_from.empty()) return Usage("--init_from NAV is required: the slave INS's initial state");
    if (FlagGiven("seed")) return Usage("--seed goes with --scenario");
    if (FlagGiven("delay_s")) return Usage("--delay_s goes with --scenario");
    if (!std::isnan(FLAGS_start_s) && !std::isfinite(FLAGS_start_s)) return Usage("--start_s must be a time, s");
    if (FLAGS_calibration.empty() && FlagGiven("imu_temperature_degC")) {
      return Usage("--imu_temperature_degC goes with --calibration");
    }
  }

  const TransferConfig config = FLAGS_config.empty() ? TransferConfig() : transfer::LoadTransferConfig(FLAGS_config);
  TransferInputs inputs;
  if (scenario) {
    const sim::Scenario s = sim::LoadScenario(FLAGS_scenario);
    if (!s.master) throw std::invalid_argument("scenario " + s.name + " has no master section (transfer alignment needs one)");
    const std::optional<double> delay = FlagGiven("delay_s") ? std::optional<double>(FLAGS_delay_s) : std::nullopt;
    std::fprintf(stderr, "transfer-align: simulating %s (seed %llu, transfer delay %g s)\n", s.name.c_str(),
                 static_cast<unsigned long long>(FLAGS_seed), delay ? *delay : s.master->transfer_delay_s);
    inputs = transfer::SimulateTransferInputs(s, FLAGS_seed, delay);
  } else {
    transfer::TransferFiles files;
    files.slave_imu = FLAGS_slave_imu;
    files.master = FLAGS_master;
    files.init = FLAGS_init_from;
    files.init_time_s = std::isnan(FLAGS_start_s) ? -1.0 : FLAGS_start_s;
    files.truth = FLAGS_truth;
    files.calibration = FLAGS_calibration;
    files.imu_temperature_degC = FLAGS_imu_temperature_degC;
    inputs = transfer::LoadTransferInputs(files);
  }
  if (inputs.truth.empty()) std::cerr << "transfer-align: no --truth: attitude errors are not known (printed as -)\n";

  std::vector<TransferResult> results;
  for (const Method m : methods) {
    std::cerr << "transfer-align: running " << transfer::MethodName(m) << " ...\n";
    results.push_back(transfer::RunMethod(inputs, config, m));
    std::fprintf(stderr, "transfer-align: %s done in %.2f s\n", transfer::MethodName(m), results.back().run_time_s);
  }

  // Every result exists before anything is printed or written: no partial output on failure.
  if (!FLAGS_out.empty()) {
    transfer::WriteTransferRunFolder(FLAGS_out, results);
    std::cerr << "transfer-align: run folder " << FLAGS_out << " (summary.json, <method>/estimates.csv"
              << (inputs.truth.empty() ? "" : ", <method>/attitude_errors.csv") << ")\n";
    if (FLAGS_report) WriteRunReport("transfer-align", FLAGS_out);
  }
  if (FLAGS_format == "json") {
    if (results.size() == 1) {
      std::cout << transfer::TransferResultJson(results.front()) << "\n";
    } else {
      std::cout << "[";
      for (std::size_t i = 0; i < results.size(); ++i) {
        std::cout << (i ? "," : "") << transfer::TransferResultJson(results[i]);
      }
      std::cout << "]\n";
    }
  } else {
    for (std::size_t i = 0; i < results.size(); ++i) {
      std::cout << (i ? "\n" : "") << transfer::TransferResultTable(results[i]);
    }
  }
  return kExitOk;
}

}  // namespace

Command TransferAlignCommand() {
  return {"transfer-align",
          "Transfer alignment with misalignment and delay estimation (seed 002): order1, order2, history or batch",
          kUsage,
          {"master", "slave_imu", "init_from", "start_s", "truth", "config", "scenario", "seed", "delay_s", "method",
           "calibration", "imu_temperature_degC", "out", "report"},
          &RunTransferAlign};
}

}  // namespace navtwin::app
