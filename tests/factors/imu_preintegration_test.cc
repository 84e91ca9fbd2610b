// ImuPreintegration and its factor: (1) residual at the true states of error-free
// trajectories (static; 15 m/s and 250 m/s turning, accelerating, climbing flight) with
// jittered sample intervals and states between samples; (2) bias and scale-factor
// Jacobians against Reintegrate (central differences) and the factor's corrections; (3) the autodiff
// Jacobian against central differences in the tangent spaces; (4) the covariance and the
// whitening against a Monte Carlo of noisy increments. Figures: docs/imu-preintegration.md.
#include "factors/imu_preintegration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/imu_error_model.h"
#include "core/imu_split.h"
#include "core/rotation.h"
#include "core/sim/random.h"
#include "core/sim/truth.h"
#include "core/units.h"
#include "factors/attitude_manifold.h"
#include "factors/position_manifold.h"

namespace navtwin {
namespace factors_imu_preintegration_test {

// ---------------------------------------------------------------------------------------
// Trajectories.

/// Speed V(t) = v0 + v1 t, heading psi = psi0 + psi1 t + psi_amp sin(psi_w t), flight-path
/// angle gamma = gamma_amp sin(gamma_w t); v_n = V (cos g cos psi, cos g sin psi, -sin g);
/// roll = atan(V psi' / g0) + roll_amp sin(roll_w t) (coordinated turn plus rocking),
/// pitch = gamma + 0.05 + 0.02 sin(0.9 t), yaw = psi + 0.03 sin(0.7 t).
struct FlightShape {
  double v0, v1, psi0, psi1, psi_amp, psi_w, gamma_amp, gamma_w, roll_amp, roll_w;
};

class Flight : public sim::AnalyticTrajectory {
 public:
  explicit Flight(const FlightShape& s) : s_(s) {}

  Eigen::Vector3d Euler_rad(double t) const override {
    return {std::atan(Speed(t) * Psi(t, 1) / kStandardGravity_mps2) + s_.roll_amp * std::sin(s_.roll_w * t),
            Gamma(t, 0) + 0.05 + 0.02 * std::sin(0.9 * t), Psi(t, 0) + 0.03 * std::sin(0.7 * t)};
  }
  Eigen::Vector3d EulerRate_radps(double t) const override {
    const double x = Speed(t) * Psi(t, 1) / kStandardGravity_mps2;
    const double dx = (s_.v1 * Psi(t, 1) + Speed(t) * Psi(t, 2)) / kStandardGravity_mps2;
    return {dx / (1.0 + x * x) + s_.roll_amp * s_.roll_w * std::cos(s_.roll_w * t),
            Gamma(t, 1) + 0.018 * std::cos(0.9 * t), Psi(t, 1) + 0.021 * std::cos(0.7 * t)};
  }
  Eigen::Vector3d Velocity_n_mps(double t) const override { return Speed(t) * Direction(t); }
  Eigen::Vector3d Acceleration_n_mps2(double t) const override {
    const double g = Gamma(t, 0), dg = Gamma(t, 1), p = Psi(t, 0), dp = Psi(t, 1);
    const Eigen::Vector3d d_dir(-std::sin(g) * dg * std::cos(p) - std::cos(g) * std::sin(p) * dp,
                                -std::sin(g) * dg * std::sin(p) + std::cos(g) * std::cos(p) * dp,
                                -std::cos(g) * dg);
    return s_.v1 * Direction(t) + Speed(t) * d_dir;
  }

 private:
  double Speed(double t) const { return s_.v0 + s_.v1 * t; }
  // n-th derivative (0, 1, 2) of psi and gamma.
  double Psi(double t, int n) const {
    const double w = s_.psi_w;
    if (n == 0) return s_.psi0 + s_.psi1 * t + s_.psi_amp * std::sin(w * t);
    if (n == 1) return s_.psi1 + s_.psi_amp * w * std::cos(w * t);
    return -s_.psi_amp * w * w * std::sin(w * t);
  }
  double Gamma(double t, int n) const {
    const double w = s_.gamma_w;
    if (n == 0) return s_.gamma_amp * std::sin(w * t);
    return s_.gamma_amp * w * std::cos(w * t);
  }
  Eigen::Vector3d Direction(double t) const {
    const double g = Gamma(t, 0), p = Psi(t, 0);
    return {std::cos(g) * std::cos(p), std::cos(g) * std::sin(p), -std::sin(g)};
  }
  FlightShape s_;
};

// 250 m/s accelerating at 3 m/s^2, turning at 0.05 .. 0.1 rad/s (up to 25 m/s^2 lateral,
// bank up to 69 deg), climbing/diving at up to 12 m/s, rocking +-0.2 rad in roll.
const FlightShape kFast{250.0, 3.0, 0.3, 0.05, 0.1, 0.5, 0.05, 0.3, 0.2, 1.1};
// 15 m/s, turning at up to 0.2 rad/s (3 m/s^2), climbing at up to 0.75 m/s.
const FlightShape kSlow{15.0, 0.2, -1.0, 0.1, 0.2, 0.5, 0.05, 0.3, 0.1, 0.8};

class Static : public sim::AnalyticTrajectory {
 public:
  Eigen::Vector3d Euler_rad(double) const override { return {0.02, -0.01, 1.0}; }
  Eigen::Vector3d EulerRate_radps(double) const override { return Eigen::Vector3d::Zero(); }
  Eigen::Vector3d Velocity_n_mps(double) const override { return Eigen::Vector3d::Zero(); }
  Eigen::Vector3d Acceleration_n_mps2(double) const override { return Eigen::Vector3d::Zero(); }
};

// ---------------------------------------------------------------------------------------
// Error-free data: truth at 1 kHz (exact increments, core/sim/truth.h), summed into IMU
// samples of 4, 5, 6, 5, 4, 6 ms (a jittered 200 Hz IMU with intervals from time tags), or
// kept as 1 ms samples.

struct Record {
  std::vector<NavState> truth;     // at t = k ms
  std::vector<ImuSample> imu;      // jittered
};

Record MakeRecord(const sim::AnalyticTrajectory& trajectory, double duration_s, bool one_ms = false) {
  const wgs84::Geodetic start{45.0 * kDegToRad, 10.0 * kDegToRad, 3000.0};
  sim::TruthGenerator gen(trajectory, start, 1000.0);
  Record rec;
  rec.truth.push_back(gen.current().state);
  const int pattern[] = {4, 5, 6, 5, 4, 6};
  int group = 0, in_group = 0;
  ImuSample acc;
  double t_start = 0.0;
  const long n = std::lround(duration_s * 1000.0);
  for (long k = 1; k <= n; ++k) {
    const sim::TruthSample& s = gen.Next();
    rec.truth.push_back(s.state);
    acc.dtheta_b_rad += s.exact.dtheta_b_rad;
    acc.dv_b_mps += s.exact.dv_b_mps;
    if (++in_group == (one_ms ? 1 : pattern[group % 6])) {
      acc.t_s = s.t_s;
      acc.dt_s = s.t_s - t_start;  // from the time tags
      rec.imu.push_back(acc);
      acc = ImuSample();
      t_start = s.t_s;
      in_group = 0;
      ++group;
    }
  }
  return rec;
}

/// Preintegrates the samples over [t_i, t_j], splitting the samples that straddle t_i or t_j.
std::shared_ptr<ImuPreintegration> Preintegrate(const std::vector<ImuSample>& imu, double t_i, double t_j,
                                                const ImuErrors& lin, double arw, double vrw) {
  auto pre = std::make_shared<ImuPreintegration>(lin, arw, vrw);
  constexpr double kEps = 1e-9;  // time-tag comparison (tags are multiples of 1 ms)
  for (ImuSample s : imu) {
    const double t0 = s.t_s - s.dt_s;
    if (s.t_s <= t_i + kEps || t0 >= t_j - kEps) continue;
    if (t0 < t_i - kEps) s = SplitImuSample(s, t_i).second;
    if (s.t_s > t_j + kEps) s = SplitImuSample(s, t_j).first;
    pre->Integrate(s);
  }
  return pre;
}

std::shared_ptr<ImuPreintegration> Preintegrate(const std::vector<ImuSample>& imu, double t_i,
                                                double t_j, const Eigen::Vector3d& bg,
                                                const Eigen::Vector3d& ba, double arw, double vrw) {
  ImuErrors lin;
  lin.bg_radps = bg;
  lin.ba_mps2 = ba;
  return Preintegrate(imu, t_i, t_j, lin, arw, vrw);
}

/// A state as the factor's parameter blocks.
struct Blocks {
  double pos[3], vel[3], q[4], bg[3], ba[3];
};

Blocks ToBlocks(const NavState& s, const Eigen::Vector3d& bg = Eigen::Vector3d::Zero(),
                const Eigen::Vector3d& ba = Eigen::Vector3d::Zero()) {
  Blocks b;
  b.pos[0] = s.lat_rad;
  b.pos[1] = s.lon_rad;
  b.pos[2] = s.h_m;
  Eigen::Map<Eigen::Vector3d>(b.vel) = s.v_n_mps;
  Eigen::Map<Eigen::Vector4d>(b.q) = s.q_n_b.coeffs();
  Eigen::Map<Eigen::Vector3d>(b.bg) = bg;
  Eigen::Map<Eigen::Vector3d>(b.ba) = ba;
  return b;
}

Eigen::Matrix<double, 9, 1> Residual(const ImuPreintegration& pre, const Blocks& i, const Blocks& j,
                                     bool whitened) {
  return ImuFactorResidual(pre, i.pos, i.vel, i.q, i.bg, i.ba, j.pos, j.vel, j.q, whitened);
}

// Typical tactical/MEMS densities for the factor tests: 0.1 deg/sqrt(h), 0.03 m/s/sqrt(h)
// would make S huge; the values below keep whitened numbers O(1..1e3).
constexpr double kArw = 3e-3;  // rad/sqrt(s)
constexpr double kVrw = 1e-2;  // m/s/sqrt(s)

// ---------------------------------------------------------------------------------------
// (1) Residual at the true states.
//
// Error budget (docs/imu-preintegration.md, "Neglected terms") for dt <= 1 s, with the
// extremes of the shapes above (from the truth at 1 kHz): 250 m/s flight |w| <= 0.46 rad/s,
// |alpha| <= 0.36 rad/s^2, |f| <= 29.5 m/s^2, |f'| <= 7.9 m/s^3, |a_n| <= 29 m/s^2,
// |v| <= 290 m/s; 15 m/s flight 0.24, 0.10, 10.5, 0.92, 3.5, 18; latitude 45 deg.
//  - constant rate and specific force inside each sample of h s (no coning or sculling
//    correction): per second |w||alpha| h^2/12 rad and (|w||f'| + |alpha||f|) h^2/12 m/s,
//    for h = 6 ms: 5e-7 rad, 4.3e-5 m/s (250 m/s); 7e-8 rad, 3.9e-6 m/s (15 m/s);
//  - a sample split at a state (SplitImuSample, constant rate) errs by |alpha| t1 t2 / 2
//    and |f'| t1 t2 / 2 with t1 t2 <= (3 ms)^2, at each end: 1.6e-6 rad, 3.6e-5 m/s
//    (250 m/s); 4.7e-7 rad, 4.1e-6 m/s (15 m/s); the velocity error at the start grows
//    into a position error of that times dt;
//  - Earth model, first order in w_in dt, from the change of w_in and c = 2 w_ie + w_en
//    over the interval (|w_en'| <= |a_n| / (R cos lat)): velocity
//    |w_en'| (|a_n| + |f|) dt^3 / 12 = 3.2e-5 m/s (9e-7), position |w_en'| |v| dt^3 / 12
//    = 1.6e-4 m (1.1e-6), and the midpoint radii |a_n| |v| tan(lat) dt^3 / (12 R) =
//    1.1e-4 m (8e-7); second order in w_in dt: < 1e-7;
//  - the truth generator (Gauss-Legendre increments, RK4 position at 1 kHz): < 1e-10.
// The tolerances below are the sums of these bounds (the observed values are 3..10 times
// smaller: the bounds take every term at its worst at once).
// Static: the second order of the Earth rate, |w_ie|^2 |g| dt^3 / 6 = 9e-9 m/s and
// |w_ie|^2 |g| dt^4 / 24 = 2e-9 m; the attitude is exact to rounding.

struct Window {
  double t_i, t_j;
};

// 1 s and 0.2 s windows: 2.0, 3.0, 7.5, 12.0, 12.2 s are sample boundaries of the jittered
// IMU, 10.003, 11.003, 5.001, 5.201, 8.5 s fall inside samples (split).
const Window kWindows[] = {{2.0, 3.0}, {10.003, 11.003}, {5.001, 5.201}, {12.0, 12.2}, {7.5, 8.5}};

struct Tolerance {
  double att_rad, vel_mps, pos_m;
};

void ExpectSmallResidual(const Record& rec, const Window& w, const Tolerance& tol, const char* name) {
  const long ki = std::lround(w.t_i * 1000.0), kj = std::lround(w.t_j * 1000.0);
  const auto pre = Preintegrate(rec.imu, rec.truth[ki].t_s, rec.truth[kj].t_s, Eigen::Vector3d::Zero(),
                                Eigen::Vector3d::Zero(), kArw, kVrw);
  ASSERT_NEAR(pre->dt_s(), w.t_j - w.t_i, 1e-9);
  const Eigen::Matrix<double, 9, 1> r =
      Residual(*pre, ToBlocks(rec.truth[ki]), ToBlocks(rec.truth[kj]), /*whitened=*/false);
  std::printf("  %-16s [%6.3f, %6.3f] s: attitude %.2e rad, velocity %.2e m/s, position %.2e m\n",
              name, w.t_i, w.t_j, r.segment<3>(0).norm(), r.segment<3>(3).norm(),
              r.segment<3>(6).norm());
  EXPECT_LT(r.segment<3>(0).norm(), tol.att_rad) << name << " " << w.t_i;
  EXPECT_LT(r.segment<3>(3).norm(), tol.vel_mps) << name << " " << w.t_i;
  EXPECT_LT(r.segment<3>(6).norm(), tol.pos_m) << name << " " << w.t_i;
}

TEST(ImuPreintegration, ResidualAtTruthStatic) {
  const Record rec = MakeRecord(Static(), 13.0);
  // Rounding of ~1e3 summed increments: < 1e-12 rad; Earth rate: see above (margin 3).
  for (const Window& w : kWindows) ExpectSmallResidual(rec, w, {1e-12, 3e-8, 1e-8}, "static");
}

TEST(ImuPreintegration, ResidualAtTruthSlowFlight) {
  const Record rec = MakeRecord(Flight(kSlow), 13.0);
  for (const Window& w : kWindows) ExpectSmallResidual(rec, w, {2e-6, 1.5e-5, 1e-5}, "15 m/s");
}

TEST(ImuPreintegration, ResidualAtTruthFastFlight) {
  const Record rec = MakeRecord(Flight(kFast), 13.0);
  for (const Window& w : kWindows) ExpectSmallResidual(rec, w, {5e-6, 1.5e-4, 3.3e-4}, "250 m/s");
}

TEST(ImuPreintegration, ResidualAtTruthFastFlight1kHz) {
  // 1 ms samples, no split: the discretisation terms shrink 36 times (coning 1.4e-8 rad,
  // sculling 1.2e-6 m/s), which leaves the Earth-model terms (3.2e-5 m/s, 2.7e-4 m).
  const Record rec = MakeRecord(Flight(kFast), 13.0, /*one_ms=*/true);
  for (const Window& w : kWindows) ExpectSmallResidual(rec, w, {3e-8, 4e-5, 3e-4}, "250 m/s, 1 kHz");
}

// ---------------------------------------------------------------------------------------
// (2) Bias Jacobians.

TEST(ImuPreintegration, BiasJacobiansMatchReintegration) {
  const Record rec = MakeRecord(Flight(kFast), 4.0);
  const Eigen::Vector3d bg0(1e-3, -2e-3, 5e-4), ba0(0.02, -0.01, 0.03);
  const auto pre = Preintegrate(rec.imu, 2.0, 3.0, bg0, ba0, kArw, kVrw);
  // Central differences of the reintegrated increments. Steps: 1e-5 rad/s, 1e-4 m/s^2;
  // truncation h^2 |d3/db3| / 6 (|d3 dv/dbg3| ~ |f| dt^4 < 30) < 1e-9 and rounding
  // eps |dv| / h < 1e-9, against Jacobians of O(0.1 .. 10): relative 1e-7 is safe.
  constexpr double kHg = 1e-5, kHa = 1e-4;
  Eigen::Matrix3d num_R_bg, num_v_bg, num_v_ba, num_p_bg, num_p_ba, num_R_ba;
  for (int k = 0; k < 3; ++k) {
    ImuPreintegration plus = *pre, minus = *pre;
    plus.Reintegrate(bg0 + kHg * Eigen::Vector3d::Unit(k), ba0);
    minus.Reintegrate(bg0 - kHg * Eigen::Vector3d::Unit(k), ba0);
    num_R_bg.col(k) = (LogSO3<double>(pre->delta_R().transpose() * plus.delta_R()) -
                       LogSO3<double>(pre->delta_R().transpose() * minus.delta_R())) / (2 * kHg);
    num_v_bg.col(k) = (plus.delta_v_mps() - minus.delta_v_mps()) / (2 * kHg);
    num_p_bg.col(k) = (plus.delta_p_m() - minus.delta_p_m()) / (2 * kHg);
    plus.Reintegrate(bg0, ba0 + kHa * Eigen::Vector3d::Unit(k));
    minus.Reintegrate(bg0, ba0 - kHa * Eigen::Vector3d::Unit(k));
    num_R_ba.col(k) = (LogSO3<double>(pre->delta_R().transpose() * plus.delta_R()) -
                       LogSO3<double>(pre->delta_R().transpose() * minus.delta_R())) / (2 * kHa);
    num_v_ba.col(k) = (plus.delta_v_mps() - minus.delta_v_mps()) / (2 * kHa);
    num_p_ba.col(k) = (plus.delta_p_m() - minus.delta_p_m()) / (2 * kHa);
  }
  const auto expect_close = [](const Eigen::Matrix3d& analytic, const Eigen::Matrix3d& numeric,
                               const char* what) {
    std::printf("  %s: |analytic - numeric| / |numeric| = %.1e\n", what,
                (analytic - numeric).norm() / numeric.norm());
    EXPECT_LT((analytic - numeric).norm(), 1e-7 * std::max(1.0, numeric.norm()))
        << what << "\nanalytic\n" << analytic << "\nnumeric\n" << numeric;
  };
  expect_close(pre->J_R_bg(), num_R_bg, "J_R_bg");
  expect_close(pre->J_v_bg(), num_v_bg, "J_v_bg");
  expect_close(pre->J_v_ba(), num_v_ba, "J_v_ba");
  expect_close(pre->J_p_bg(), num_p_bg, "J_p_bg");
  expect_close(pre->J_p_ba(), num_p_ba, "J_p_ba");
  EXPECT_LT(num_R_ba.norm(), 1e-12);  // the rotation does not depend on ba
}

/// Biases and scale factors of a consumer IMU to linearise at (1500-3000 ppm).
ImuErrors NonZeroLinearisation() {
  ImuErrors lin;
  lin.bg_radps = Eigen::Vector3d(1e-3, -2e-3, 5e-4);
  lin.ba_mps2 = Eigen::Vector3d(0.02, -0.01, 0.03);
  lin.sg = Eigen::Vector3d(1500e-6, -800e-6, 2000e-6);
  lin.sa = Eigen::Vector3d(-1200e-6, 900e-6, 3000e-6);
  return lin;
}

// The scale-factor Jacobians, and the bias Jacobians at non-zero scale factors (where the
// bias enters divided by 1 + s), against central differences of Reintegrate. Steps 1e-5:
// truncation h^2 |d3/ds3| / 6 with |d3 dv/ds3| ~ 6 |dv| < 200 gives 3e-9, rounding
// eps |dv| / h < 1e-9, against Jacobians of O(1 .. 30).
TEST(ImuPreintegration, ScaleFactorJacobiansMatchReintegration) {
  const Record rec = MakeRecord(Flight(kFast), 4.0);
  const ImuErrors lin = NonZeroLinearisation();
  const auto pre = Preintegrate(rec.imu, 2.0, 3.0, lin, kArw, kVrw);
  using Member = Eigen::Vector3d ImuErrors::*;
  // Central differences of (rotation, velocity, position) in one member of the errors.
  const auto numeric = [&](Member member, double h) {
    Eigen::Matrix<double, 9, 3> J;
    for (int k = 0; k < 3; ++k) {
      ImuErrors up = lin, down = lin;
      (up.*member)[k] += h;
      (down.*member)[k] -= h;
      ImuPreintegration plus = *pre, minus = *pre;
      plus.Reintegrate(up);
      minus.Reintegrate(down);
      J.block<3, 1>(0, k) = (LogSO3<double>(pre->delta_R().transpose() * plus.delta_R()) -
                             LogSO3<double>(pre->delta_R().transpose() * minus.delta_R())) / (2 * h);
      J.block<3, 1>(3, k) = (plus.delta_v_mps() - minus.delta_v_mps()) / (2 * h);
      J.block<3, 1>(6, k) = (plus.delta_p_m() - minus.delta_p_m()) / (2 * h);
    }
    return J;
  };
  const auto expect_close = [](const Eigen::Matrix3d& analytic, const Eigen::Matrix3d& numeric_J, const char* what) {
    std::printf("  %s: |analytic - numeric| / |numeric| = %.1e\n", what,
                (analytic - numeric_J).norm() / numeric_J.norm());
    EXPECT_LT((analytic - numeric_J).norm(), 1e-7 * std::max(1.0, numeric_J.norm()))
        << what << "\nanalytic\n" << analytic << "\nnumeric\n" << numeric_J;
  };
  const Eigen::Matrix<double, 9, 3> sg = numeric(&ImuErrors::sg, 1e-5), sa = numeric(&ImuErrors::sa, 1e-5);
  const Eigen::Matrix<double, 9, 3> bg = numeric(&ImuErrors::bg_radps, 1e-5);
  const Eigen::Matrix<double, 9, 3> ba = numeric(&ImuErrors::ba_mps2, 1e-4);
  expect_close(pre->J_R_sg(), sg.block<3, 3>(0, 0), "J_R_sg");
  expect_close(pre->J_v_sg(), sg.block<3, 3>(3, 0), "J_v_sg");
  expect_close(pre->J_p_sg(), sg.block<3, 3>(6, 0), "J_p_sg");
  expect_close(pre->J_v_sa(), sa.block<3, 3>(3, 0), "J_v_sa");
  expect_close(pre->J_p_sa(), sa.block<3, 3>(6, 0), "J_p_sa");
  EXPECT_LT(sa.topRows<3>().norm(), 1e-12);  // the rotation does not depend on sa
  expect_close(pre->J_R_bg(), bg.block<3, 3>(0, 0), "J_R_bg at s != 0");
  expect_close(pre->J_v_bg(), bg.block<3, 3>(3, 0), "J_v_bg at s != 0");
  expect_close(pre->J_p_bg(), bg.block<3, 3>(6, 0), "J_p_bg at s != 0");
  expect_close(pre->J_v_ba(), ba.block<3, 3>(3, 0), "J_v_ba at s != 0");
  expect_close(pre->J_p_ba(), ba.block<3, 3>(6, 0), "J_p_ba at s != 0");
  // The scale factors' effect is large enough that the check means something: 2000 ppm of
  // a 1 s turn at 0.46 rad/s is about 1e-3 rad, of 30 m/s^2 for 1 s 0.06 m/s.
  EXPECT_GT(pre->J_R_sg().norm(), 0.1);
  EXPECT_GT(pre->J_v_sa().norm(), 10.0);
}

// Samples with 2000 ppm scale-factor errors (and biases), preintegrated at zero errors.
struct ScaleCorrection {
  Eigen::Matrix<double, 9, 1> uncorrected, corrected;  ///< residuals at the true states, s = 0 and s true
  double remainder_rad = 0.0, remainder_mps = 0.0;     ///< Corrected() against Reintegrate
};

ScaleCorrection CorrectScaleFactors(const Record& rec, double fraction) {
  ImuErrors truth;
  truth.bg_radps = Eigen::Vector3d(2e-4, -3e-4, 1e-4) * fraction;
  truth.ba_mps2 = Eigen::Vector3d(0.05, -0.03, 0.08) * fraction;
  truth.sg = Eigen::Vector3d(2000e-6, -2000e-6, 2000e-6) * fraction;
  truth.sa = Eigen::Vector3d(-2000e-6, 2000e-6, 2000e-6) * fraction;
  std::vector<ImuSample> measured = rec.imu;
  for (ImuSample& s : measured) {  // omega_meas = (1 + sg) omega + bg (core/imu_errors.h)
    s.dtheta_b_rad = (Eigen::Vector3d::Ones() + truth.sg).cwiseProduct(s.dtheta_b_rad) + truth.bg_radps * s.dt_s;
    s.dv_b_mps = (Eigen::Vector3d::Ones() + truth.sa).cwiseProduct(s.dv_b_mps) + truth.ba_mps2 * s.dt_s;
  }
  const auto pre = Preintegrate(measured, 2.0, 3.0, ImuErrors{}, kArw, kVrw);
  const Blocks i = ToBlocks(rec.truth[2000], truth.bg_radps, truth.ba_mps2), j = ToBlocks(rec.truth[3000]);
  double sg[3], sa[3], zero[3] = {0.0, 0.0, 0.0};
  Eigen::Map<Eigen::Vector3d>{sg} = truth.sg;
  Eigen::Map<Eigen::Vector3d>{sa} = truth.sa;
  ScaleCorrection c;
  c.corrected = ImuScaleFactorResidual(*pre, i.pos, i.vel, i.q, i.bg, i.ba, sg, sa, j.pos, j.vel, j.q, false);
  c.uncorrected = ImuScaleFactorResidual(*pre, i.pos, i.vel, i.q, i.bg, i.ba, zero, zero, j.pos, j.vel, j.q, false);
  ImuPreintegration re = *pre;
  re.Reintegrate(truth);
  const ImuPreintegration::Deltas d = pre->Corrected(truth);
  c.remainder_rad = AttitudeError<double>(d.delta_q, re.delta_q()).norm();
  c.remainder_mps = (d.delta_v_mps - re.delta_v_mps()).norm();
  return c;
}

// The factor at the true scale factors and biases leaves the second-order remainder of the
// first-order correction; at zero scale factors it leaves their whole effect. The remainder
// is shown to be second order: it shrinks four times when the errors are halved.
TEST(ImuPreintegration, FactorCorrectsScaleFactorsToFirstOrder) {
  const Record rec = MakeRecord(Flight(kFast), 4.0);
  const ScaleCorrection full = CorrectScaleFactors(rec, 1.0), half = CorrectScaleFactors(rec, 0.5);
  std::printf("  uncorrected %.2e rad %.2e m/s %.2e m, corrected %.2e rad %.2e m/s %.2e m\n",
              full.uncorrected.segment<3>(0).norm(), full.uncorrected.segment<3>(3).norm(),
              full.uncorrected.segment<3>(6).norm(), full.corrected.segment<3>(0).norm(),
              full.corrected.segment<3>(3).norm(), full.corrected.segment<3>(6).norm());
  std::printf("  remainder of the first-order correction: %.2e rad %.2e m/s; at half the errors %.2e rad %.2e m/s\n",
              full.remainder_rad, full.remainder_mps, half.remainder_rad, half.remainder_mps);
  // Uncorrected: 2000 ppm of the 1 s rotation (0.46 rad) and velocity change (|f| <= 30 m/s^2).
  EXPECT_GT(full.uncorrected.segment<3>(0).norm(), 2e-4);
  EXPECT_GT(full.uncorrected.segment<3>(3).norm(), 0.01);
  // The remainder is second order (ratio 4 for halved errors; 3..5 leaves room for the
  // third-order terms), and small against the effect it corrects (below 1 %).
  EXPECT_GT(full.remainder_rad / half.remainder_rad, 3.0);
  EXPECT_LT(full.remainder_rad / half.remainder_rad, 5.0);
  EXPECT_GT(full.remainder_mps / half.remainder_mps, 3.0);
  EXPECT_LT(full.remainder_mps / half.remainder_mps, 5.0);
  EXPECT_LT(full.remainder_rad, 0.01 * full.uncorrected.segment<3>(0).norm());
  EXPECT_LT(full.remainder_mps, 0.01 * full.uncorrected.segment<3>(3).norm());
  // Corrected: that remainder on top of test (1)'s budget for the 250 m/s flight without
  // split samples (5e-7 rad, 7.5e-5 m/s, 2.9e-4 m); the position remainder is at most the
  // velocity one integrated over the 1 s interval.
  EXPECT_LT(full.corrected.segment<3>(0).norm(), 5e-7 + full.remainder_rad);
  EXPECT_LT(full.corrected.segment<3>(3).norm(), 7.5e-5 + full.remainder_mps);
  EXPECT_LT(full.corrected.segment<3>(6).norm(), 2.9e-4 + full.remainder_mps);
}

/// The samples a triad with errors lin (biases, scale factors) and axis misalignments mg, ma
/// would give for the exact increments of `truth_samples`: raw = (I + S + M) x + b dt.
std::vector<ImuSample> WithInstrumentErrors(const std::vector<ImuSample>& truth_samples, const ImuErrors& lin,
                                            const Eigen::Matrix<double, 6, 1>& mg,
                                            const Eigen::Matrix<double, 6, 1>& ma) {
  // Triad blocks of core/imu_error_model.h: scale factors, misalignments (bias apart).
  double gyro[kTriadParameters] = {}, accel[kTriadParameters] = {};
  Eigen::Map<Eigen::Vector3d>{gyro} = lin.sg;
  Eigen::Map<Eigen::Matrix<double, 6, 1>>(gyro + 3) = mg;
  Eigen::Map<Eigen::Vector3d>{accel} = lin.sa;
  Eigen::Map<Eigen::Matrix<double, 6, 1>>(accel + 3) = ma;
  const Eigen::Matrix3d Eg = TriadMatrix(gyro), Ea = TriadMatrix(accel);
  std::vector<ImuSample> out = truth_samples;
  for (ImuSample& x : out) {
    x.dtheta_b_rad = Eg * x.dtheta_b_rad + lin.bg_radps * x.dt_s;
    x.dv_b_mps = Ea * x.dv_b_mps + lin.ba_mps2 * x.dt_s;
  }
  return out;
}

std::shared_ptr<ImuPreintegration> PreintegrateTracked(const std::vector<ImuSample>& imu, const ImuErrors& lin) {
  auto pre = std::make_shared<ImuPreintegration>(lin, kArw, kVrw);
  pre->TrackAxisMisalignment();
  for (const ImuSample& x : imu) {
    if (x.t_s - x.dt_s >= 2.0 - 1e-9 && x.t_s <= 3.0 + 1e-9) pre->Integrate(x);
  }
  return pre;
}

// J_mg, J_ma against central differences: the same exact increments measured by triads whose
// misalignment entry k is +-h, preintegrated at the same (non-zero) biases and scale factors.
// The raw samples that correct to (I + S + M)^-1 (raw - b dt) at M = +-h are built
// explicitly, so this checks the model and the recursion. Step 1e-5: truncation and
// rounding as in the scale-factor test (1e-9 against Jacobians of O(1 .. 30)).
TEST(ImuPreintegration, AxisMisalignmentJacobiansMatchCentralDifferences) {
  const Record rec = MakeRecord(Flight(kFast), 4.0);
  const ImuErrors lin = NonZeroLinearisation();
  const Eigen::Matrix<double, 6, 1> zero = Eigen::Matrix<double, 6, 1>::Zero();
  // The exact increments: the record's samples are the truth's.
  const auto pre = PreintegrateTracked(WithInstrumentErrors(rec.imu, lin, zero, zero), lin);
  const double h = 1e-5;
  for (int sensor = 0; sensor < 2; ++sensor) {
    Eigen::Matrix<double, 9, 6> numeric;
    for (int k = 0; k < 6; ++k) {
      const Eigen::Matrix<double, 6, 1> d = h * Eigen::Matrix<double, 6, 1>::Unit(k);
      const auto plus = PreintegrateTracked(
          WithInstrumentErrors(rec.imu, lin, sensor == 0 ? d : zero, sensor == 1 ? d : zero), lin);
      const auto minus = PreintegrateTracked(
          WithInstrumentErrors(rec.imu, lin, sensor == 0 ? Eigen::Matrix<double, 6, 1>(-d) : zero,
                               sensor == 1 ? Eigen::Matrix<double, 6, 1>(-d) : zero),
          lin);
      // The preintegration of samples measured with M = +-h, at M = 0, gives the increments
      // at the truth moved by -J dm: the columns are minus the difference.
      numeric.block<3, 1>(0, k) = -(LogSO3<double>(pre->delta_R().transpose() * plus->delta_R()) -
                                    LogSO3<double>(pre->delta_R().transpose() * minus->delta_R())) / (2 * h);
      numeric.block<3, 1>(3, k) = -(plus->delta_v_mps() - minus->delta_v_mps()) / (2 * h);
      numeric.block<3, 1>(6, k) = -(plus->delta_p_m() - minus->delta_p_m()) / (2 * h);
    }
    const Eigen::Matrix<double, 9, 6>& analytic = sensor == 0 ? pre->J_mg() : pre->J_ma();
    std::printf("  %s: |analytic - numeric| / |numeric| = %.1e, |J| = %.2f\n", sensor == 0 ? "J_mg" : "J_ma",
                (analytic - numeric).norm() / numeric.norm(), numeric.norm());
    EXPECT_LT((analytic - numeric).norm(), 1e-7 * std::max(1.0, numeric.norm())) << "analytic\n"
                                                                                 << analytic << "\nnumeric\n"
                                                                                 << numeric;
    EXPECT_GT(numeric.norm(), 0.1);  // the fast flight makes every entry matter
  }
  EXPECT_LT(pre->J_ma().topRows<3>().norm(), 1e-15);  // the rotation does not depend on ma
}

// Samples with 1e-3 rad axis misalignments preintegrated at zero: the factor at the true
// misalignments leaves a second-order remainder (|M|^2 ~ 1e-6 of the effect), at zero their
// whole effect (1e-3 of the 1 s rotation and velocity change).
TEST(ImuPreintegration, InstrumentFactorCorrectsAxisMisalignmentToFirstOrder) {
  const Record rec = MakeRecord(Flight(kFast), 4.0);
  Eigen::Matrix<double, 6, 1> mg, ma;
  mg << 1e-3, -1e-3, 5e-4, 1e-3, -5e-4, 1e-3;
  ma << -1e-3, 5e-4, 1e-3, -1e-3, 1e-3, 5e-4;
  const auto pre = PreintegrateTracked(WithInstrumentErrors(rec.imu, ImuErrors{}, mg, ma), ImuErrors{});
  const Blocks i = ToBlocks(rec.truth[2000]), j = ToBlocks(rec.truth[3000]);
  const double zero3[3] = {0, 0, 0}, zero6[6] = {0, 0, 0, 0, 0, 0};
  const Eigen::Matrix<double, 9, 1> corrected = ImuInstrumentFactorResidual(
      *pre, i.pos, i.vel, i.q, i.bg, i.ba, zero3, zero3, mg.data(), ma.data(), j.pos, j.vel, j.q, false);
  const Eigen::Matrix<double, 9, 1> uncorrected = ImuInstrumentFactorResidual(
      *pre, i.pos, i.vel, i.q, i.bg, i.ba, zero3, zero3, zero6, zero6, j.pos, j.vel, j.q, false);
  std::printf("  uncorrected %.2e rad %.2e m/s, corrected %.2e rad %.2e m/s\n", uncorrected.head<3>().norm(),
              uncorrected.segment<3>(3).norm(), corrected.head<3>().norm(), corrected.segment<3>(3).norm());
  EXPECT_GT(uncorrected.head<3>().norm(), 1e-4);
  EXPECT_GT(uncorrected.segment<3>(3).norm(), 5e-3);
  // Corrected: test (1)'s budget for this flight (5e-7 rad, 7.5e-5 m/s) plus 1 % of the effect.
  EXPECT_LT(corrected.head<3>().norm(), 5e-7 + 0.01 * uncorrected.head<3>().norm());
  EXPECT_LT(corrected.segment<3>(3).norm(), 7.5e-5 + 0.01 * uncorrected.segment<3>(3).norm());
  // Without TrackAxisMisalignment the factor cannot be made; tracking starts before a sample.
  const auto untracked = Preintegrate(rec.imu, 2.0, 3.0, ImuErrors{}, kArw, kVrw);
  EXPECT_THROW(CreateImuInstrumentFactor(untracked), std::invalid_argument);
  ImuPreintegration late = *untracked;
  EXPECT_THROW(late.TrackAxisMisalignment(), std::logic_error);
  EXPECT_TRUE(untracked->J_mg().isZero(0.0));
}

TEST(ImuPreintegration, FactorCorrectsBiasToFirstOrder) {
  const Record rec = MakeRecord(Flight(kFast), 4.0);
  const Eigen::Vector3d bg(2e-4, -3e-4, 1e-4), ba(0.05, -0.03, 0.08);  // 40..60 deg/h, 3..8 mg
  std::vector<ImuSample> biased = rec.imu;
  for (ImuSample& s : biased) {
    s.dtheta_b_rad += bg * s.dt_s;
    s.dv_b_mps += ba * s.dt_s;
  }
  const Blocks i = ToBlocks(rec.truth[2000], bg, ba), j = ToBlocks(rec.truth[3000]);
  const auto pre = Preintegrate(biased, 2.0, 3.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                kArw, kVrw);
  Blocks i_zero = i;
  Eigen::Map<Eigen::Vector3d>(i_zero.bg).setZero();
  Eigen::Map<Eigen::Vector3d>(i_zero.ba).setZero();
  const Eigen::Matrix<double, 9, 1> uncorrected = Residual(*pre, i_zero, j, false);
  const Eigen::Matrix<double, 9, 1> corrected = Residual(*pre, i, j, false);
  // Without the correction the residual is the bias effect: |bg| dt = 3.9e-4 rad,
  // |ba| dt = 0.1 m/s, |ba| dt^2/2 = 0.05 m.
  EXPECT_GT(uncorrected.segment<3>(0).norm(), 3e-4);
  EXPECT_GT(uncorrected.segment<3>(3).norm(), 0.08);
  EXPECT_GT(uncorrected.segment<3>(6).norm(), 0.04);
  // With it, what is left is second order in the bias (|dba| |dbg| dt^2 / 2 = 2e-5 m/s,
  // 7e-6 m, |dbg|^2 dt^2 / 2 = 7e-8 rad) on top of the error-free budget of test (1) for
  // the 250 m/s flight without split samples (5e-7 rad, 7.5e-5 m/s, 2.9e-4 m).
  EXPECT_LT(corrected.segment<3>(0).norm(), 1e-6);
  EXPECT_LT(corrected.segment<3>(3).norm(), 1e-4);
  EXPECT_LT(corrected.segment<3>(6).norm(), 3e-4);
  // Reintegrating at the true biases gives the error-free residual of test (1) back, and
  // Corrected() agrees with Reintegrate to second order in the bias change.
  ImuPreintegration re = *pre;
  re.Reintegrate(bg, ba);
  const ImuPreintegration::Deltas c = pre->Corrected(bg, ba);
  EXPECT_LT(AttitudeError<double>(c.delta_q, re.delta_q()).norm(), 1e-7);
  // Second-order terms: the cross term |dba| |dbg| dt^2 / 2 = 2e-5 m/s (|dba| dt^3/6 |dbg|
  // = 6.5e-6 m) dominates |f| |dbg|^2 dt^3 / 6 = 1e-6 m/s.
  EXPECT_LT((c.delta_v_mps - re.delta_v_mps()).norm(), 4e-5);
  EXPECT_LT((c.delta_p_m - re.delta_p_m()).norm(), 1.5e-5);
  const Eigen::Matrix<double, 9, 1> reintegrated = Residual(re, i, j, false);
  EXPECT_LT(reintegrated.segment<3>(0).norm(), 6e-7);
  EXPECT_LT(reintegrated.segment<3>(3).norm(), 7.5e-5);
  EXPECT_LT(reintegrated.segment<3>(6).norm(), 3e-4);
}

// ---------------------------------------------------------------------------------------
// (3) The autodiff Jacobian in the tangent spaces against central differences.

/// The cost's Jacobian (autodiff, mapped to the tangent spaces by the manifolds' PlusJacobian)
/// against central differences with the given step per block, at `blocks` (which it
/// perturbs and restores): each block within 1e-6 of its norm.
void ExpectJacobianMatchesCentralDifferences(const ceres::CostFunction& cost, const std::vector<double*>& blocks,
                                             const std::vector<const ceres::Manifold*>& manifolds,
                                             const std::vector<double>& steps) {
  ASSERT_EQ(blocks.size(), manifolds.size());
  ASSERT_EQ(blocks.size(), steps.size());
  const auto evaluate = [&](const std::vector<double*>& b, double** jac) {
    Eigen::Matrix<double, 9, 1> r;
    EXPECT_TRUE(cost.Evaluate(b.data(), r.data(), jac));
    return r;
  };
  // Ceres fills row-major 9 x size(block) arrays.
  const int num_blocks = static_cast<int>(blocks.size());
  std::vector<double*> jac_ptrs(blocks.size());
  std::vector<std::vector<double>> jac_storage(blocks.size());
  for (int b = 0; b < num_blocks; ++b) {
    jac_storage[b].resize(9 * cost.parameter_block_sizes()[b]);
    jac_ptrs[b] = jac_storage[b].data();
  }
  const Eigen::Matrix<double, 9, 1> r0 = evaluate(blocks, jac_ptrs.data());
  EXPECT_GT(r0.norm(), 10.0);

  for (int b = 0; b < num_blocks; ++b) {
    const int n = cost.parameter_block_sizes()[b];
    const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J_amb(
        jac_storage[b].data(), 9, n);
    Eigen::MatrixXd J_tan(9, 3);
    if (manifolds[b] != nullptr) {
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> plus_jac(n, 3);
      ASSERT_TRUE(manifolds[b]->PlusJacobian(blocks[b], plus_jac.data()));
      J_tan = J_amb * plus_jac;
    } else {
      J_tan = J_amb;
    }
    Eigen::MatrixXd J_num(9, 3);
    for (int k = 0; k < 3; ++k) {
      std::vector<double> x_plus(blocks[b], blocks[b] + n), x_minus(x_plus);
      double delta[3] = {0, 0, 0};
      delta[k] = steps[b];
      std::vector<double*> bp = blocks, bm = blocks;
      if (manifolds[b] != nullptr) {
        manifolds[b]->Plus(blocks[b], delta, x_plus.data());
        delta[k] = -steps[b];
        manifolds[b]->Plus(blocks[b], delta, x_minus.data());
      } else {
        x_plus[k] += steps[b];
        x_minus[k] -= steps[b];
      }
      bp[b] = x_plus.data();
      bm[b] = x_minus.data();
      J_num.col(k) = (evaluate(bp, nullptr) - evaluate(bm, nullptr)) / (2.0 * steps[b]);
    }
    std::printf("  block %d: |J| = %.2e, |autodiff - numeric| / |J| = %.1e\n", b, J_num.norm(),
                (J_tan - J_num).norm() / J_num.norm());
    EXPECT_LT((J_tan - J_num).norm(), 1e-6 * J_num.norm())
        << "block " << b << "\nautodiff\n" << J_tan << "\nnumeric\n" << J_num;
  }
}

TEST(ImuPreintegration, FactorJacobianMatchesCentralDifferences) {
  const Record rec = MakeRecord(Flight(kFast), 12.0);
  const Eigen::Vector3d bg0(1e-3, -2e-3, 5e-4), ba0(0.02, -0.01, 0.03);
  const auto pre = Preintegrate(rec.imu, 10.003, 11.003, bg0, ba0, kArw, kVrw);
  const std::unique_ptr<ceres::CostFunction> cost(CreateImuFactor(pre));
  ASSERT_EQ(cost->num_residuals(), 9);
  ASSERT_EQ(cost->parameter_block_sizes(), (std::vector<int32_t>{3, 3, 4, 3, 3, 3, 3, 4}));

  // A point away from the solution (whitened residuals O(10..1e3)).
  Blocks i = ToBlocks(rec.truth[10003], bg0 + Eigen::Vector3d(1e-4, 2e-4, -1e-4),
                      ba0 + Eigen::Vector3d(0.01, -0.02, 0.01));
  Blocks j = ToBlocks(rec.truth[11003]);
  const double dp_i[3] = {0.7, -1.2, 0.4}, dp_j[3] = {-0.3, 0.5, 1.1};
  const PositionManifold pos_manifold;
  const AttitudeManifold att_manifold;
  double tmp[4];
  PositionPlus(i.pos, dp_i, tmp);
  std::copy(tmp, tmp + 3, i.pos);
  PositionPlus(j.pos, dp_j, tmp);
  std::copy(tmp, tmp + 3, j.pos);
  Eigen::Map<Eigen::Vector3d>(i.vel) += Eigen::Vector3d(0.1, -0.05, 0.02);
  Eigen::Map<Eigen::Vector4d>(i.q) =
      ApplyAttitudeError<double>(Eigen::Vector3d(0.01, -0.02, 0.005), Eigen::Map<Eigen::Quaterniond>(i.q)).coeffs();
  Eigen::Map<Eigen::Vector4d>(j.q) =
      ApplyAttitudeError<double>(Eigen::Vector3d(-0.004, 0.01, 0.02), Eigen::Map<Eigen::Quaterniond>(j.q)).coeffs();

  std::vector<double*> blocks = {i.pos, i.vel, i.q, i.bg, i.ba, j.pos, j.vel, j.q};
  const std::vector<const ceres::Manifold*> manifolds = {&pos_manifold, nullptr, &att_manifold, nullptr,
                                                         nullptr, &pos_manifold, nullptr, &att_manifold};
  // Steps per block: 1e-3 m, 1e-4 m/s, 1e-6 rad, 1e-6 rad/s, 1e-5 m/s^2 (whitened changes
  // of 1e-3 .. 1e-2). Truncation h^2 |r'''| / 6 and rounding eps |r| / h are < 1e-8 relative
  // to the block's Jacobian norm; a position step is rounded to the ulp of lat/lon
  // (1e-16 rad = 0.7 nm, 7e-7 of the 1 mm step): tolerance 1e-6 relative.
  ExpectJacobianMatchesCentralDifferences(*cost, blocks, manifolds, {1e-3, 1e-4, 1e-6, 1e-6, 1e-5, 1e-3, 1e-4, 1e-6});
}

// The same for the factor with scale-factor blocks, linearised at non-zero scale factors and
// evaluated at others (steps 1e-6 on the scale factors: whitened changes of 1e-3).
TEST(ImuPreintegration, ScaleFactorJacobianMatchesCentralDifferences) {
  const Record rec = MakeRecord(Flight(kFast), 12.0);
  const ImuErrors lin = NonZeroLinearisation();
  const auto pre = Preintegrate(rec.imu, 10.003, 11.003, lin, kArw, kVrw);
  const std::unique_ptr<ceres::CostFunction> cost(CreateImuScaleFactor(pre));
  ASSERT_EQ(cost->num_residuals(), 9);
  ASSERT_EQ(cost->parameter_block_sizes(), (std::vector<int32_t>{3, 3, 4, 3, 3, 3, 3, 3, 3, 4}));
  Blocks i = ToBlocks(rec.truth[10003], lin.bg_radps + Eigen::Vector3d(1e-4, 2e-4, -1e-4),
                      lin.ba_mps2 + Eigen::Vector3d(0.01, -0.02, 0.01));
  Blocks j = ToBlocks(rec.truth[11003]);
  Eigen::Map<Eigen::Vector3d>(i.vel) += Eigen::Vector3d(0.1, -0.05, 0.02);
  Eigen::Map<Eigen::Vector4d>(i.q) =
      ApplyAttitudeError<double>(Eigen::Vector3d(0.01, -0.02, 0.005), Eigen::Map<Eigen::Quaterniond>(i.q)).coeffs();
  double sg[3] = {1000e-6, -500e-6, 2500e-6}, sa[3] = {-1000e-6, 1500e-6, 2000e-6};
  const PositionManifold pos_manifold;
  const AttitudeManifold att_manifold;
  std::vector<double*> blocks = {i.pos, i.vel, i.q, i.bg, i.ba, sg, sa, j.pos, j.vel, j.q};
  const std::vector<const ceres::Manifold*> manifolds = {
      &pos_manifold, nullptr, &att_manifold, nullptr, nullptr, nullptr, nullptr, &pos_manifold, nullptr, &att_manifold};
  ExpectJacobianMatchesCentralDifferences(*cost, blocks, manifolds,
                                          {1e-3, 1e-4, 1e-6, 1e-6, 1e-5, 1e-6, 1e-6, 1e-3, 1e-4, 1e-6});
  // At the linearisation point's scale factors it is the factor without them.
  double sg_lin[3], sa_lin[3];
  Eigen::Map<Eigen::Vector3d>{sg_lin} = lin.sg;
  Eigen::Map<Eigen::Vector3d>{sa_lin} = lin.sa;
  const Eigen::Matrix<double, 9, 1> with =
      ImuScaleFactorResidual(*pre, i.pos, i.vel, i.q, i.bg, i.ba, sg_lin, sa_lin, j.pos, j.vel, j.q, true);
  EXPECT_LT((with - Residual(*pre, i, j, true)).norm(), 1e-12 * with.norm());
}


TEST(ImuPreintegration, CeresRecoversStateJ) {
  // State i and the biases held, state j started 5 m, 0.5 m/s and 0.05 rad off: the factor
  // alone determines j (9 residuals, 9 tangent dimensions), so the solver must return to
  // the truth within the error-free residual budget of test (1) (250 m/s, 1 s, no split:
  // 5e-7 rad, 7.5e-5 m/s, 2.9e-4 m).
  const Record rec = MakeRecord(Flight(kFast), 4.0);
  const auto pre = Preintegrate(rec.imu, 2.0, 3.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                kArw, kVrw);
  Blocks i = ToBlocks(rec.truth[2000]);
  const Blocks j_true = ToBlocks(rec.truth[3000]);
  Blocks j = j_true;
  const double off[3] = {3.0, -4.0, 0.5};
  double moved[3];
  PositionPlus(j_true.pos, off, moved);
  std::copy(moved, moved + 3, j.pos);
  Eigen::Map<Eigen::Vector3d>(j.vel) += Eigen::Vector3d(0.3, -0.4, 0.1);
  Eigen::Map<Eigen::Vector4d>(j.q) =
      ApplyAttitudeError<double>(Eigen::Vector3d(0.03, -0.02, 0.03), Eigen::Map<const Eigen::Quaterniond>(j_true.q))
          .coeffs();

  ceres::Problem problem;
  problem.AddResidualBlock(CreateImuFactor(pre), nullptr, i.pos, i.vel, i.q, i.bg, i.ba, j.pos, j.vel, j.q);
  problem.SetManifold(i.pos, new PositionManifold);
  problem.SetManifold(j.pos, new PositionManifold);
  problem.SetManifold(i.q, new AttitudeManifold);
  problem.SetManifold(j.q, new AttitudeManifold);
  for (double* b : {i.pos, i.vel, i.q, i.bg, i.ba}) problem.SetParameterBlockConstant(b);
  ceres::Solver::Options options;
  options.max_num_iterations = 20;
  options.function_tolerance = 1e-16;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
  double dp[3];
  PositionMinus(j.pos, j_true.pos, dp);
  EXPECT_LT(Eigen::Map<const Eigen::Vector3d>(dp).norm(), 3e-4);
  EXPECT_LT((Eigen::Map<const Eigen::Vector3d>(j.vel) - Eigen::Map<const Eigen::Vector3d>(j_true.vel)).norm(),
            7.5e-5);
  EXPECT_LT(AttitudeError<double>(Eigen::Map<const Eigen::Quaterniond>(j.q),
                                  Eigen::Map<const Eigen::Quaterniond>(j_true.q))
                .norm(),
            6e-7);
}

// ---------------------------------------------------------------------------------------
// (4) Covariance and whitening against a Monte Carlo of noisy increments.

TEST(ImuPreintegration, CovarianceMatchesMonteCarlo) {
  const Record rec = MakeRecord(Flight(kFast), 12.0);
  const double t_i = rec.truth[10003].t_s, t_j = rec.truth[11003].t_s;
  const Eigen::Vector3d bg0 = Eigen::Vector3d::Zero(), ba0 = Eigen::Vector3d::Zero();
  const auto clean = Preintegrate(rec.imu, t_i, t_j, bg0, ba0, kArw, kVrw);
  const ImuPreintegration::Matrix9d S = clean->SqrtInformation();
  const Blocks bi = ToBlocks(rec.truth[10003]), bj = ToBlocks(rec.truth[11003]);

  // N runs: the whitened sample covariance (mean known to be 0) has entries with standard
  // deviation sqrt(2/N) on the diagonal and sqrt(1/N) off it, the sample mean 1/sqrt(N);
  // 5 of those is the tolerance (a deterministic seed; a factor-2 variance error or a
  // dropped v-p correlation would be > 20 sigma). The discrete (per-increment) noise of
  // the simulation and the continuous-time p-p term of the model differ by 1/(4 K^2)
  // (K = 200 samples), the neglected rotation terms of the noise input by < 1e-2 relative.
  constexpr int kRuns = 3000;
  sim::Rng rng(1);
  Eigen::Matrix<double, 9, 9> cov_pre = Eigen::Matrix<double, 9, 9>::Zero();
  Eigen::Matrix<double, 9, 9> cov_res = Eigen::Matrix<double, 9, 9>::Zero();
  Eigen::Matrix<double, 9, 1> mean_res = Eigen::Matrix<double, 9, 1>::Zero();
  for (int run = 0; run < kRuns; ++run) {
    ImuPreintegration noisy(bg0, ba0, kArw, kVrw);
    for (ImuSample s : clean->samples()) {
      s.dtheta_b_rad += rng.Normal3(kArw * std::sqrt(s.dt_s));
      s.dv_b_mps += rng.Normal3(kVrw * std::sqrt(s.dt_s));
      noisy.Integrate(s);
    }
    Eigen::Matrix<double, 9, 1> e;
    e.segment<3>(0) = LogSO3<double>(clean->delta_R().transpose() * noisy.delta_R());
    e.segment<3>(3) = noisy.delta_v_mps() - clean->delta_v_mps();
    e.segment<3>(6) = noisy.delta_p_m() - clean->delta_p_m();
    const Eigen::Matrix<double, 9, 1> z = S * e;
    cov_pre += z * z.transpose() / kRuns;
    // The factor (whitened with the same S, rotated into NED) at the true states.
    const Eigen::Matrix<double, 9, 1> r = Residual(noisy, bi, bj, /*whitened=*/true);
    cov_res += r * r.transpose() / kRuns;
    mean_res += r / kRuns;
  }
  const double tol_diag = 5.0 * std::sqrt(2.0 / kRuns), tol_off = 5.0 * std::sqrt(1.0 / kRuns);
  for (int a = 0; a < 9; ++a) {
    for (int b = 0; b < 9; ++b) {
      const double expected = a == b ? 1.0 : 0.0, tol = a == b ? tol_diag : tol_off;
      EXPECT_NEAR(cov_pre(a, b), expected, tol) << "preintegration (" << a << "," << b << ")";
      EXPECT_NEAR(cov_res(a, b), expected, tol) << "factor residual (" << a << "," << b << ")";
    }
  }
  EXPECT_LT(mean_res.cwiseAbs().maxCoeff(), 5.0 / std::sqrt(kRuns));
  const Eigen::Matrix<double, 9, 9> I9 = Eigen::Matrix<double, 9, 9>::Identity();
  std::printf("  %d runs: max |S C S^T - I| preintegration %.3f, factor residual %.3f "
              "(tolerance %.3f diagonal, %.3f off); max |mean residual| %.3f\n",
              kRuns, (cov_pre - I9).cwiseAbs().maxCoeff(), (cov_res - I9).cwiseAbs().maxCoeff(),
              tol_diag, tol_off, mean_res.cwiseAbs().maxCoeff());
}

TEST(ImuPreintegration, CovarianceStaticClosedForm) {
  // At rest (specific force -g_b, rotation only the Earth's 7e-5 rad/s) the covariance has a
  // closed form in continuous time: the attitude error is ARW times a Wiener process W, the
  // velocity error VRW W' - [f]x int W, the position error its integral, so
  //   tr P_phi = 3 ARW^2 T,
  //   tr P_v   = 3 VRW^2 T   + 2 |g|^2 ARW^2 T^3 / 3,
  //   tr P_p   =   VRW^2 T^3 + 2 |g|^2 ARW^2 T^5 / 20
  // (tr([f]x [f]x^T) = 2 |f|^2; int of W has variance T^3/3, its double integral T^5/20).
  // The per-sample recursion approximates the integrals by sums: relative error O(h / T),
  // 0.6 % for h = 6 ms and T = 1 s; tolerance 1 %.
  const Record rec = MakeRecord(Static(), 2.0);
  const auto pre = Preintegrate(rec.imu, 0.5, 1.5, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                kArw, kVrw);
  const double T = pre->dt_s();
  const double g = wgs84::NormalGravity(rec.truth[0].lat_rad, rec.truth[0].h_m);
  const ImuPreintegration::Matrix9d& P = pre->covariance();
  const double tr_att = P.topLeftCorner<3, 3>().trace();
  const double tr_vel = P.block(3, 3, 3, 3).trace(), tr_pos = P.bottomRightCorner<3, 3>().trace();
  const double q_g = kArw * kArw, q_a = kVrw * kVrw;
  EXPECT_NEAR(tr_att, 3 * q_g * T, 1e-2 * 3 * q_g * T);
  const double vel = 3 * q_a * T + 2 * g * g * q_g * T * T * T / 3;
  EXPECT_NEAR(tr_vel, vel, 1e-2 * vel);
  const double pos = q_a * T * T * T + 2 * g * g * q_g * std::pow(T, 5) / 20;
  EXPECT_NEAR(tr_pos, pos, 1e-2 * pos);
}

// ---------------------------------------------------------------------------------------
// Input checks.

TEST(ImuPreintegration, RejectsBadInput) {
  const Eigen::Vector3d z = Eigen::Vector3d::Zero();
  EXPECT_THROW(ImuPreintegration(z, z, 0.0, kVrw), std::invalid_argument);
  EXPECT_THROW(ImuPreintegration(z, z, kArw, -1.0), std::invalid_argument);
  EXPECT_THROW(ImuPreintegration(z, z, kArw, std::nan("")), std::invalid_argument);
  ImuErrors bad_scale;
  bad_scale.sa.x() = -1.0;  // 1 + s = 0
  EXPECT_THROW(ImuPreintegration(bad_scale, kArw, kVrw), std::invalid_argument);
  EXPECT_THROW(CreateImuScaleFactor(nullptr), std::invalid_argument);
  EXPECT_THROW(ImuPreintegration(Eigen::Vector3d::Constant(std::nan("")), z, kArw, kVrw),
               std::invalid_argument);
  auto pre = std::make_shared<ImuPreintegration>(z, z, kArw, kVrw);
  EXPECT_THROW(CreateImuFactor(pre), std::invalid_argument);  // no sample
  EXPECT_THROW(CreateImuFactor(nullptr), std::invalid_argument);
  EXPECT_THROW(pre->SqrtInformation(), std::domain_error);
  ImuSample s;
  s.t_s = 1.0;
  s.dt_s = 0.0;
  EXPECT_THROW(pre->Integrate(s), std::invalid_argument);
  s.dt_s = 0.005;
  s.dv_b_mps.x() = std::nan("");
  EXPECT_THROW(pre->Integrate(s), std::invalid_argument);
  s.dv_b_mps.setZero();
  pre->Integrate(s);
  s.t_s = 1.011;  // starts at 1.006: a 6 ms gap
  EXPECT_THROW(pre->Integrate(s), std::invalid_argument);
  s.t_s = 1.003;  // starts at 0.998: overlaps the previous sample by 2 ms
  EXPECT_THROW(pre->Integrate(s), std::invalid_argument);
  s.t_s = 1.005 + 1e-7;  // a sub-microsecond tag mismatch is accepted
  EXPECT_NO_THROW(pre->Integrate(s));
  EXPECT_EQ(pre->num_samples(), 2u);
  EXPECT_NEAR(pre->t_start_s(), 0.995, 1e-12);
  std::unique_ptr<ceres::CostFunction> f(CreateImuFactor(pre));  // one sample is enough
  EXPECT_EQ(f->num_residuals(), 9);
}

// DropSamples: the preintegration keeps its increments, covariance, Jacobians, times and
// count (a factor can still be made from it), and refuses to reintegrate; more samples
// integrate as before, at the same continuity check.
TEST(ImuPreintegration, DropSamplesKeepsTheResultAndRefusesToReintegrate) {
  const Eigen::Vector3d z = Eigen::Vector3d::Zero();
  ImuPreintegration kept(z, z, kArw, kVrw), dropped(z, z, kArw, kVrw);
  ImuSample s;
  s.dt_s = 0.005;
  for (int k = 1; k <= 40; ++k) {
    s.t_s = 0.005 * k;
    s.dtheta_b_rad = Eigen::Vector3d(1e-4, -2e-4 * k, 3e-5);
    s.dv_b_mps = Eigen::Vector3d(0.01, 0.002 * k, -0.049);
    kept.Integrate(s);
    dropped.Integrate(s);
    if (k == 20) dropped.DropSamples();
  }
  EXPECT_TRUE(dropped.samples().empty());
  EXPECT_EQ(dropped.num_samples(), 40u);
  EXPECT_EQ(dropped.t_start_s(), kept.t_start_s());
  EXPECT_EQ(dropped.t_end_s(), kept.t_end_s());
  EXPECT_EQ(dropped.delta_v_mps(), kept.delta_v_mps());
  EXPECT_EQ(dropped.delta_p_m(), kept.delta_p_m());
  EXPECT_EQ(dropped.covariance(), kept.covariance());
  EXPECT_EQ(dropped.J_v_bg(), kept.J_v_bg());
  EXPECT_EQ(dropped.SqrtInformation(), kept.SqrtInformation());
  EXPECT_THROW(dropped.Reintegrate(Eigen::Vector3d::Constant(1e-5), z), std::logic_error);
  s.t_s += 0.02;  // a gap is still refused
  EXPECT_THROW(dropped.Integrate(s), std::invalid_argument);
  auto shared = std::make_shared<ImuPreintegration>(dropped);
  std::unique_ptr<ceres::CostFunction> f(CreateImuFactor(shared));
  EXPECT_EQ(f->num_residuals(), 9);
}

}  // namespace factors_imu_preintegration_test
}  // namespace navtwin
