// Foundation benchmarks on a 1 h, 200 Hz IMU record (720,000 samples of the demo flight,
// exact increments, written once to a temporary KF-GINS file):
//   BM_Mechanization      strapdown throughput, IMU samples per second, one core;
//   BM_ReadKfginsImu      KF-GINS text reader throughput, bytes per second;
//   BM_ReadULogImu        ULog reader throughput on a real PX4 log (when present).
// Run: <build>/bin/bench_foundation [--benchmark_repetitions=3]
#include <benchmark/benchmark.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "core/io/kfgins.h"
#include "core/io/ulog.h"
#include "core/rotation.h"
#include "core/sim/analytic_trajectory.h"
#include "core/strapdown.h"

namespace navtwin {
namespace {

constexpr double kRateHz = 200.0;
constexpr double kDurationS = 3600.0;

struct Record {
  std::string imu_path;
  NavState initial;
  std::vector<ImuSample> samples;
};

// The 1 h record, synthesized once per process and removed at exit.
const Record& OneHourRecord() {
  static const Record record = [] {
    Record r;
    r.imu_path = "/tmp/navtwin_bench_imu_" + std::to_string(::getpid()) + ".txt";
    KfginsImuWriter writer(r.imu_path);
    bool first = true;
    sim::SynthesizeImu(sim::DemoFlight(), {37.5 * kDegToRad, 127.0 * kDegToRad, 500.0}, kRateHz,
                       kDurationS, [&](const ImuSample& s, const NavState& truth) {
                         if (first) {
                           r.initial = truth;
                           first = false;
                           return;
                         }
                         writer.Write(s);
                         r.samples.push_back(s);
                       });
    writer.Commit();
    std::atexit([] { std::remove(OneHourRecord().imu_path.c_str()); });
    return r;
  }();
  return record;
}

void BM_Mechanization(benchmark::State& state) {
  const Record& r = OneHourRecord();
  for (auto _ : state) {
    Strapdown ins(r.initial);
    for (const ImuSample& s : r.samples) ins.Update(s);
    benchmark::DoNotOptimize(ins.state().lat_rad);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * r.samples.size()));
}
BENCHMARK(BM_Mechanization)->Unit(benchmark::kMillisecond);

long long FileSize(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 ? st.st_size : 0;
}

void BM_ReadKfginsImu(benchmark::State& state) {
  const Record& r = OneHourRecord();
  for (auto _ : state) {
    auto reader = OpenKfginsImu(r.imu_path);
    ImuSample s;
    std::size_t n = 0;
    while (reader->Next(&s)) ++n;
    if (n != r.samples.size()) state.SkipWithError("sample count differs from the record");
  }
  state.SetBytesProcessed(state.iterations() * FileSize(r.imu_path));
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * r.samples.size()));
}
BENCHMARK(BM_ReadKfginsImu)->Unit(benchmark::kMillisecond);

void BM_ReadULogImu(benchmark::State& state) {
  const char* env = std::getenv("NAVTWIN_DATA");
  const std::string path = std::string(env ? env : "../shared/data") + "/px4-ulog/ekf_failure.ulg";
  if (FileSize(path) == 0) {
    state.SkipWithError(("no ULog at " + path + " (set NAVTWIN_DATA)").c_str());
    return;
  }
  for (auto _ : state) {
    auto reader = OpenULogImu(path);
    ImuSample s;
    std::size_t n = 0;
    while (reader->Next(&s)) ++n;
    benchmark::DoNotOptimize(n);
  }
  state.SetBytesProcessed(state.iterations() * FileSize(path));
}
BENCHMARK(BM_ReadULogImu)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace navtwin

BENCHMARK_MAIN();
