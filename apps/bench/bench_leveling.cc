// Leveling benchmarks (issue 5): the seed's 10,000-run Monte Carlo with all four methods
// (target: <= 3 s wall on 2 cores), and the cost of each method on one window of the
// seed's experiment (120 samples at 600 Hz, 22-24 Hz vibration on x, 50 mg noise).
// Run: <build>/bin/bench_leveling [--benchmark_filter=MonteCarlo] [--benchmark_repetitions=3]
#include <benchmark/benchmark.h>

#include <vector>

#include "problems/leveling/batch.h"
#include "problems/leveling/filter.h"
#include "problems/leveling/leveling.h"
#include "problems/leveling/monte_carlo.h"

namespace navtwin::leveling {
namespace {

/// The options RunLevelingMonteCarlo gives the methods in the seed's experiment.
LevelingOptions SeedOptions() {
  LevelingOptions options;
  options.accel_noise_mps2 = 0.05 * kStandardGravity_mps2;
  options.vib_axes = {{true, false, false}};
  options.vib_tones = 1;
  options.batch_covariance = false;
  return options;
}

/// The 10,000-run experiment (seed defaults) on state.range(0) threads; wall time.
void BM_LevelingMonteCarlo10k(benchmark::State& state) {
  MonteCarloConfig config;
  config.threads = static_cast<int>(state.range(0));
  LevelingOptions options;
  options.batch_covariance = false;
  MonteCarloResult result;
  for (auto _ : state) {
    result = RunLevelingMonteCarlo(config, options);
  }
  for (const MethodStatistics& m : result.methods) {
    state.counters[m.method + "_pitch_rms_deg"] = m.pitch_rms_deg;
    state.counters[m.method + "_cpu_s"] = m.cpu_time_s;
  }
  state.SetItemsProcessed(state.iterations() * config.runs);
}
BENCHMARK(BM_LevelingMonteCarlo10k)->Arg(2)->Arg(1)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

/// One method on one window, cycling through 256 simulated windows of the seed's
/// experiment (different frequencies, amplitudes and phases).
void BM_Method(benchmark::State& state, LevelEstimate (*method)(const AccelWindow&, const LevelingOptions&),
               const LevelingOptions& options) {
  const MonteCarloConfig config;
  std::vector<AccelWindow> windows;
  for (int run = 0; run < 256; ++run) windows.push_back(SimulateWindow(config, run));
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(method(windows[i], options));
    i = (i + 1) % windows.size();
  }
  state.SetItemsProcessed(state.iterations());
}

/// The batch with ceres::Covariance (what `navtwin level` reports; the Monte Carlo skips it).
LevelingOptions WithCovariance() {
  LevelingOptions options = SeedOptions();
  options.batch_covariance = true;
  return options;
}

BENCHMARK_CAPTURE(BM_Method, plain_mean, &PlainMean, SeedOptions())->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Method, period_average, &PeriodAverage, SeedOptions())->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Method, filter, &RunFilter, SeedOptions())->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Method, batch, &RunBatch, SeedOptions())->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Method, batch_with_covariance, &RunBatch, WithCovariance())->Unit(benchmark::kMicrosecond);

/// Simulating one window (part of every Monte Carlo run).
void BM_SimulateWindow(benchmark::State& state) {
  const MonteCarloConfig config;
  int run = 0;
  for (auto _ : state) benchmark::DoNotOptimize(SimulateWindow(config, run++));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SimulateWindow)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace navtwin::leveling

BENCHMARK_MAIN();
