// Multi-position IMU calibration benchmarks (issue 8): the batch solve (Ceres, covariance
// included) and the recursive filter over all positions, for a 24-position table (six faces
// down at four headings, 10 s holds, 3 s moves) at 100 Hz with tactical-grade errors
// (1 deg/h, 1 mg biases, 300 ppm scale factors, 0.5 mrad misalignments, 1 deg/h/g, white
// noise 0.05 deg/sqrt(h) and 0.05 m/s/sqrt(h)); fixed seed. The data are synthesised once.
// Run: <build>/bin/bench_imu_calibration [--benchmark_repetitions=3]
#include <benchmark/benchmark.h>

#include <vector>

#include "core/rotation.h"
#include "core/sim/analytic_trajectory.h"
#include "core/sim/inertial_errors.h"
#include "core/sim/random.h"
#include "core/earth.h"
#include "core/sim/calibration_rig.h"
#include "problems/calibration/handheld.h"
#include "problems/calibration/multiposition.h"
#include "core/units.h"

namespace navtwin::calibration {
namespace {

const MultiPositionData& Data() {
  static const MultiPositionData data = [] {
    MultiPositionData d;
    d.latitude_rad = 45.0 * kDegToRad;
    d.height_m = 100.0;
    d.schedule.rotation_s = 3.0;
    for (const auto& face : std::vector<Eigen::Vector2d>{{0, 0}, {180, 0}, {0, 90}, {0, -90}, {90, 0}, {-90, 0}}) {
      for (double yaw : {0.0, 90.0, 180.0, 270.0}) {
        sim::TableStep s;
        s.euler_rad = Eigen::Vector3d(face.x(), face.y(), yaw) * kDegToRad;
        s.dwell_s = 10.0;
        d.schedule.steps.push_back(s);
      }
    }
    sim::InertialErrorConfig c;
    c.gyro.bias.sigma = kDegPerHour_radps;
    c.gyro.white_noise = 0.05 * kDegPerSqrtHour_radpsqrts;
    c.gyro.scale_factor.sigma = 300e-6;
    c.gyro.misalignment.sigma = 0.5e-3;
    c.accel.bias.sigma = kMilliG_mps2;
    c.accel.white_noise = 0.05 / 60.0;
    c.accel.scale_factor.sigma = 300e-6;
    c.accel.misalignment.sigma = 0.5e-3;
    c.g_sensitivity.sigma = kDegPerHour_radps / kStandardGravity_mps2;
    sim::InertialErrorModel model(c, sim::Rng(11).Stream("imu"), false);
    const sim::MultiPositionRig rig(d.schedule);
    sim::SynthesizeImu(rig, wgs84::Geodetic{d.latitude_rad, 0.0, d.height_m}, 100.0, rig.duration_s() + 1.0,
                       [&](const ImuSample& s, const NavState&) {
                         if (!(s.dt_s > 0.0)) return;
                         ImuSample m = s;
                         model.Apply(s.t_s, s.dt_s, 25.0, s.dtheta_b_rad, s.dv_b_mps, &m.dtheta_b_rad, &m.dv_b_mps);
                         d.imu.push_back(m);
                       });
    return d;
  }();
  return data;
}

void BM_BatchMultiPosition(benchmark::State& state) {
  const MultiPositionData& data = Data();
  ImuCalibrationResult r;
  for (auto _ : state) r = CalibrateMultiPosition(data);
  state.counters["samples"] = static_cast<double>(data.imu.size());
  state.counters["positions"] = r.positions;
  state.counters["accel_bias_x_sigma_mg"] = (*r.calibration.accel_sigma)(9) / kMilliG_mps2;
}
BENCHMARK(BM_BatchMultiPosition)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RecursiveMultiPosition(benchmark::State& state) {
  const MultiPositionData& data = Data();
  ImuCalibrationResult r;
  for (auto _ : state) {
    RecursiveMultiPosition filter(data);
    while (filter.Step()) {
    }
    r = filter.Current();
  }
  state.counters["positions"] = r.positions;
}
BENCHMARK(BM_RecursiveMultiPosition)->Unit(benchmark::kMillisecond)->UseRealTime();

// The hand-placed calibration (problems/calibration/handheld.h) of a 30-minute 100 Hz
// record: 30 s still, then 327 hand placements (2-5 s still, 1-3 s turns) of a MEMS IMU
// (300 deg/h, 6 mg biases, 4000 ppm scale factors, 2 mrad misalignments; 0.3 deg/sqrt(h),
// 0.05 m/s/sqrt(h)). The goal: <= 5 s.
const HandheldData& HandheldRecord() {
  static const HandheldData data = [] {
    sim::HandheldConfig h;
    h.positions = 327;
    const sim::MultiPositionRig rig(sim::HandheldSchedule(h));
    sim::InertialErrorConfig c;
    c.gyro.bias.sigma = 300.0 * kDegPerHour_radps;
    c.gyro.white_noise = 0.3 * kDegPerSqrtHour_radpsqrts;
    c.gyro.scale_factor.sigma = 4000e-6;
    c.gyro.misalignment.sigma = 2e-3;
    c.accel.bias.sigma = 6.0 * kMilliG_mps2;
    c.accel.white_noise = 0.05 * kMpsPerSqrtHour_mpspsqrts;
    c.accel.scale_factor.sigma = 4000e-6;
    c.accel.misalignment.sigma = 2e-3;
    sim::InertialErrorModel model(c, sim::Rng(1).Stream("imu"), false);
    HandheldData d;
    d.latitude_rad = 37.45 * kDegToRad;
    d.height_m = 300.0;
    sim::SynthesizeImu(rig, wgs84::Geodetic{d.latitude_rad, 0.0, d.height_m}, 100.0, rig.duration_s(),
                       [&](const ImuSample& s, const NavState&) {
                         if (s.dt_s <= 0.0) return;
                         ImuSample m = s;
                         model.Apply(s.t_s, s.dt_s, 25.0, s.dtheta_b_rad, s.dv_b_mps, &m.dtheta_b_rad, &m.dv_b_mps);
                         d.imu.push_back(m);
                       });
    return d;
  }();
  return data;
}

void BM_Handheld30Min(benchmark::State& state) {
  const HandheldData& data = HandheldRecord();
  int intervals = 0;
  for (auto _ : state) {
    StillDetection detection;
    benchmark::DoNotOptimize(CalibrateHandheld(data, {}, &detection));
    intervals = detection.intervals;
  }
  state.counters["record_s"] = data.imu.back().t_s - data.imu.front().t_s;
  state.counters["still_intervals"] = intervals;
}
BENCHMARK(BM_Handheld30Min)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace navtwin::calibration

BENCHMARK_MAIN();
