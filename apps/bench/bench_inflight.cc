// In-flight heading alignment benchmarks (issue 7): each method on the preset
// inflight-mach07-south (545 s of 100 Hz IMU, 1 Hz GPS, 10 Hz baro; simulated once, seed 1),
// and the parts they share: the free INS and one whole-flight batch solve.
// Run: <build>/bin/bench_inflight [--benchmark_filter=Method] [--benchmark_repetitions=3]
#include <benchmark/benchmark.h>

#include <cmath>

#include "core/sim/scenario.h"
#include "problems/inflight_alignment/batch.h"
#include "problems/inflight_alignment/distance_heading.h"
#include "problems/inflight_alignment/filter.h"
#include "problems/inflight_alignment/free_ins.h"
#include "problems/inflight_alignment/run.h"

namespace navtwin::inflight {
namespace {

const InflightInputs& Preset() {
  static const InflightInputs inputs = SimulateInflightInputs(sim::LoadScenario("inflight-mach07-south"), 1);
  return inputs;
}

constexpr double kRadToArcmin = 180.0 * 60.0 / M_PI;

/// One method end to end as `navtwin inflight-align` runs it (the batch includes its four
/// prefix solves for the 10/20/50/100 km figures); the final heading error as a counter.
void BM_Method(benchmark::State& state, Method method) {
  const InflightInputs& inputs = Preset();
  const InflightConfig config;
  MethodResult result;
  for (auto _ : state) result = RunMethod(inputs, config, method);
  state.counters["final_error_arcmin"] = result.final_error_rad * kRadToArcmin;
  state.counters["imu_samples_per_s"] =
      benchmark::Counter(static_cast<double>(inputs.imu.size()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK_CAPTURE(BM_Method, distance, Method::kDistance)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Method, kalman, Method::kKalman)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Method, batch, Method::kBatch)->Unit(benchmark::kMillisecond);

/// The free INS over the whole flight (mechanization, baro loop, one sample per fix).
void BM_FreeIns(benchmark::State& state) {
  const InflightInputs& inputs = Preset();
  const InflightConfig config;
  for (auto _ : state) benchmark::DoNotOptimize(RunFreeIns(inputs, config));
  state.SetItemsProcessed(state.iterations() * static_cast<long>(inputs.imu.size()));
}
BENCHMARK(BM_FreeIns)->Unit(benchmark::kMillisecond);

/// One whole-flight batch solve with covariance, on the free INS's epochs.
void BM_BatchSolve(benchmark::State& state) {
  const InflightInputs& inputs = Preset();
  const InflightConfig config;
  const std::vector<FreeInsEpoch> epochs = RunFreeIns(inputs, config);
  const double sigma_m = EstimateGpsSigma(inputs.gnss);
  const double rate = SchulerRate(inputs.initial.lat_rad, inputs.initial.h_m);
  for (auto _ : state)
    benchmark::DoNotOptimize(SolveHeadingBatch(epochs, sigma_m, inputs.initial.lat_rad, rate, config));
  state.counters["fixes"] = static_cast<double>(epochs.size());
}
BENCHMARK(BM_BatchSolve)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace navtwin::inflight

BENCHMARK_MAIN();
