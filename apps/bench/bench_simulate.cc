// Simulator benchmark: `navtwin simulate --scenario nav-grade-vehicle-1h` in-process —
// 1 h of 200 Hz IMU with 1 Hz GNSS, every error model of the preset on, all files
// written (to a temporary folder, removed afterwards).
// Run: <build>/bin/bench_simulate [--benchmark_repetitions=3]
#include <benchmark/benchmark.h>

#include <stdlib.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "core/sim/simulator.h"

namespace navtwin::sim {
namespace {

void BM_SimulateNavGrade1h(benchmark::State& state) {
  const Scenario scenario = LoadScenario("nav-grade-vehicle-1h");
  std::string dir = "/tmp/navtwin_bench_sim_XXXXXX";
  if (::mkdtemp(dir.data()) == nullptr) {
    state.SkipWithError("cannot create a temporary folder");
    return;
  }
  SimulationReport report;
  SimulationOptions options;
  for (auto _ : state) {
    report = Simulate(scenario, options, dir);
  }
  for (const std::string& f : report.files) std::remove(f.c_str());
  ::rmdir(dir.c_str());
  state.counters["imu_samples"] = static_cast<double>(report.imu_samples);
  state.counters["gnss_samples"] = static_cast<double>(report.gnss_samples);
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * report.imu_samples));
}
BENCHMARK(BM_SimulateNavGrade1h)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace
}  // namespace navtwin::sim

BENCHMARK_MAIN();
