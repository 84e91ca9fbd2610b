#include "problems/gnss_ins/run.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <vector>

#include "core/io/atomic_file.h"
#include "core/io/open.h"
#include "core/rotation.h"
#include "core/units.h"
#include "core/sim/scenario.h"
#include "core/sim/simulator.h"
#include "problems/gnss_ins/adapted_noise.h"
#include "problems/gnss_ins/batch.h"
#include "problems/gnss_ins/densify.h"
#include "problems/gnss_ins/diagnostics.h"
#include "problems/gnss_ins/filter.h"
#include "problems/gnss_ins/initial_state.h"
#include "problems/gnss_ins/output.h"
#include "problems/gnss_ins/sim_config.h"
#include "problems/ins/pure_ins.h"

namespace navtwin::gnss_ins {
namespace {

using Scorer = std::unique_ptr<TrajectoryScorer>;
using MethodFiles = std::vector<std::unique_ptr<MethodOutputWriter>>;

/// Where one method's outputs go: its folder <out_dir>/<method>/ (output epochs, residuals)
/// and, with a reference, a scorer (every IMU epoch) writing the folder's errors.csv.
struct MethodSinks {
  Scorer scorer;  ///< null without a reference
  MethodOutputWriter* files;
};

/// Where the estimators' outputs go: the solution writer (output epochs) and each method's
/// folder.
struct RunSinks {
  const RunOptions& options;
  const GnssInsConfig& config;
  const Inputs& inputs;
  NavOutputWriter* writer;
  MethodFiles* method_files;  ///< committed by RunGnssIns when the whole run succeeds

  /// The folder <out_dir>/<method>/ (nav.csv, std.csv) and, with a reference, the scorer
  /// writing its errors.csv.
  MethodSinks Open(const std::string& method) const {
    method_files->push_back(
        std::make_unique<MethodOutputWriter>(options.out_dir, method, config.filter.scale_factors));
    MethodSinks sinks{nullptr, method_files->back().get()};
    if (options.truth.empty()) return sinks;
    sinks.scorer = OpenReference(options.truth, inputs.outages, config.installation.antenna_lever_arm_b_m);
    sinks.files->OpenErrors(sinks.scorer->reference_has_std());
    sinks.scorer->OnEpoch([files = sinks.files](const ScoredEpoch& e) { files->WriteErrors(e); });
    return sinks;
  }
};

/// The callback an estimator's states at every IMU epoch go to: all of them to the
/// method's scorer (when there is one), so the score does not depend on the output rate,
/// and the output epochs (OutputDecimator at config.output_rate_hz; their σ and IMU errors
/// at config.std_rate_hz) to `writer` when not null (the method written at the top level,
/// whose folder then shares its files), else to the method's folder.
std::function<void(const NavEpoch&)> Feed(const MethodSinks& sinks, NavOutputWriter* writer,
                                          const GnssInsConfig& config) {
  if (writer) sinks.files->ShareTopLevelFiles();
  return [scorer = sinks.scorer.get(), files = sinks.files, writer, decimator = OutputDecimator(config.output_rate_hz),
          std_decimator = OutputDecimator(config.std_rate_hz)](const NavEpoch& e) mutable {
    if (scorer) scorer->Add(e);
    if (!decimator.Take(e.state.nav.t_s)) return;
    const bool with_std = std_decimator.Take(e.state.nav.t_s);
    if (writer) {
      writer->Write(e, with_std);
    } else {
      files->Write(e, with_std);
    }
  };
}

/// The method's run; residuals.csv in its folder for an estimator with residuals of its own.
MethodRun Scored(const std::string& name, Solution solution, const MethodSinks& sinks, bool has_residuals) {
  if (has_residuals) sinks.files->WriteResiduals(solution.measurement_residuals);
  MethodRun m{name, std::move(solution), std::nullopt, ""};
  if (sinks.scorer) {
    m.errors = sinks.scorer->Report();
    m.errors_csv = sinks.files->errors_path();
  }
  return m;
}

/// A smoother's knots densified to every IMU epoch, scored, and written when `writer`.
MethodRun DensifyAndScore(const std::string& name, Solution knots, const RunSinks& run_sinks, NavOutputWriter* writer,
                          bool has_residuals) {
  const MethodSinks sinks = run_sinks.Open(name);
  Densify(knots, run_sinks.inputs, Feed(sinks, writer, run_sinks.config));
  return Scored(name, std::move(knots), sinks, has_residuals);
}

/// With the batch's variance components: the filter and its RTS smoother again with the
/// noise they found (adapted_noise.h), as methods "filter_adapted" and "rts_adapted".
void RunAdaptedFilter(const RunSinks& sinks, const FilterStart& start, GnssInsRun* run) {
  AdaptedNoise adapted = AdaptNoise(sinks.config, run->methods.back().solution.residuals);
  run->adapted_noise = adapted.lines;
  if (!adapted.changed) return;
  const RunOptions& options = sinks.options;
  if (options.progress) {
    *options.progress << options.command << ": filter + RTS smoother again with the batch's adapted noise\n";
  }
  const MethodSinks filter_sinks = sinks.Open("filter_adapted");
  FilterResult fr = RunFilter(sinks.inputs, adapted.config, start, true,
                              Feed(filter_sinks, nullptr, adapted.config), options.progress);
  run->methods.push_back(Scored("filter_adapted", std::move(fr.filter), filter_sinks, true));
  if (!fr.rts) throw std::runtime_error("the filter returned no RTS solution");
  run->methods.push_back(DensifyAndScore("rts_adapted", std::move(*fr.rts), sinks, nullptr, false));
}

/// Filter, then RTS and batch as options.methods asks; the last one goes to the writer.
void RunEstimators(const RunSinks& sinks, GnssInsRun* run) {
  const RunOptions& options = sinks.options;
  const GnssInsConfig& config = sinks.config;
  const Inputs& inputs = sinks.inputs;
  const bool run_rts = options.methods != RunMethods::kFilter;
  const bool run_batch = options.methods == RunMethods::kAll;
  if (options.progress) *options.progress << options.command << ": filter" << (run_rts ? " + RTS smoother" : "") << "\n";
  // The alignment runs once, before the filter; the batch's prior is the same start.
  const FilterStart start = InitialFilterState(inputs, config, options.progress);
  const MethodSinks filter_sinks = sinks.Open("filter");
  // Without a smoother nothing reads the filter's knots but the last: memory stays flat.
  FilterResult fr = RunFilter(inputs, config, start, run_rts,
                              Feed(filter_sinks, run_rts ? nullptr : sinks.writer, config), options.progress,
                              run_rts ? FilterKnots::kAll : FilterKnots::kLast);
  run->methods.push_back(Scored("filter", std::move(fr.filter), filter_sinks, true));
  run->output_method = "filter";
  if (!run_rts) return;
  if (!fr.rts) throw std::runtime_error("the filter returned no RTS solution");
  run->methods.push_back(DensifyAndScore("rts", std::move(*fr.rts), sinks, run_batch ? nullptr : sinks.writer, false));
  run->output_method = "rts";
  if (!run_batch) return;
  if (options.progress) {
    *options.progress << options.command << ": batch smoother (Ceres) started from the RTS solution\n";
  }
  Solution batch = RunBatch(inputs, config, run->methods.back().solution, &start, options.progress);
  run->methods.push_back(DensifyAndScore("batch", std::move(batch), sinks, sinks.writer, true));
  run->output_method = "batch";
  RunAdaptedFilter(sinks, start, run);
}

/// InitConfig::nav_file_at_start: its record at start_time_s, else at the start of the first
/// IMU interval (after the installation's time offset); the IMU-error estimates and the
/// stds stay the configuration's.
void InitFromNavFile(const Inputs& inputs, GnssInsConfig* config) {
  const double t_s = std::isfinite(config->start_time_s) ? config->start_time_s : inputs.imu.begin_s();
  const std::unique_ptr<NavReader> reader = OpenNav(config->init.nav_file_at_start);
  InsState state;
  state.nav = InitialStateFromNav(*reader, t_s);
  config->init.source = InitConfig::Source::kGiven;
  config->init.position_from_gnss = false;
  config->init.state = state;
}

}  // namespace

InputSummary SummarizeInputs(const Inputs& inputs) {
  InputSummary s;
  s.paths = inputs.paths;
  s.imu_samples = inputs.imu.size();
  s.gnss_epochs = inputs.gnss.size();
  s.mag_samples = inputs.mag.size();
  s.baro_samples = inputs.baro.size();
  s.bridged_imu_gaps = inputs.imu.bridged_gaps();
  s.gnss_removed_by_outages = inputs.gnss_removed_by_outages;
  if (!inputs.imu.empty()) {
    s.t_start_s = inputs.imu.begin_s();
    s.t_end_s = inputs.imu.back().t_s;
  }
  s.outages = inputs.outages;
  return s;
}

GnssInsRun RunGnssIns(const RunOptions& options, GnssInsConfig config) {
  const auto t0 = std::chrono::steady_clock::now();
  const InputPaths& p = options.paths;
  if (options.progress) {
    *options.progress << options.command << ": reading " << p.imu << ", " << p.gnss
                      << (p.mag.empty() ? "" : ", " + p.mag) << (p.baro.empty() ? "" : ", " + p.baro) << "\n";
  }
  // Every estimator reads the IMU record in passes (the batch keeps its preintegrated pieces).
  Inputs inputs = LoadInputs(p, config, ImuStorage::kStreamed);
  if (inputs.installation_from_calibration && options.progress) {
    const Eigen::Vector3d rpy_deg = inputs.installation.imu_mounting_rpy_rad * kRadToDeg;
    char line[256];
    std::snprintf(line, sizeof line, ": IMU installation from %s: mounting roll %.3f pitch %.3f yaw %.3f deg, time offset %.4f s\n",
                  p.calibration.c_str(), rpy_deg.x(), rpy_deg.y(), rpy_deg.z(), inputs.installation.imu_time_offset_s);
    *options.progress << options.command << line;
  }
  if (!config.init.nav_file_at_start.empty()) InitFromNavFile(inputs, &config);
  if (config.init.state && std::isnan(config.init.state->nav.t_s)) config.init.state->nav.t_s = inputs.imu.begin_s();
  GnssInsRun run;
  run.output_rate_hz = config.output_rate_hz;
  run.prior_std = InitialStdVector(config, config.filter.scale_factors ? ins::err::kSize21 : ins::err::kSize15);
  NavOutputWriter writer(options.out_dir, config.filter.scale_factors);
  MethodFiles method_files;
  RunEstimators(RunSinks{options, config, inputs, &writer, &method_files}, &run);
  if (inputs.imu.streamed()) CutToImuEnd(&inputs);  // the filter's pass found the IMU record's end
  if (inputs.imu.bridged_gaps() > 0 && options.progress) {
    *options.progress << options.command << ": bridged " << inputs.imu.bridged_gaps() << " short IMU gap(s)\n";
  }
  run.inputs = SummarizeInputs(inputs);
  AtomicFile gnss_csv(options.out_dir + "/gnss.csv");
  WriteGnssCsv(gnss_csv.stream(), inputs.gnss, inputs.gnss_removed);
  run.output_epochs = writer.count();
  if (run.output_epochs == 0) throw std::runtime_error("the run produced no output epoch");
  run.warnings = Diagnose(run);
  if (options.progress) {
    for (const std::string& w : run.warnings) *options.progress << options.command << ": warning: " << w << "\n";
  }
  run.total_run_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // summary.json first (it can still fail), then the method folders, gnss.csv and the solution.
  const std::string summary = options.out_dir + "/summary.json";
  WriteJsonFile(summary, [&](JsonWriter& w) { WriteRunSummary(w, options, run); });
  try {
    writer.Commit();  // before the method folders: the output method's links to its files
    for (const auto& f : method_files) f->Commit();
    gnss_csv.Commit();
  } catch (...) {
    for (const auto& f : method_files) f->Revoke();
    gnss_csv.Revoke();
    writer.Revoke();
    std::remove(summary.c_str());
    throw;
  }
  return run;
}

DemoFiles SimulateDemo(const std::string& scenario_name, std::uint64_t seed, const std::string& mag_mode,
                       const std::string& sim_dir, std::ostream* progress) {
  struct stat st;
  const bool exists = ::stat(sim_dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
  if (!exists && ::mkdir(sim_dir.c_str(), 0755) != 0) throw std::runtime_error("cannot create " + sim_dir);
  const sim::Scenario scenario = sim::LoadScenario(scenario_name);
  if (!scenario.gnss) throw std::runtime_error("the demo scenario " + scenario_name + " has no GNSS");
  sim::SimulationOptions options;
  options.seed = seed;
  if (progress) {
    options.progress = [progress, &scenario_name](double fraction) {
      char line[256];
      std::snprintf(line, sizeof line, "\rsimulating %s %3.0f %%", scenario_name.c_str(), 100.0 * fraction);
      *progress << line << (fraction >= 1.0 ? "\n" : "") << std::flush;
    };
  }
  sim::Simulate(scenario, options, sim_dir);
  const std::string yaml = ConfigYamlForSimulation(scenario, sim_dir, seed, mag_mode);
  DemoFiles f;
  f.config = sim_dir + "/navtwin.yaml";
  AtomicFile file(f.config);
  file.stream() << yaml;
  file.Commit();
  f.imu = sim_dir + "/imu.txt";
  f.gnss = sim_dir + "/gnss.txt";
  if (scenario.mag && mag_mode != "off") f.mag = sim_dir + "/mag.csv";
  f.truth = sim_dir + "/truth.nav";
  return f;
}

}  // namespace navtwin::gnss_ins
