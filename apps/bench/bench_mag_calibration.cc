// Magnetometer calibration benchmarks (issue 8): the batch ellipsoid fit of 100,000 samples
// (target: <= 1 s wall), with the default Cauchy loss and with the field magnitude given or
// fitted, and the recursive fit's cost per sample. Samples: m = (I + S) R_b_n m_n + h + n with
// the seed's field (57 deg inclination, 50 uT), h = (22, -15, 28) uT, a symmetric S with
// entries up to 0.06, 0.3 uT noise, uniformly random attitudes, fixed seed.
// Run: <build>/bin/bench_mag_calibration [--benchmark_repetitions=3]
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "core/sim/random.h"
#include "problems/calibration/mag_calibration.h"
#include "core/units.h"

namespace navtwin::calibration {
namespace {

std::vector<MagSample> Simulate(int n) {
  sim::Rng rng(8);
  const double inclination = 57.0 * kDegToRad;
  const Eigen::Vector3d field_ned = 50.0 * Eigen::Vector3d(std::cos(inclination), 0.0, std::sin(inclination));
  const Eigen::Vector3d h(22.0, -15.0, 28.0);
  Eigen::Matrix3d M;
  M << 1.05, 0.03, -0.04, 0.03, 0.96, 0.06, -0.04, 0.06, 1.02;  // I + S
  std::vector<MagSample> samples(n);
  for (int i = 0; i < n; ++i) {
    Eigen::Quaterniond q(rng.Normal(), rng.Normal(), rng.Normal(), rng.Normal());
    q.normalize();
    samples[i].t_s = 0.01 * i;
    samples[i].m_b_uT = M * (q.toRotationMatrix().transpose() * field_ned) + h + rng.Normal3(0.3);
  }
  return samples;
}

void BM_FitEllipsoid(benchmark::State& state) {
  const std::vector<MagSample> samples = Simulate(static_cast<int>(state.range(0)));
  EllipsoidFitOptions options;
  options.field_uT = state.range(1) != 0 ? 50.0 : 0.0;
  MagCalibration c;
  for (auto _ : state) {
    c = FitEllipsoid(samples, options);
  }
  state.counters["residual_rms_uT"] = c.residual_rms_uT;
  state.counters["spread_after_uT"] = c.field_spread_after_uT;
  state.counters["h_sigma_x_uT"] = c.hard_iron_sigma_uT.x();
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
// Args: samples, field given (1) or fitted (0).
BENCHMARK(BM_FitEllipsoid)
    ->Args({100000, 1})
    ->Args({100000, 0})
    ->Args({1000, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_RecursiveAdd(benchmark::State& state) {
  const std::vector<MagSample> samples = Simulate(10000);
  RecursiveEllipsoidFit fit(50.0);
  for (int k = 0; k < 100; ++k) fit.Add(samples[k].m_b_uT);  // Current() below needs >= 9
  std::size_t i = 100;
  for (auto _ : state) {
    fit.Add(samples[i].m_b_uT);
    i = (i + 1) % samples.size();
  }
  benchmark::DoNotOptimize(fit.Current());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RecursiveAdd);

}  // namespace
}  // namespace navtwin::calibration

BENCHMARK_MAIN();
