// The transfer-alignment batch (problems/transfer_alignment/batch.h) on simulated data with
// a known truth: a 60 s shortened copy of the preset (cruise, wing rock, turn) and the
// preset transfer-alignment-high-maneuver itself, seed 1 each. Checked: the delay within
// 1 ms of the truth (0.3 s, the issue's goal) and within 3 sigma, the misalignment within 3
// sigma per axis plus the slave IMU's unmodelled axis misalignment, the slave attitude RMS after settle_s below the order-2 filter's (the
// batch is the smoothed reference, batch.h). The seed-style table is printed.
#include "problems/transfer_alignment/batch.h"

#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "core/sim/scenario.h"
#include "core/config/yaml_config.h"
#include "core/units.h"
#include "problems/transfer_alignment/filter.h"
#include "problems/transfer_alignment/run.h"

namespace navtwin::transfer {
namespace transfer_alignment_batch_test {

// The preset's sensors and master, 60 s of its first manoeuvres: 10 s cruise, 40 s wing
// rock (+-30 deg at 0.5 Hz, the largest angular acceleration of the preset), a 45 deg turn.
constexpr const char* kShortScenario = R"(name: transfer-alignment-short
description: batch test - the first 60 s of transfer-alignment-high-maneuver
start: {lat_deg: 36.0, lon_deg: 127.5, h_m: 3000}
trajectory:
  initial: {speed_mps: 200, heading_deg: 0}
  segments:
    - {kind: cruise, duration_s: 10}
    - {kind: wing_rock, duration_s: 40, roll_amplitude_deg: 30, roll_frequency_hz: 0.5, pitch_amplitude_deg: 5, pitch_frequency_hz: 0.25, yaw_amplitude_deg: 5, yaw_frequency_hz: 0.25}
    - {kind: turn, duration_s: 10, heading_change_deg: 45}
imu:
  rate_hz: 100
  mounting_deg: [0.5, -0.3, 0.8]
  errors:
    gyro: {bias_deg_h: 1.0, arw_deg_sqrt_h: 0.05, scale_factor_ppm: 100, misalignment_arcsec: 20}
    accel: {bias_ug: 200, vrw_m_s_sqrt_h: 0.05, scale_factor_ppm: 100, misalignment_arcsec: 20}
master:
  rate_hz: 50
  transfer_delay_s: 0.3
  attitude_error_sigma_mrad: 0.05
  velocity_noise_mps: 0.01
init_errors: {velocity_ned_mps: [0.5, -0.5, 0.2], attitude_deg: [0.5, -0.5, 1.0]}
)";

const TransferInputs& ShortInputs() {
  static const TransferInputs in =
      SimulateTransferInputs(sim::ParseScenario(ParseYaml(kShortScenario, "batch_test.cc")), 1);
  return in;
}

const TransferInputs& PresetInputs() {
  static const TransferInputs in = SimulateTransferInputs(sim::LoadScenario("transfer-alignment-high-maneuver"), 1);
  return in;
}

void PrintRow(const char* name, const TransferResult& r) {
  std::printf("%-8s %6.3f / %6.3f  %6.3f / %6.3f  %6.3f / %6.3f   %.5f +- %.5f\n", name, r.rms_mrad.x(),
              r.max_mrad.x(), r.rms_mrad.y(), r.max_mrad.y(), r.rms_mrad.z(), r.max_mrad.z(), r.delay_s,
              r.delay_sigma_s);
}

/// Runs the order-2 filter and the batch from it with the default configuration and
/// checks the batch against the truth and the filter.
void CheckBatch(const TransferInputs& in, const char* label) {
  ASSERT_TRUE(in.true_delay_s.has_value());
  ASSERT_TRUE(in.true_misalignment.has_value());
  const TransferConfig cfg;
  const TransferFilterRun filter = RunTransferFilter(in, cfg, DelayOrder::kSecond);
  const TransferBatchSolution sol = SolveTransferBatch(in, cfg, filter);

  TransferResult f, b;
  std::vector<NavState> filter_states;
  for (const TransferEpoch& e : filter.epochs) filter_states.push_back(e.slave);
  ScoreAttitude(in, filter_states, filter.epochs.back().misalignment, cfg.settle_s, &f);
  f.delay_s = filter.epochs.back().delay_s;
  f.delay_sigma_s = filter.epochs.back().sigma[kTransferStates - 1];
  ScoreAttitude(in, sol.states, sol.misalignment, cfg.settle_s, &b);
  b.delay_s = sol.delay_s;
  b.delay_sigma_s = sol.delay_sigma_s;

  const double true_delay = *in.true_delay_s;
  // Misalignment error in the tangent of batch.h: M_true = Exp(mu) M_est, mu in master body axes.
  const Eigen::Vector3d mu_rad =
      LogSO3<double>(Eigen::Matrix3d((*in.true_misalignment * sol.misalignment.conjugate()).toRotationMatrix()));
  std::printf("%s: slave attitude error after %.0f s (mrad, RMS / max), delay (s) +- sigma; true delay %.3f s\n",
              label, cfg.settle_s, true_delay);
  std::printf("method    roll            pitch           heading         delay\n");
  PrintRow("order2", f);
  PrintRow("batch", b);
  std::printf("batch: misalignment error mu [%.4f %.4f %.4f] mrad, sigma [%.4f %.4f %.4f] mrad; %zu states, "
              "%d iterations, final cost %.1f, %.2f s (filter %.2f s)\n",
              mu_rad.x() * 1e3, mu_rad.y() * 1e3, mu_rad.z() * 1e3, sol.misalignment_sigma_rad.x() * 1e3,
              sol.misalignment_sigma_rad.y() * 1e3, sol.misalignment_sigma_rad.z() * 1e3, sol.states.size(),
              sol.iterations, sol.final_cost, sol.run_time_s, filter.run_time_s);

  // The issue's goal: within 1 ms of the truth; and consistent with its own sigma.
  EXPECT_LT(std::abs(sol.delay_s - true_delay), 1e-3);
  EXPECT_LT(std::abs(sol.delay_s - true_delay), 3.0 * sol.delay_sigma_s);
  // The batch estimates the slave triads' scale factors and axis misalignments (100 ppm,
  // 20 arcsec in the simulation and the default priors), so its misalignment sigma covers
  // them: measured |error| 0.46-1.33 sigma on the short flight and the preset (without them
  // in the model it was 3.7 sigma on the preset's pitch). Bound: 3 sigma per axis.
  for (int i = 0; i < 3; ++i) {
    const double sigma = sol.misalignment_sigma_rad[i];
    std::printf("misalignment axis %d: |error| = %.2f sigma\n", i, std::abs(mu_rad[i]) / sigma);
    EXPECT_LT(std::abs(mu_rad[i]), 3.0 * sigma) << "axis " << i;
  }
  if (!sol.instrument_not_observable.empty()) {
    std::printf("not observable:");
    for (const std::string& name : sol.instrument_not_observable) std::printf(" [%s]", name.c_str());
    std::printf("\n");
  }
  for (int i = 0; i < 3; ++i) EXPECT_LT(b.rms_mrad[i], f.rms_mrad[i]) << "axis " << i;
}

TEST(TransferBatch, ShortWingRockScenario) { CheckBatch(ShortInputs(), "short (60 s), seed 1"); }

TEST(TransferBatch, PresetSeed1) { CheckBatch(PresetInputs(), "transfer-alignment-high-maneuver, seed 1"); }

}  // namespace transfer_alignment_batch_test
}  // namespace navtwin::transfer
