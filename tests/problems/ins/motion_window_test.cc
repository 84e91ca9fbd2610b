// MotionWindow (problems/ins/measurement_rules.h): on noise-free steps of a known motion it
// returns the rate, angular acceleration, acceleration and jerk at the window's end (exact
// for a rate and an acceleration linear in time), and its shrinkage sets an estimate of the
// size of the IMU's noise to zero while leaving a manoeuvre's values nearly untouched.
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "core/types.h"
#include "core/units.h"
#include "problems/ins/measurement_rules.h"

namespace navtwin::ins {
namespace ins_motion_window_test {

constexpr double kDt_s = 0.01;  // 100 Hz steps

/// One step ending at t_s of a motion with rate w0 + alpha t and acceleration a0 + j t
/// (exact integrals over the step), plus the given noise increments.
ImuSample Step(double t_s, const Eigen::Vector3d& w0, const Eigen::Vector3d& alpha, const Eigen::Vector3d& a0,
               const Eigen::Vector3d& j, Eigen::Vector3d* dv_n,
               const Eigen::Vector3d& dtheta_noise = Eigen::Vector3d::Zero(),
               const Eigen::Vector3d& dv_noise = Eigen::Vector3d::Zero()) {
  const double mid = t_s - 0.5 * kDt_s;
  ImuSample s;
  s.t_s = t_s;
  s.dt_s = kDt_s;
  s.dtheta_b_rad = (w0 + alpha * mid) * kDt_s + dtheta_noise;
  *dv_n = (a0 + j * mid) * kDt_s + dv_noise;
  return s;
}

TEST(MotionWindow, LinearRateAndAccelerationAreRecoveredAtTheEnd) {
  const Eigen::Vector3d w0(0.1, -0.2, 0.3), alpha(0.5, 0.1, -0.4), a0(1.0, -2.0, 0.5), j(0.3, 0.7, -0.2);
  MotionWindow window(0.0, 0.0);  // no noise: no shrinkage
  for (int k = 1; k <= 100; ++k) {
    Eigen::Vector3d dv;
    const ImuSample s = Step(k * kDt_s, w0, alpha, a0, j, &dv);
    window.Add(s, dv);
  }
  const double t = 1.0;
  const ImuMotion m = window.Get(0.0);
  EXPECT_LT((m.omega_ib_b_radps - (w0 + alpha * t)).norm(), 1e-12);
  EXPECT_LT((m.alpha_ib_b_radps2 - alpha).norm(), 1e-10);
  EXPECT_LT((m.a_n_mps2 - (a0 + j * t)).norm(), 1e-12);
  EXPECT_LT((m.j_n_mps3 - j).norm(), 1e-10);
}

TEST(MotionWindow, BeforeTwoHalvesOnlyTheNewerMeanAndNoRates) {
  MotionWindow window(0.0, 0.0);
  EXPECT_EQ(window.Get(0.0).a_n_mps2, Eigen::Vector3d::Zero());
  Eigen::Vector3d dv;
  const ImuSample s = Step(kDt_s, Eigen::Vector3d(0, 0, 0.2), Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 0, 0),
                           Eigen::Vector3d::Zero(), &dv);
  window.Add(s, dv);
  const ImuMotion m = window.Get(0.0);
  EXPECT_LT((m.a_n_mps2 - Eigen::Vector3d(1, 0, 0)).norm(), 1e-12);
  EXPECT_LT((m.omega_ib_b_radps - Eigen::Vector3d(0, 0, 0.2)).norm(), 1e-12);
  EXPECT_EQ(m.j_n_mps3, Eigen::Vector3d::Zero());
  EXPECT_EQ(m.alpha_ib_b_radps2, Eigen::Vector3d::Zero());
}

// White noise of a MEMS IMU (3 deg/sqrt(h), 0.849 m/s/sqrt(h)) on a still IMU: the window's
// acceleration estimate has a per-axis sigma of 0.07 m/s^2; shrunk, it is zero in about 89 %
// of the epochs (chi-square 3 dof below 6) and its mean square falls by more than a factor
// 10. A 2 m/s^2 turn acceleration keeps 99 % of its size (1 - 6 sigma^2 / |a|^2); a tilt
// variance of (1 deg)^2 sets a 0.3 m/s^2 estimate to zero (g times 1 deg is 0.17 m/s^2).
TEST(MotionWindow, ShrinkageRemovesNoiseAndKeepsAManoeuvre) {
  const double arw = 3.0 * kDegPerSqrtHour_radpsqrts, vrw = 0.849 * kMpsPerSqrtHour_mpspsqrts;
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  const auto noise = [&](double density) -> Eigen::Vector3d {
    return Eigen::Vector3d(normal(rng), normal(rng), normal(rng)) * density * std::sqrt(kDt_s);
  };
  MotionWindow still(arw, vrw), raw(0.0, 0.0);
  int zero = 0, epochs = 0;
  double shrunk_sq = 0.0, raw_sq = 0.0;
  for (int k = 1; k <= 20000; ++k) {
    Eigen::Vector3d dv;
    const Eigen::Vector3d z = Eigen::Vector3d::Zero();
    const ImuSample s = Step(k * kDt_s, z, z, z, z, &dv, noise(arw), noise(vrw));
    still.Add(s, dv);
    raw.Add(s, dv);
    if (k % 20 != 0 || k < 40) continue;  // every 0.2 s: independent windows
    const ImuMotion m = still.Get(0.0);
    ++epochs;
    zero += m.a_n_mps2.isZero(0.0);
    shrunk_sq += m.a_n_mps2.squaredNorm();
    raw_sq += raw.Get(0.0).a_n_mps2.squaredNorm();
  }
  EXPECT_NEAR(static_cast<double>(zero) / epochs, 0.89, 0.05);
  EXPECT_LT(shrunk_sq, raw_sq / 10.0);

  MotionWindow turn(arw, vrw);
  for (int k = 1; k <= 30; ++k) {
    Eigen::Vector3d dv;
    const Eigen::Vector3d z = Eigen::Vector3d::Zero();
    turn.Add(Step(k * kDt_s, Eigen::Vector3d(0, 0, 0.1), z, Eigen::Vector3d(0, 2.0, 0), z, &dv), dv);
  }
  EXPECT_NEAR(turn.Get(0.0).a_n_mps2.y(), 2.0, 0.02);
  MotionWindow tilted(arw, vrw);
  for (int k = 1; k <= 30; ++k) {
    Eigen::Vector3d dv;
    const Eigen::Vector3d z = Eigen::Vector3d::Zero();
    tilted.Add(Step(k * kDt_s, z, z, Eigen::Vector3d(0.3, 0, 0), z, &dv), dv);
  }
  EXPECT_GT(tilted.Get(0.0).a_n_mps2.x(), 0.0);
  EXPECT_EQ(tilted.Get(std::pow(kDegToRad, 2)).a_n_mps2, Eigen::Vector3d::Zero());
}

}  // namespace ins_motion_window_test
}  // namespace navtwin::ins
