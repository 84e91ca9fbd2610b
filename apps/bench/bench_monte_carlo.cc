// The Monte Carlo engine of `navtwin mc` on the leveling experiment of seed 000: 10,000 runs
// (one 0.2 s window of 600 Hz accelerometer data each, four methods, the batch with its
// covariance) computed, serialized, reduced in run order and summarised, on 1 and 2 threads;
// and the record round trip alone. Multi-rank scaling is measured with mpirun
// (docs/cluster.md), not here.
// Run: <build>/bin/bench_monte_carlo [--benchmark_filter=Leveling]
#include <benchmark/benchmark.h>

#include <string>

#include "core/units.h"
#include "problems/leveling/monte_carlo.h"
#include "solvers/mc_distribute.h"
#include "solvers/mc_statistics.h"

namespace navtwin::mc {
namespace {

/// 10,000 leveling runs through DistributeRuns and the Accumulator, as `navtwin mc
/// --problem leveling` does; the batch's pitch RMS as a counter (0.2687 deg at seed 1).
void BM_LevelingExperiment(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  leveling::MonteCarloConfig config;
  config.seed = 1;
  const RankSession session(false);
  double batch_pitch_rms_deg = 0.0;
  for (auto _ : state) {
    Accumulator acc;
    DistributeRuns(
        session, config.runs, threads,
        [&](int run) { return SerializeRunRecord(leveling::LevelingMcRun(config, leveling::LevelingOptions(), run)); },
        [&](int, const std::string& bytes) { acc.Add(DeserializeRunRecord(bytes)); }, nullptr);
    const std::vector<MethodStatistics> stats = acc.Finish();
    batch_pitch_rms_deg = stats[FindMethod(stats, "batch")].quantities[0].points[0].rms[1] * kRadToDeg;
  }
  state.counters["batch_pitch_rms_deg"] = batch_pitch_rms_deg;
  state.counters["runs_per_s"] = benchmark::Counter(config.runs, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_LevelingExperiment)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

/// One leveling run's record to bytes and back.
void BM_RecordRoundTrip(benchmark::State& state) {
  leveling::MonteCarloConfig config;
  const RunRecord record = leveling::LevelingMcRun(config, leveling::LevelingOptions(), 0);
  for (auto _ : state) benchmark::DoNotOptimize(DeserializeRunRecord(SerializeRunRecord(record)));
}
BENCHMARK(BM_RecordRoundTrip);

}  // namespace
}  // namespace navtwin::mc

BENCHMARK_MAIN();
