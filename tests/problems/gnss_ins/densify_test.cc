// Densify: mechanization between knots with the knots' IMU errors, the mismatch spread
// linearly, knots between IMU epochs, every IMU epoch out; the output decimator.
#include "problems/gnss_ins/densify.h"

#include <cmath>
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/imu_split.h"
#include "core/rotation.h"
#include "core/strapdown.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_densify_test {

constexpr double kDt = 0.01;   // 100 Hz
constexpr int kSamples = 600;  // 6 s

/// Error-free increments of a manoeuvring vehicle: turning, pitching, accelerating.
ImuSample TrueSample(int k) {
  const double t = k * kDt, tm = t - 0.5 * kDt;
  ImuSample s;
  s.t_s = t;
  s.dt_s = kDt;
  s.dtheta_b_rad = Eigen::Vector3d(0.02 * std::sin(0.5 * tm), 0.01, 0.05) * kDt;
  s.dv_b_mps = Eigen::Vector3d(0.5 + 0.2 * std::sin(tm), 0.1, -9.79) * kDt;
  return s;
}

NavState Start() {
  NavState s;
  s.t_s = 0.0;
  s.lat_rad = 30.0 * kDegToRad;
  s.lon_rad = 114.0 * kDegToRad;
  s.h_m = 20.0;
  s.v_n_mps = Eigen::Vector3d(10.0, 5.0, 0.0);
  s.q_n_b = QuatFromEuler(0.01, 0.02, 0.7);
  return s;
}

struct Truth {
  std::map<int, NavState> at_imu;          // by sample index
  std::vector<NavState> at_knots;          // at the knot times
};

/// Continuous mechanization of the true samples; states at every IMU epoch and, for knot
/// times between IMU epochs, a side mechanization over the first part of the split sample.
Truth MakeTruth(const std::vector<double>& knot_times) {
  Truth truth;
  Strapdown mech(Start());
  std::size_t next = 0;
  if (knot_times[0] == 0.0) {
    truth.at_knots.push_back(Start());
    ++next;
  }
  for (int k = 1; k <= kSamples; ++k) {
    const ImuSample s = TrueSample(k);
    while (next < knot_times.size() && knot_times[next] < s.t_s - 1e-12) {
      Strapdown side = mech;
      side.Update(SplitImuSample(s, knot_times[next]).first);
      truth.at_knots.push_back(side.state());
      ++next;
    }
    mech.Update(s);
    truth.at_imu[k] = mech.state();
    if (next < knot_times.size() && std::abs(knot_times[next] - s.t_s) < 1e-12) {
      truth.at_knots.push_back(mech.state());
      ++next;
    }
  }
  return truth;
}

const std::vector<double> kKnotTimes = {0.0, 0.333, 0.5, 1.2345, 2.0, 3.005, 4.0, 5.0};

Solution Knots(const Truth& truth, const ImuErrors& errors) {
  Solution s;
  s.method = "test";
  for (const NavState& n : truth.at_knots) {
    NavEpoch e;
    e.state.nav = n;
    e.state.imu = errors;
    e.std = Eigen::VectorXd::Constant(15, 1.0);
    s.epochs.push_back(e);
  }
  return s;
}

Inputs ImuInputs(const ImuErrors& errors) {
  Inputs in;
  for (int k = 1; k <= kSamples; ++k) {
    ImuSample s = TrueSample(k);
    // Raw = (1 + s) true + b dt, the model CorrectImu inverts (ins_state.h).
    s.dtheta_b_rad = (Eigen::Vector3d::Ones() + errors.sg).cwiseProduct(s.dtheta_b_rad) + errors.bg_radps * kDt;
    s.dv_b_mps = (Eigen::Vector3d::Ones() + errors.sa).cwiseProduct(s.dv_b_mps) + errors.ba_mps2 * kDt;
    in.imu.push_back(s);
  }
  return in;
}

Eigen::Vector3d NedError(const NavState& est, const NavState& truth) {
  return wgs84::GeodeticToNed({est.lat_rad, est.lon_rad, est.h_m}, {truth.lat_rad, truth.lon_rad, truth.h_m});
}

std::vector<NavEpoch> DensifyAll(const Solution& knots, const Inputs& in) {
  std::vector<NavEpoch> out;
  Densify(knots, in, [&](const NavEpoch& e) { out.push_back(e); });
  return out;
}

// Knots on the true trajectory, IMU with biases and scale-factor errors the knots know:
// the dense output is the true trajectory at every IMU epoch. The only difference is where
// the mechanization splits a sample at a knot (two-sample coning/sculling over the split
// parts), O(omega^2 dt^2) per split: 1e-6 m, 1e-7 m/s and 1e-9 rad bound it.
TEST(Densify, ReproducesTheTrajectoryFromConsistentKnots) {
  ImuErrors errors;
  errors.bg_radps = Eigen::Vector3d(1e-3, -2e-3, 5e-4);
  errors.ba_mps2 = Eigen::Vector3d(0.05, -0.02, 0.1);
  errors.sg = Eigen::Vector3d(2e-3, -1e-3, 5e-4);
  errors.sa = Eigen::Vector3d(-1e-3, 3e-3, 1e-3);
  const Truth truth = MakeTruth(kKnotTimes);
  ASSERT_EQ(truth.at_knots.size(), kKnotTimes.size());
  const std::vector<NavEpoch> out = DensifyAll(Knots(truth, errors), ImuInputs(errors));
  ASSERT_EQ(out.size(), static_cast<std::size_t>(kSamples));  // every IMU epoch after t = 0
  for (int k = 1; k <= kSamples; ++k) {
    const NavState& e = out[k - 1].state.nav;
    const NavState& t = truth.at_imu.at(k);
    ASSERT_NEAR(e.t_s, t.t_s, 1e-12);
    EXPECT_LT(NedError(e, t).norm(), 1e-6) << k;
    EXPECT_LT((e.v_n_mps - t.v_n_mps).norm(), 1e-7) << k;
    EXPECT_LT(AttitudeError(t.q_n_b, e.q_n_b).norm(), 1e-9) << k;
    // Blended (1 - w) a + w b of equal knots: equal up to rounding.
    EXPECT_LT((out[k - 1].state.imu.bg_radps - errors.bg_radps).norm(), 1e-18) << k;
  }
}

// A mismatch at knot 4 (t = 2.0 s) is spread linearly over (1.2345, 2.0]: the error at t is
// w times the mismatch, w = (t - 1.2345) / 0.7655.
TEST(Densify, SpreadsTheMismatchLinearly) {
  const Truth truth = MakeTruth(kKnotTimes);
  Solution knots = Knots(truth, ImuErrors());
  NavState& k4 = knots.epochs[4].state.nav;
  const double M = wgs84::MeridianRadius(k4.lat_rad) + k4.h_m;
  k4.lat_rad += 1.0 / M;  // 1 m north
  k4.h_m += 0.5;          // 0.5 m up
  k4.v_n_mps += Eigen::Vector3d(0.1, -0.2, 0.0);
  const Eigen::Vector3d phi(0.0, 0.0, 0.01);
  k4.q_n_b = ApplyAttitudeError(phi, k4.q_n_b);
  knots.epochs[3].std.setConstant(1.0);
  knots.epochs[4].std.setConstant(3.0);
  const std::vector<NavEpoch> out = DensifyAll(knots, ImuInputs(ImuErrors()));
  int checked = 0;
  for (const NavEpoch& e : out) {
    const double t = e.state.nav.t_s;
    if (t <= 1.2345 || t > 2.0 + 1e-9) continue;
    const int k = static_cast<int>(std::lround(t / kDt));
    const NavState& tr = truth.at_imu.at(k);
    const double w = (t - 1.2345) / (2.0 - 1.2345);
    const Eigen::Vector3d dp = NedError(e.state.nav, tr);
    // 1e-6 m etc.: the splitting effect of the test above; the spread itself is exact
    // to first order in the 1 m offset (1e-7 m from the radius of curvature).
    EXPECT_NEAR(dp.x(), w * 1.0, 1e-6) << t;
    EXPECT_NEAR(dp.z(), -w * 0.5, 1e-6) << t;
    EXPECT_NEAR(e.state.nav.v_n_mps.x() - tr.v_n_mps.x(), w * 0.1, 1e-7) << t;
    EXPECT_NEAR(e.state.nav.v_n_mps.y() - tr.v_n_mps.y(), -w * 0.2, 1e-7) << t;
    EXPECT_NEAR(AttitudeError(e.state.nav.q_n_b, tr.q_n_b).z(), w * 0.01, 1e-8) << t;
    EXPECT_NEAR(e.std[0], 1.0 + 2.0 * w, 1e-12) << t;
    ++checked;
  }
  EXPECT_EQ(checked, 77);  // IMU epochs 1.24 .. 2.00
}

// Every IMU epoch after the first knot, through the last knot (5 s) to the end of the IMU
// record; decimated to 10 Hz for a file (OutputDecimator): the first epoch, then the first
// IMU epoch at or after each 0.1 s.
TEST(Densify, EveryImuEpochAndContinuesAfterTheLastKnot) {
  const Truth truth = MakeTruth(kKnotTimes);
  Solution knots = Knots(truth, ImuErrors());
  knots.epochs.back().std.setConstant(7.0);
  const std::vector<NavEpoch> out = DensifyAll(knots, ImuInputs(ImuErrors()));
  ASSERT_EQ(out.size(), static_cast<std::size_t>(kSamples));
  for (int k = 1; k <= kSamples; ++k) ASSERT_NEAR(out[k - 1].state.nav.t_s, k * kDt, 1e-12) << k;
  EXPECT_EQ(out.back().std[0], 7.0);
  EXPECT_LT(NedError(out.back().state.nav, truth.at_imu.at(kSamples)).norm(), 1e-6);
  OutputDecimator decimator(10.0);
  std::vector<double> taken;
  for (const NavEpoch& e : out) {
    if (decimator.Take(e.state.nav.t_s)) taken.push_back(e.state.nav.t_s);
  }
  ASSERT_EQ(taken.size(), 61u);
  EXPECT_NEAR(taken[0], 0.01, 1e-12);
  for (std::size_t i = 1; i < taken.size(); ++i) EXPECT_NEAR(taken[i], 0.1 * i, 1e-9) << i;
}

TEST(OutputDecimator, EveryEpochAtRateZero) {
  OutputDecimator every(0.0);
  for (int k = 0; k < 10; ++k) EXPECT_TRUE(every.Take(k * 0.01));
  OutputDecimator d(2.0);
  std::vector<double> taken;
  for (int k = 1; k <= 100; ++k) {
    if (d.Take(k * 0.0333)) taken.push_back(k * 0.0333);
  }
  // 2 Hz from 0.0333 s: the first IMU epoch at or after 0.5, 1.0, 1.5, ... 3.0 s.
  ASSERT_EQ(taken.size(), 7u);
  EXPECT_NEAR(taken[1], 0.5328, 1e-12);
}

}  // namespace gnss_ins_densify_test
}  // namespace navtwin::gnss_ins
