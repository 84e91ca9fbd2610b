// GNSS/INS estimator benchmark on the nav-grade-vehicle-1h preset (200 Hz IMU, 1 Hz RTK
// GNSS, one hour of driving), simulated once into a temporary folder:
//   Filter/output_hz:10   the error-state filter over the hour reading the IMU file as it goes
//                         (as `navigate` does), navigation output at 10 Hz
//                         written to nav.nav, nav.csv, std.csv and imu_errors.csv (the
//                         last two at std_rate_hz, 1 Hz, as `navigate` writes them)
//   Filter/output_hz:0    the same with output at every IMU epoch (200 Hz)
//   Batch/minutes:N       the full-batch Ceres smoother (started from the filter, with the
//                         per-state covariance) over the first N = 15, 30, 60 minutes,
//                         reading the IMU file in a pass (as `smooth` does); the filter run
//                         that starts it is not timed
//   ParseImu, FilterOnly, WriteEveryEpoch   the stages of `navtwin navigate` apart (below)
// Each case reports peak_rss_MB, the process's peak resident memory after the case: run one
// case per process for per-case figures, e.g.
//   <build>/bin/bench_gnss_ins --benchmark_filter='Batch/minutes:30'
#include <benchmark/benchmark.h>

#include <stdlib.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "core/io/open.h"
#include "core/sim/simulator.h"
#include "problems/gnss_ins/batch.h"
#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/densify.h"
#include "problems/gnss_ins/filter.h"
#include "problems/gnss_ins/inputs.h"
#include "problems/gnss_ins/output.h"
#include "problems/ins/pure_ins.h"
#include "core/units.h"

namespace navtwin::gnss_ins {
namespace {


double PeakRss_MB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

/// The simulated hour, made once per process (removed at exit).
class NavGradeHour {
 public:
  static const NavGradeHour& Get() {
    static const NavGradeHour instance;
    return instance;
  }
  ~NavGradeHour() { std::filesystem::remove_all(dir_); }

  const std::string& dir() const { return dir_; }

  /// The configuration a user of this IMU would write (the preset's specification values).
  GnssInsConfig Config(double minutes) const {
    GnssInsConfig c;
    c.imu_noise.gyro_arw_rad_per_sqrt_s = 0.002 * kDegPerSqrtHour_radpsqrts;
    c.imu_noise.accel_vrw_mps_per_sqrt_s = 0.01 * kMpsPerSqrtHour_mpspsqrts;
    c.imu_noise.gyro_bias_std_radps = 0.005 * kDegPerHour_radps;
    c.imu_noise.accel_bias_std_mps2 = 25.0 * kMicroG_mps2;
    c.imu_noise.correlation_time_s = kHour_s;
    c.installation.antenna_lever_arm_b_m = Eigen::Vector3d(0.5, 0.0, -1.5);
    c.init.source = InitConfig::Source::kGiven;
    c.init.state = InsState{initial_, ImuErrors{}};
    c.init.std.pos_ned_m.setConstant(0.05);
    c.init.std.vel_ned_mps.setConstant(0.01);
    c.init.std.att_rad.setConstant(0.01 * kDegToRad);
    c.end_time_s = initial_.t_s + minutes * 60.0;
    return c;
  }

 private:
  NavGradeHour() {
    dir_ = (std::filesystem::temp_directory_path() / ("navtwin_bench_gi_" + std::to_string(::getpid()))).string();
    std::filesystem::create_directories(dir_);
    std::cerr << "bench_gnss_ins: simulating nav-grade-vehicle-1h into " << dir_ << " ...\n";
    sim::SimulationOptions options;
    options.seed = 1;
    sim::Simulate(sim::LoadScenario("nav-grade-vehicle-1h"), options, dir_);
    auto init = OpenNav(dir_ + "/init.nav");
    initial_ = InitialStateFromNav(*init, std::nullopt);
  }

  std::string dir_;
  NavState initial_;
};

InputPaths Paths(const NavGradeHour& hour) {
  InputPaths paths;
  paths.imu = hour.dir() + "/imu.txt";
  paths.gnss = hour.dir() + "/gnss.txt";
  return paths;
}

void BM_Filter(benchmark::State& state) {
  const NavGradeHour& hour = NavGradeHour::Get();
  GnssInsConfig config = hour.Config(60.0);
  config.output_rate_hz = static_cast<double>(state.range(0));
  const Inputs inputs = LoadInputs(Paths(hour), config, ImuStorage::kStreamed);
  const std::string out_dir = hour.dir() + "/filter_out";
  std::filesystem::create_directories(out_dir);
  std::size_t outputs = 0;
  for (auto _ : state) {
    NavOutputWriter writer(out_dir, config.filter.scale_factors);
    OutputDecimator decimator(config.output_rate_hz);  // as RunGnssIns decimates for its files
    OutputDecimator std_decimator(config.std_rate_hz);
    outputs = 0;
    const FilterResult result = RunFilter(inputs, config, /*run_rts=*/false,
                                          [&](const NavEpoch& e) {
                                            if (!decimator.Take(e.state.nav.t_s)) return;
                                            writer.Write(e, std_decimator.Take(e.state.nav.t_s));
                                            ++outputs;
                                          },
                                          nullptr);
    writer.Commit();
    benchmark::DoNotOptimize(result.filter.epochs.size());
  }
  state.counters["imu_samples"] = static_cast<double>(inputs.imu.size());
  state.counters["outputs"] = static_cast<double>(outputs);
  state.counters["peak_rss_MB"] = PeakRss_MB();
}
// Wall time: the files are written by a writer thread (core/io/write_queue.h).
BENCHMARK(BM_Filter)->ArgName("output_hz")->Arg(10)->Arg(0)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

// The three stages of `navtwin navigate` apart (issue: the filter at disk speed):
//   ParseImu             the KF-GINS IMU text through the reader (OpenImu), MB/s and samples/s
//   FilterOnly           the filter over the loaded hour, its states dropped (no output)
//   WriteEveryEpoch      nav.nav and nav.csv at every IMU epoch, std.csv and imu_errors.csv
//                        at 1 Hz (the defaults), from states kept in memory
void BM_ParseImu(benchmark::State& state) {
  const NavGradeHour& hour = NavGradeHour::Get();
  const std::string path = Paths(hour).imu;
  std::size_t samples = 0;
  for (auto _ : state) {
    const std::unique_ptr<ImuReader> reader = OpenImu(path);
    ImuSample s;
    samples = 0;
    while (reader->Next(&s)) ++samples;
    benchmark::DoNotOptimize(s);
  }
  const double bytes = static_cast<double>(std::filesystem::file_size(path));
  state.counters["MB_per_s"] = benchmark::Counter(bytes / 1e6, benchmark::Counter::kIsRate);
  state.counters["samples_per_s"] = benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
  state.counters["peak_rss_MB"] = PeakRss_MB();
}
BENCHMARK(BM_ParseImu)->Unit(benchmark::kSecond)->Iterations(1);

void BM_FilterOnly(benchmark::State& state) {
  const NavGradeHour& hour = NavGradeHour::Get();
  const GnssInsConfig config = hour.Config(60.0);
  const Inputs inputs = LoadInputs(Paths(hour), config);
  for (auto _ : state) {
    const FilterResult result = RunFilter(inputs, config, /*run_rts=*/false, [](const NavEpoch&) {}, nullptr);
    benchmark::DoNotOptimize(result.filter.epochs.size());
  }
  state.counters["samples_per_s"] =
      benchmark::Counter(static_cast<double>(inputs.imu.size()), benchmark::Counter::kIsRate);
  state.counters["peak_rss_MB"] = PeakRss_MB();
}
BENCHMARK(BM_FilterOnly)->Unit(benchmark::kSecond)->Iterations(1);

void BM_WriteEveryEpoch(benchmark::State& state) {
  const NavGradeHour& hour = NavGradeHour::Get();
  const GnssInsConfig config = hour.Config(60.0);
  const Inputs inputs = LoadInputs(Paths(hour), config);
  std::vector<NavEpoch> epochs;
  epochs.reserve(inputs.imu.size());
  RunFilter(inputs, config, /*run_rts=*/false, [&epochs](const NavEpoch& e) { epochs.push_back(e); }, nullptr);
  const std::string out_dir = hour.dir() + "/write_out";
  std::filesystem::create_directories(out_dir);
  double bytes = 0.0;
  for (auto _ : state) {
    NavOutputWriter writer(out_dir, config.filter.scale_factors);
    OutputDecimator std_epochs(config.std_rate_hz);
    for (const NavEpoch& e : epochs) writer.Write(e, std_epochs.Take(e.state.nav.t_s));
    writer.Commit();
  }
  for (const char* f : NavOutputWriter::kFiles) bytes += static_cast<double>(std::filesystem::file_size(out_dir + "/" + f));
  state.counters["MB_per_s"] = benchmark::Counter(bytes / 1e6, benchmark::Counter::kIsRate);
  state.counters["samples_per_s"] = benchmark::Counter(static_cast<double>(epochs.size()), benchmark::Counter::kIsRate);
  state.counters["peak_rss_MB"] = PeakRss_MB();
}
BENCHMARK(BM_WriteEveryEpoch)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

void BM_Batch(benchmark::State& state) {
  const NavGradeHour& hour = NavGradeHour::Get();
  const GnssInsConfig config = hour.Config(static_cast<double>(state.range(0)));
  const Inputs inputs = LoadInputs(Paths(hour), config, ImuStorage::kStreamed);
  const FilterResult start = RunFilter(inputs, config, /*run_rts=*/false, {}, nullptr);
  std::size_t states = 0;
  for (auto _ : state) {
    const Solution batch = RunBatch(inputs, config, start.filter, nullptr);
    states = batch.epochs.size();
  }
  state.counters["imu_samples"] = static_cast<double>(inputs.imu.size());
  state.counters["states"] = static_cast<double>(states);
  state.counters["peak_rss_MB"] = PeakRss_MB();
}
BENCHMARK(BM_Batch)->ArgName("minutes")->Arg(15)->Arg(30)->Arg(60)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace
}  // namespace navtwin::gnss_ins

BENCHMARK_MAIN();
