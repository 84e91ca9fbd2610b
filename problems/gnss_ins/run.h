// One entry point for a GNSS/INS run over a record (docs/gnss-ins.md): read the inputs,
// run the error-state filter, optionally its RTS smoother and the full-batch smoother,
// densify each smoother's knots to every IMU epoch, score every method at every IMU epoch
// against a reference when one is given (so the score does not depend on the output
// rate; each method's compared epochs go to <method>/errors.csv), and write the chosen
// method's solution at the output epochs (nav.nav, nav.csv, std.csv, imu_errors.csv,
// output.h), every method's solution and measurement residuals (<method>/nav.csv, std.csv,
// residuals.csv), the GNSS fixes read (gnss.csv) and summary.json into one folder, all or
// nothing (docs/run-folder.md).
// The JSON summary and the table of `navtwin navigate` / `navtwin smooth` come from here.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/io/json_writer.h"
#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/inputs.h"
#include "problems/gnss_ins/scoring.h"
#include "problems/gnss_ins/solution.h"

namespace navtwin::gnss_ins {

/// The estimators a run computes; the last one is the solution written.
enum class RunMethods {
  kFilter,     ///< the filter; its real-time solution is written
  kFilterRts,  ///< filter and RTS smoother; the RTS solution is written
  kAll,        ///< filter, RTS and the batch smoother (started from RTS); the batch is written;
               ///< with variance components, then filter and RTS with the adapted noise
               ///< ("filter_adapted", "rts_adapted", scored but not written)
};

struct RunOptions {
  InputPaths paths;            ///< imu, gnss (required), mag, baro, calibration
  std::string truth;           ///< reference to score against (OpenReference), or empty
  std::string out_dir;         ///< an existing folder
  std::string config_path;     ///< the configuration file, reported in the summary
  std::string command = "navigate";  ///< names the run in the summary and on `progress`
  RunMethods methods = RunMethods::kFilter;
  std::ostream* progress = nullptr;  ///< progress and warnings; null: silent
};

/// What was read, for the summary (the samples themselves are not kept).
struct InputSummary {
  InputPaths paths;
  std::size_t imu_samples = 0, gnss_epochs = 0, mag_samples = 0, baro_samples = 0;
  std::size_t bridged_imu_gaps = 0;
  std::size_t gnss_removed_by_outages = 0;
  double t_start_s = 0.0;  ///< start of the first IMU interval
  double t_end_s = 0.0;    ///< last IMU epoch
  std::vector<std::pair<double, double>> outages;  ///< injected [start, end)
};

InputSummary SummarizeInputs(const Inputs& inputs);

struct MethodRun {
  std::string name;  ///< "filter", "rts", "batch"
  Solution solution;
  /// Errors of the method's states at every IMU epoch (whatever the output rate) against
  /// RunOptions::truth; empty without it.
  std::optional<ScoreReport> errors;
  /// <out_dir>/<name>/errors.csv, the compared epochs (output.h); empty without a reference.
  std::string errors_csv;
};

struct GnssInsRun {
  InputSummary inputs;
  std::vector<MethodRun> methods;  ///< in the order computed: filter, rts, batch
  std::string output_method;       ///< the method written
  std::size_t output_epochs = 0;
  double output_rate_hz = 0.0;     ///< 0: every IMU epoch
  double total_run_time_s = 0.0;   ///< reading, estimation, scoring and writing
  /// What went wrong (problems/gnss_ins/diagnostics.h), one sentence each; also printed on
  /// RunOptions::progress as they are found.
  std::vector<std::string> warnings;
  /// The noise values the batch's variance components changed, one line each ("gyro ARW
  /// 0.912 -> 2.93 deg/sqrt(h) ..."); empty without adaptation.
  std::vector<std::string> adapted_noise;
  /// The configured prior std of the error state (InitialStdVector; 15 or 21 entries), for
  /// judging whether the record observed the IMU scale factors.
  Eigen::VectorXd prior_std;
};

/// Runs options.methods over the record with `config` and writes the outputs and
/// summary.json into options.out_dir (WriteRunSummary; docs/run-folder.md). A given initial state without a
/// time starts at the first IMU interval. Nothing is left in the folder when it throws:
/// InputError for bad input data, std::runtime_error when no output epoch results.
GnssInsRun RunGnssIns(const RunOptions& options, GnssInsConfig config);

/// summary.json (and `--format=json`): command, output_method, inputs, outages, output,
/// truth, and per method its run time, knots, measurement counts, solver report and,
/// with a reference, its errors (docs/gnss-ins.md "Outputs").
void WriteRunSummary(JsonWriter& w, const RunOptions& options, const GnssInsRun& run);

/// The text a person reads: what was read, where the solution went, and per method the
/// RMS errors (horizontal, vertical, velocity, roll, pitch, yaw; outage drifts) or, without
/// a reference, the knots and run time.
std::string RunTable(const RunOptions& options, const GnssInsRun& run);

/// The files of a simulated demo record (SimulateDemo).
struct DemoFiles {
  std::string imu, gnss, mag, truth, config;  ///< mag empty when not simulated or not used
};

/// Simulates `scenario_name` (a preset or a scenario YAML, with GNSS) with `seed` into
/// sim_dir (created when missing) and writes the configuration a user of that record would
/// write (ConfigYamlForSimulation with mag_mode) to sim_dir/navtwin.yaml. Progress on
/// `progress` when not null. Throws std::runtime_error for a scenario without GNSS or a
/// folder that cannot be created.
DemoFiles SimulateDemo(const std::string& scenario_name, std::uint64_t seed, const std::string& mag_mode,
                       const std::string& sim_dir, std::ostream* progress);

}  // namespace navtwin::gnss_ins
