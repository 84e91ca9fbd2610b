// The transfer-alignment filter (problems/transfer_alignment/filter.h) on the preset
// transfer-alignment-high-maneuver, seed 1 (300 ms delay), orders 1 and 2.
#include "problems/transfer_alignment/filter.h"

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "core/imu_error_model.h"
#include "core/rotation.h"
#include "core/sim/scenario.h"
#include "core/units.h"
#include "problems/transfer_alignment/history_filter.h"
#include "problems/transfer_alignment/run.h"

namespace navtwin::transfer {
namespace transfer_alignment_filter_test {

const TransferInputs& PresetInputs() {
  static const TransferInputs in =
      SimulateTransferInputs(sim::LoadScenario("transfer-alignment-high-maneuver"), 1);
  return in;
}

// Measured (seed 1, default TransferConfig): order 1 delay 295.8 ms, order 2 288.0 ms
// (sigma 0.1-0.3 ms: the filter is over-confident, the compensation's truncation error
// during the wing rock - 120-200 mrad RMS of attitude mismatch, master_test.cc - biases the
// delay). Tolerances: delay within 20 ms (a 12 ms error costs omega * 12 ms = 1 mrad at
// the turns' 0.08 rad/s), misalignment within 5 mrad, order 2 below order 1 in RMS on
// every axis, order 2 level (roll, pitch) RMS below 15 mrad and heading below 5 mrad.
TEST(TransferFilter, PresetOrder1AndOrder2) {
  const TransferInputs& in = PresetInputs();
  const TransferConfig cfg;
  TransferResult r[2];
  for (int i = 0; i < 2; ++i) {
    r[i] = RunMethod(in, cfg, i == 0 ? Method::kOrder1 : Method::kOrder2);
    std::printf("%s", TransferResultTable(r[i]).c_str());
  }
  std::printf("seed-style table (mrad, RMS / max after %.0f s), delay ms, misalignment error mrad\n", cfg.settle_s);
  for (int i = 0; i < 2; ++i) {
    std::printf("order%d  roll %6.2f / %6.2f  pitch %6.2f / %6.2f  heading %6.2f / %6.2f  delay %.1f  mis %.2f  run %.3f s\n",
                i + 1, r[i].rms_mrad.x(), r[i].max_mrad.x(), r[i].rms_mrad.y(), r[i].max_mrad.y(), r[i].rms_mrad.z(),
                r[i].max_mrad.z(), 1e3 * r[i].delay_s, r[i].misalignment_error_mrad, r[i].run_time_s);
  }
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(r[i].delay_s, *in.true_delay_s, 0.020) << "order " << i + 1;
    EXPECT_LT(r[i].misalignment_error_mrad, 5.0) << "order " << i + 1;
  }
  for (int axis = 0; axis < 3; ++axis) EXPECT_LT(r[1].rms_mrad[axis], r[0].rms_mrad[axis]) << "axis " << axis;
  EXPECT_LT(r[1].rms_mrad.head<2>().maxCoeff(), 15.0);
  EXPECT_LT(r[1].rms_mrad.z(), 5.0);
  // Their covariance understates the errors (delay 4-12 ms off with sigma 0.1-0.3 ms; the
  // truncation bounds make the reported sigma 48 and 6.3 ms, but the first neglected term
  // understates a series that does not converge here), and the innovations show it without
  // the truth: mean NIS 38 and 16 (expected 6); the run says so.
  for (int i = 0; i < 2; ++i) {
    std::printf("order%d: mean NIS %.1f, NEES of (misalignment, delay) %.0f\n", i + 1, r[i].nis_mean,
                r[i].nees_misalignment_delay);
    EXPECT_GT(r[i].nis_mean, 12.0) << "order " << i + 1;
    EXPECT_NE(r[i].note.find("innovations inconsistent"), std::string::npos) << r[i].note;
  }
}

// A gentle flight (docs/transfer/seed-regime-bounded.yaml, seed 1, 300 ms): the series'
// remainder is below the master's noise at each record but in phase with the delay's own
// column, so it biases the delay alike at every record: order 1 -2.87 ms, order 2 -1.91 ms
// (within 0.06 ms of that on each of 50 seeds), where the covariance alone says 0.16 and
// 0.11 ms (NEES of (misalignment, delay) 350 and 320; mean NIS 0.3: under the conservative
// master sigma the innovations cannot show it). With the truncation bounds
// (TransferFilterRun::truncation_bound) the reported sigma are 13.1 and 5.2 ms,
// misalignment 0.86 and 0.55 mrad per axis; NEES 0.06 and 0.16. Tolerances: the delay error
// inside 3 sigma, NEES below chi-square(4)'s 99.9 % point (18.5), and a delay bound of at
// least 1 ms (it must not vanish where the covariance alone claims 0.1 ms).
TEST(TransferFilter, TheSigmaCarryTheSeriesTruncationOnAGentleFlight) {
  const TransferInputs in = SimulateTransferInputs(
      sim::LoadScenario(std::string(NAVTWIN_SOURCE_DIR) + "/docs/transfer/seed-regime-bounded.yaml"), 1);
  for (const DelayOrder order : {DelayOrder::kFirst, DelayOrder::kSecond}) {
    const TransferFilterRun run = RunTransferFilter(in, TransferConfig{}, order);
    EXPECT_GT(run.truncation_bound(3), 1e-3);
    EXPECT_GT(run.truncation_bound.head<3>().minCoeff(), 0.0);
    const TransferResult r = RunMethod(in, TransferConfig{}, order == DelayOrder::kFirst ? Method::kOrder1 : Method::kOrder2);
    std::printf("%s", TransferResultTable(r).c_str());
    EXPECT_LT(std::abs(r.delay_s - *in.true_delay_s), 3.0 * r.delay_sigma_s);
    EXPECT_LT(r.nees_misalignment_delay, 18.5);
    EXPECT_NE(r.note.find("truncation bounds"), std::string::npos) << r.note;
  }
  // The history filter has no series.
  EXPECT_TRUE(RunHistoryFilter(in, TransferConfig{}).truncation_bound.isZero(0.0));
}

// The consider analysis (TransferFilterRun::instrument_sensitivity) against the filter
// itself: the preset's slave IMU re-measured with an extra instrument error dp (each
// sample's increments K x + b dt, core/imu_error_model.h) moves the final misalignment and
// delay by -S dp to first order (S acts on the error state, true minus estimate). Measured:
// the largest component of each within 1 %, the small ones (the delay shifts among them)
// within 30 %. One error at a time, each of the priors' size: 100 ppm on
// the accelerometer's x scale factor, 20 arcsec on the gyro's xy misalignment, 200 ug on the
// accelerometer's y bias, 1 deg/h on the gyro's z bias; at 0 ms (no series truncation) and
// 300 ms. Tolerance: 25 % of |S dp| plus 2 urad / 2 us (the iterated update and the
// nominal's own change make the filter only approximately linear in dp).
TEST(TransferFilter, InstrumentSensitivityPredictsTheFiltersResponse) {
  for (const double delay_s : {0.0, 0.3}) {
    const TransferInputs base =
        SimulateTransferInputs(sim::LoadScenario("transfer-alignment-high-maneuver"), 1, delay_s);
    const TransferConfig cfg;
    const TransferFilterRun run0 = RunTransferFilter(base, cfg, DelayOrder::kSecond);
    const std::pair<int, double> errors[] = {{istate::kSa, 100e-6},
                                             {istate::kMg, 20.0 * kArcsec_rad},
                                             {istate::kBa + 1, 200.0 * kMicroG_mps2},
                                             {istate::kBg + 2, 1.0 * kDegPerHour_radps}};
    for (const auto& [index, size] : errors) {
      InstrumentPrior dp = InstrumentPrior::Zero();
      dp(index) = size;
      TransferInputs in = base;
      for (ImuSample& x : in.slave_imu) {
        x.dtheta_b_rad = TriadMatrix(dp.data() + istate::kSg) * x.dtheta_b_rad + TriadBias(dp.data() + istate::kSg) * x.dt_s;
        x.dv_b_mps = TriadMatrix(dp.data() + istate::kSa) * x.dv_b_mps + TriadBias(dp.data() + istate::kSa) * x.dt_s;
      }
      const TransferFilterRun run = RunTransferFilter(in, cfg, DelayOrder::kSecond);
      Eigen::Vector4d moved;
      moved.head<3>() = LogSO3<double>(Eigen::Matrix3d(run.epochs.back().misalignment.toRotationMatrix() *
                                                       run0.epochs.back().misalignment.toRotationMatrix().transpose()));
      moved(3) = run.epochs.back().delay_s - run0.epochs.back().delay_s;
      // S is the sensitivity of the error state (true minus estimate): the estimate moves by -S dp.
      const Eigen::Vector4d predicted = -run0.instrument_sensitivity * dp;
      std::printf("delay %.1f s, error %2d: moved [%.3g %.3g %.3g %.3g], predicted [%.3g %.3g %.3g %.3g]\n", delay_s,
                  index, moved(0), moved(1), moved(2), moved(3), predicted(0), predicted(1), predicted(2),
                  predicted(3));
      for (int i = 0; i < 4; ++i) {
        EXPECT_NEAR(moved(i), predicted(i), 0.25 * predicted.norm() + 2e-6)
            << "delay " << delay_s << " error " << index << " component " << i << "\nmoved     "
            << moved.transpose() << "\npredicted " << predicted.transpose();
      }
    }
  }
}

// One epoch per master record inside the slave span, finite, sigma shrinking from the
// initial values (the configuration's 1 m/s, 2 deg, 2 deg, 0.5 s).
TEST(TransferFilter, EpochsAndCovariance) {
  const TransferInputs& in = PresetInputs();
  const TransferFilterRun run = RunTransferFilter(in, TransferConfig{}, DelayOrder::kSecond);
  std::size_t inside = 0;
  for (const NavState& m : in.master) {
    if (m.t_s >= in.slave_initial.t_s - 1e-9 && m.t_s <= in.slave_imu.back().t_s + 1e-9) ++inside;
  }
  ASSERT_EQ(run.epochs.size(), inside);
  const TransferEpoch& last = run.epochs.back();
  EXPECT_TRUE(last.sigma.allFinite());
  EXPECT_LT(last.sigma(9), 0.5);
  EXPECT_LT(last.sigma.segment<3>(6).maxCoeff(), 2.0 * M_PI / 180.0);
  for (std::size_t k = 1; k < run.epochs.size(); ++k) ASSERT_GT(run.epochs[k].t_s, run.epochs[k - 1].t_s);
}

TEST(TransferFilter, RejectsABadConfiguration) {
  TransferConfig cfg;
  cfg.master_attitude_rad = 0.0;
  EXPECT_THROW(RunTransferFilter(PresetInputs(), cfg, DelayOrder::kFirst), std::invalid_argument);
}

}  // namespace transfer_alignment_filter_test
}  // namespace navtwin::transfer
