// Transfer-alignment benchmarks: each method end to end as `navtwin transfer-align` runs it,
// on the preset transfer-alignment-high-maneuver (200 s of 100 Hz slave IMU, 50 Hz master
// 300 ms late; simulated once, seed 1). The batch includes the order-2 filter it starts from.
// Run: <build>/bin/bench_transfer [--benchmark_filter=Method] [--benchmark_repetitions=3]
#include <benchmark/benchmark.h>

#include "core/sim/scenario.h"
#include "problems/transfer_alignment/run.h"

namespace navtwin::transfer {
namespace {

const TransferInputs& Preset() {
  static const TransferInputs inputs = SimulateTransferInputs(sim::LoadScenario("transfer-alignment-high-maneuver"), 1);
  return inputs;
}

/// One method; its attitude RMS (the largest axis), delay error and master records per second
/// as counters.
void BM_Method(benchmark::State& state, Method method) {
  const TransferInputs& inputs = Preset();
  const TransferConfig config;
  TransferResult result;
  for (auto _ : state) result = RunMethod(inputs, config, method);
  state.counters["rms_max_axis_mrad"] = result.rms_mrad.maxCoeff();
  state.counters["delay_error_ms"] = (result.delay_s - result.delay_true_s) * 1e3;
  state.counters["records_per_s"] =
      benchmark::Counter(static_cast<double>(inputs.master.size()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK_CAPTURE(BM_Method, order1, Method::kOrder1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Method, order2, Method::kOrder2)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Method, history, Method::kHistory)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Method, batch, Method::kBatch)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace navtwin::transfer

BENCHMARK_MAIN();
