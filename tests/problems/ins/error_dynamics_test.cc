#include "problems/ins/error_dynamics.h"

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/strapdown.h"
#include "factors/position_manifold.h"
#include "solvers/eskf.h"

namespace navtwin::ins {
namespace ins_error_dynamics_test {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Two flight conditions with every rate, angle and IMU error estimate non-zero, so that no
// sign can hide behind a zero: a turning, climbing, accelerating aircraft at 45.8 deg N
// heading south-west, and one descending eastward at 33 deg S.
struct Scenario {
  InsState x0;
  Eigen::Vector3d omega_radps;  // raw angular rate (before the scale/bias modulation)
  Eigen::Vector3d f_mps2;       // raw specific force
};

Scenario NorthernTurn() {
  Scenario s;
  s.x0.nav.lat_rad = 0.8;
  s.x0.nav.lon_rad = 0.2;
  s.x0.nav.h_m = 1500.0;
  s.x0.nav.v_n_mps = Eigen::Vector3d(150.0, -80.0, -6.0);
  s.x0.nav.q_n_b = QuatFromEuler(0.35, 0.08, -2.3);
  s.x0.imu.bg_radps = Eigen::Vector3d(2e-4, -1e-4, 3e-4);
  s.x0.imu.ba_mps2 = Eigen::Vector3d(0.03, -0.02, 0.05);
  s.x0.imu.sg = Eigen::Vector3d(3e-3, -2e-3, 1e-3);
  s.x0.imu.sa = Eigen::Vector3d(-1e-3, 2e-3, 4e-3);
  s.omega_radps = Eigen::Vector3d(0.05, -0.03, 0.2);
  s.f_mps2 = Eigen::Vector3d(1.5, 2.0, -10.5);
  return s;
}

Scenario SouthernDescent() {
  Scenario s;
  s.x0.nav.lat_rad = -0.58;
  s.x0.nav.lon_rad = -1.1;
  s.x0.nav.h_m = 300.0;
  s.x0.nav.v_n_mps = Eigen::Vector3d(-20.0, 60.0, 4.0);
  s.x0.nav.q_n_b = QuatFromEuler(-0.2, -0.15, 1.4);
  s.x0.imu.bg_radps = Eigen::Vector3d(-3e-4, 2e-4, -1e-4);
  s.x0.imu.ba_mps2 = Eigen::Vector3d(-0.04, 0.01, -0.03);
  s.x0.imu.sg = Eigen::Vector3d(-2e-3, 1e-3, 3e-3);
  s.x0.imu.sa = Eigen::Vector3d(2e-3, -3e-3, -1e-3);
  s.omega_radps = Eigen::Vector3d(-0.08, 0.04, -0.12);
  s.f_mps2 = Eigen::Vector3d(-0.8, -1.2, -9.2);
  return s;
}

// Raw samples at rate_hz over duration_s; the rates are modulated (+-20 %) so that they
// are not constant.
std::vector<ImuSample> RawSamples(const Scenario& sc, double rate_hz, double duration_s) {
  const double dt = 1.0 / rate_hz;
  const int n = static_cast<int>(std::lround(duration_s * rate_hz));
  std::vector<ImuSample> out;
  for (int k = 1; k <= n; ++k) {
    ImuSample s;
    s.t_s = k * dt;
    s.dt_s = dt;
    const double m = 1.0 + 0.2 * std::sin(3.0 * k * dt);
    s.dtheta_b_rad = sc.omega_radps * m * dt;
    s.dv_b_mps = sc.f_mps2 * m * dt;
    out.push_back(s);
  }
  return out;
}

// The mechanization under test: Strapdown on the samples corrected with the state's own
// IMU error estimates (held constant: tau = inf). Optionally records every state.
InsState Propagate(const InsState& x0, const std::vector<ImuSample>& raw,
                   std::vector<InsState>* history = nullptr) {
  Strapdown ins(x0.nav);
  if (history) history->assign(1, x0);
  for (const ImuSample& s : raw) {
    ins.Update(CorrectImu(s, x0.imu));
    if (history) history->push_back({ins.state(), x0.imu});
  }
  return {ins.state(), x0.imu};
}

// Phi of the linearised model along the nominal trajectory: product of per-sample
// transitions, each exp(F_bar dt) to third order with F_bar the mean of F at the two ends
// of the sample (a second-order accurate product integral). `modify` may alter F (used to
// show that the comparison detects a missing term).
Eigen::MatrixXd ModelPhi(const std::vector<InsState>& hist, const std::vector<ImuSample>& raw,
                         int n, const std::function<void(Eigen::MatrixXd*)>& modify = nullptr) {
  ImuNoise noise;
  noise.correlation_time_s = kInf;
  Eigen::MatrixXd Phi = Eigen::MatrixXd::Identity(n, n);
  for (size_t k = 0; k < raw.size(); ++k) {
    const ImuSample c = CorrectImu(raw[k], hist[k].imu);
    const Eigen::Vector3d w = c.dtheta_b_rad / c.dt_s, f = c.dv_b_mps / c.dt_s;
    Eigen::MatrixXd F = 0.5 * (ErrorDynamicsF(hist[k], f, w, noise, n) +
                               ErrorDynamicsF(hist[k + 1], f, w, noise, n));
    if (modify) modify(&F);
    const Eigen::MatrixXd Fdt = F * c.dt_s;
    Eigen::MatrixXd step = Fdt + 0.5 * Fdt * Fdt + Fdt * Fdt * Fdt / 6.0;
    step.diagonal().array() += 1.0;
    Phi = step * Phi;
  }
  return Phi;
}

// Central differences of the mechanization: column i is
// (D(+eps e_i) - D(-eps e_i)) / (2 eps), D(d) = StateDifference(Propagate(x0 (+) d), Propagate(x0)).
// Steps per block (pos m, vel m/s, att rad, bg rad/s, ba m/s^2, sg, sa): large enough that
// the rounding of lat/lon (~1e-9 m per step) stays below 1e-5 of each column, small
// enough that the third-order terms (relative ~ (attitude change)^2 <= 1e-6) are negligible.
Eigen::MatrixXd NumericPhi(const InsState& x0, const std::vector<ImuSample>& raw, int n) {
  const double eps[7] = {10.0, 0.1, 1e-3, 1e-3, 1e-2, 1e-3, 1e-3};
  const InsState x1 = Propagate(x0, raw);
  Eigen::MatrixXd Num(n, n);
  for (int i = 0; i < n; ++i) {
    Eigen::VectorXd d = Eigen::VectorXd::Zero(n);
    d(i) = eps[i / 3];
    const InsState p = Propagate(ApplyCorrection(x0, d), raw);
    const InsState m = Propagate(ApplyCorrection(x0, -d), raw);
    Num.col(i) = (StateDifference(p, x1, n) - StateDifference(m, x1, n)) / (2.0 * eps[i / 3]);
  }
  return Num;
}

// Largest relative error over the 3x3 blocks: |Num - Phi|_max / |Phi - I|_max of each block,
// relative to Phi - I so that the small Earth-rate, transport-rate and gravity-gradient
// couplings (blocks of 1e-11 .. 1e-4) are each checked at their own scale. Blocks where
// Phi - I vanishes must match to 1e-12 absolute (else the result is infinite).
double MaxBlockError(const Eigen::MatrixXd& Phi, const Eigen::MatrixXd& Num) {
  const int nb = static_cast<int>(Phi.rows()) / 3;
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(Phi.rows(), Phi.cols());
  double worst = 0.0;
  for (int bi = 0; bi < nb; ++bi) {
    for (int bj = 0; bj < nb; ++bj) {
      const double scale = (Phi - I).block(3 * bi, 3 * bj, 3, 3).cwiseAbs().maxCoeff();
      const double e = (Num - Phi).block(3 * bi, 3 * bj, 3, 3).cwiseAbs().maxCoeff();
      if (scale > 0.0) {
        worst = std::max(worst, e / scale);
      } else if (e > 1e-12) {
        return std::numeric_limits<double>::infinity();
      }
    }
  }
  return worst;
}

// 1 s at 100 Hz. Observed worst block errors ~5e-5 (the O(dt^2) error of the product
// integral, which falls 10x at 400 Hz, and rounding); tolerance 1e-3. Every term of F is
// at least 10% of its block (the mutation test below shows dropping one fails by > 0.1).
constexpr double kRate_hz = 100.0;
constexpr double kDuration_s = 1.0;
constexpr double kPhiTolerance = 1e-3;

class ErrorDynamicsVsMechanization : public ::testing::TestWithParam<int> {
 protected:
  Scenario scenario() const { return GetParam() == 0 ? NorthernTurn() : SouthernDescent(); }
};

TEST_P(ErrorDynamicsVsMechanization, PhiMatchesCentralDifferences21) {
  const Scenario sc = scenario();
  const auto raw = RawSamples(sc, kRate_hz, kDuration_s);
  std::vector<InsState> hist;
  Propagate(sc.x0, raw, &hist);
  const Eigen::MatrixXd Phi = ModelPhi(hist, raw, 21);
  const Eigen::MatrixXd Num = NumericPhi(sc.x0, raw, 21);
  const double err = MaxBlockError(Phi, Num);
  EXPECT_LT(err, kPhiTolerance);
  RecordProperty("max_block_error", std::to_string(err));
}

TEST_P(ErrorDynamicsVsMechanization, PhiMatchesCentralDifferences15) {
  Scenario sc = scenario();
  // The 15-state filter has no scale-factor estimates: nominal scale factors are zero.
  sc.x0.imu.sg.setZero();
  sc.x0.imu.sa.setZero();
  const auto raw = RawSamples(sc, kRate_hz, kDuration_s);
  std::vector<InsState> hist;
  Propagate(sc.x0, raw, &hist);
  const double err = MaxBlockError(ModelPhi(hist, raw, 15), NumericPhi(sc.x0, raw, 15));
  EXPECT_LT(err, kPhiTolerance);
  RecordProperty("max_block_error", std::to_string(err));
}

// The comparison is sharp enough to see each of the small coupling terms: removing any one
// of them (or flipping the gravity-gradient sign) makes the block error exceed 0.1.
TEST_P(ErrorDynamicsVsMechanization, DroppingAnyCouplingTermIsDetected) {
  const Scenario sc = scenario();
  const auto raw = RawSamples(sc, kRate_hz, kDuration_s);
  std::vector<InsState> hist;
  Propagate(sc.x0, raw, &hist);
  const Eigen::MatrixXd Num = NumericPhi(sc.x0, raw, 21);
  using namespace err;
  const std::vector<std::pair<const char*, std::function<void(Eigen::MatrixXd*)>>> mutations = {
      {"position-position (radii / transport)", [](Eigen::MatrixXd* F) { F->block<3, 3>(kPos, kPos).setZero(); }},
      {"gravity gradient sign", [](Eigen::MatrixXd* F) { (*F)(kVel + 2, kPos + 2) *= -1.0; }},
      {"velocity-position (Coriolis, gravity)", [](Eigen::MatrixXd* F) { F->block<3, 3>(kVel, kPos).setZero(); }},
      {"Coriolis on velocity", [](Eigen::MatrixXd* F) { F->block<3, 3>(kVel, kVel).setZero(); }},
      {"attitude-position (Earth rate, transport)", [](Eigen::MatrixXd* F) { F->block<3, 3>(kAtt, kPos).setZero(); }},
      {"attitude-velocity (transport rate)", [](Eigen::MatrixXd* F) { F->block<3, 3>(kAtt, kVel).setZero(); }},
      {"nav-frame rate on attitude", [](Eigen::MatrixXd* F) { F->block<3, 3>(kAtt, kAtt).setZero(); }},
  };
  for (const auto& [name, mutate] : mutations) {
    const double err = MaxBlockError(ModelPhi(hist, raw, 21, mutate), Num);
    EXPECT_GT(err, 0.1) << name;
    RecordProperty(name, std::to_string(err));
  }
  // Even the 1/(1 + sg) factor on the bias columns (sg <= 3e-3 here) is resolved: without
  // it the error exceeds twice the tolerance (and is ~50 times the correct model's).
  const Eigen::Vector3d one_plus_sg = Eigen::Vector3d::Ones() + sc.x0.imu.sg;
  const auto no_scale = [&](Eigen::MatrixXd* F) {
    F->block<3, 3>(kAtt, kBg) = F->block<3, 3>(kAtt, kBg) * one_plus_sg.asDiagonal();
  };
  const double err = MaxBlockError(ModelPhi(hist, raw, 21, no_scale), Num);
  EXPECT_GT(err, 2.0 * kPhiTolerance);
  RecordProperty("without 1/(1+sg)", std::to_string(err));
}

INSTANTIATE_TEST_SUITE_P(Scenarios, ErrorDynamicsVsMechanization, ::testing::Values(0, 1));

// What the filter does: DiscreteErrorDynamics at the state at the START of each
// covariance interval (20 ms = 2 samples, the default covariance_interval_s) with the mean
// corrected rates of the interval. First order in the interval: observed block error
// 2.6e-3 over 1 s, checked at 1e-2 (a sign or a missing term gives >= 0.1, see above).
TEST(ErrorDynamics, FilterStyleDiscretePhiTracksMechanization) {
  const Scenario sc = NorthernTurn();
  const auto raw = RawSamples(sc, kRate_hz, kDuration_s);
  std::vector<InsState> hist;
  Propagate(sc.x0, raw, &hist);
  ImuNoise noise;
  noise.correlation_time_s = kInf;
  const int n = 21;
  Eigen::MatrixXd Phi = Eigen::MatrixXd::Identity(n, n);
  for (size_t k = 0; k + 1 < raw.size() + 1; k += 2) {
    Eigen::Vector3d dth = Eigen::Vector3d::Zero(), dv = Eigen::Vector3d::Zero();
    double dt = 0.0;
    for (size_t j = k; j < k + 2 && j < raw.size(); ++j) {
      const ImuSample c = CorrectImu(raw[j], sc.x0.imu);
      dth += c.dtheta_b_rad;
      dv += c.dv_b_mps;
      dt += c.dt_s;
    }
    Eigen::MatrixXd step;
    DiscreteErrorDynamics(hist[k], dv / dt, dth / dt, noise, n, dt, &step, nullptr);
    Phi = step * Phi;
  }
  const double err = MaxBlockError(Phi, NumericPhi(sc.x0, raw, n));
  EXPECT_LT(err, 1e-2);
  RecordProperty("block_error", std::to_string(err));
}

TEST(ErrorDynamics, SizesAndStructure) {
  const Scenario sc = NorthernTurn();
  ImuNoise noise;
  noise.correlation_time_s = 300.0;
  const Eigen::MatrixXd F21 = ErrorDynamicsF(sc.x0, sc.f_mps2, sc.omega_radps, noise, 21);
  Scenario sc15 = sc;
  const Eigen::MatrixXd F15 = ErrorDynamicsF(sc15.x0, sc.f_mps2, sc.omega_radps, noise, 15);
  ASSERT_EQ(F21.rows(), 21);
  ASSERT_EQ(F15.rows(), 15);
  EXPECT_EQ((F21.topLeftCorner(15, 15) - F15).cwiseAbs().maxCoeff(), 0.0);
  using namespace err;
  // Gauss-Markov: -1/tau on the bias and scale-factor diagonals.
  for (int i = kBg; i < 21; ++i) EXPECT_DOUBLE_EQ(F21(i, i), -1.0 / 300.0);
  // White sensor noise enters exactly like a bias error of the same sensor: G's noise
  // columns equal F's bias columns (the bias columns are checked against the mechanization).
  const Eigen::MatrixXd G = ErrorDynamicsG(sc.x0, 21);
  EXPECT_EQ((G.block<3, 3>(kAtt, 0) - F21.block<3, 3>(kAtt, kBg)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((G.block<3, 3>(kVel, 3) - F21.block<3, 3>(kVel, kBa)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((G.block(kBg, 6, 12, 15) - Eigen::MatrixXd::Identity(12, 15)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_THROW(ErrorDynamicsF(sc.x0, sc.f_mps2, sc.omega_radps, noise, 18), std::invalid_argument);
  EXPECT_THROW(ApplyCorrection(sc.x0, Eigen::VectorXd::Zero(9)), std::invalid_argument);
}

TEST(ErrorDynamics, ProcessNoiseDensities) {
  ImuNoise noise;
  noise.gyro_arw_rad_per_sqrt_s = 2e-3;
  noise.accel_vrw_mps_per_sqrt_s = 3e-2;
  noise.gyro_bias_std_radps = 1e-4;
  noise.accel_bias_std_mps2 = 5e-3;
  noise.gyro_scale_std = 1e-3;
  noise.accel_scale_std = 2e-3;
  noise.correlation_time_s = 100.0;
  const Eigen::VectorXd q = ErrorDynamicsQc(noise, 21);
  const double expected[6] = {4e-6, 9e-4, 2 * 1e-8 / 100, 2 * 25e-6 / 100, 2 * 1e-6 / 100, 2 * 4e-6 / 100};
  for (int i = 0; i < 18; ++i) EXPECT_DOUBLE_EQ(q(i), expected[i / 3]) << i;
  noise.correlation_time_s = kInf;  // random constants: no driving noise
  const Eigen::VectorXd q_inf = ErrorDynamicsQc(noise, 15);
  EXPECT_DOUBLE_EQ(q_inf(0), 4e-6);
  EXPECT_EQ(q_inf.tail(6).cwiseAbs().maxCoeff(), 0.0);
}

// Phi = I + F dt + (F dt)^2 / 2 and Qd = (Phi G Qc G^T Phi^T + G Qc G^T) dt / 2, as
// documented; and the discrete Gauss-Markov bias reaches its steady-state variance.
TEST(ErrorDynamics, DiscreteFormulasAndGaussMarkovSteadyState) {
  const Scenario sc = NorthernTurn();
  ImuNoise noise;
  noise.gyro_arw_rad_per_sqrt_s = 2e-3;
  noise.accel_vrw_mps_per_sqrt_s = 3e-2;
  noise.gyro_bias_std_radps = 1e-4;
  noise.accel_bias_std_mps2 = 5e-3;
  noise.gyro_scale_std = 1e-3;
  noise.accel_scale_std = 2e-3;
  noise.correlation_time_s = 100.0;
  const double dt = 0.02;
  Eigen::MatrixXd Phi, Qd;
  DiscreteErrorDynamics(sc.x0, sc.f_mps2, sc.omega_radps, noise, 21, dt, &Phi, &Qd);
  const Eigen::MatrixXd Fdt = ErrorDynamicsF(sc.x0, sc.f_mps2, sc.omega_radps, noise, 21) * dt;
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(21, 21);
  EXPECT_LT((Phi - (I + Fdt + 0.5 * Fdt * Fdt)).cwiseAbs().maxCoeff(), 1e-15);
  const Eigen::MatrixXd G = ErrorDynamicsG(sc.x0, 21);
  const Eigen::MatrixXd GQG = G * ErrorDynamicsQc(noise, 21).asDiagonal() * G.transpose();
  const Eigen::MatrixXd Qd_ref = 0.5 * dt * (Phi * GQG * Phi.transpose() + GQG);
  EXPECT_LT((Qd - Qd_ref).cwiseAbs().maxCoeff(), 1e-18);  // entries <= 1e-6: rounding only
  EXPECT_EQ((Qd - Qd.transpose()).cwiseAbs().maxCoeff(), 0.0);
  // Attitude random walk: 3 ARW^2 dt / (1 + sg)^2 summed over the axes, to O(dt^2).
  const Eigen::Vector3d Dg = (Eigen::Vector3d::Ones() + sc.x0.imu.sg).cwiseInverse();
  const double att_trace = Qd.block<3, 3>(err::kAtt, err::kAtt).trace();
  EXPECT_NEAR(att_trace, 4e-6 * dt * Dg.squaredNorm(), 1e-12);
  // Steady state of the gyro bias: iterate P = Phi P Phi + Qd (scalar, one axis). With
  // a = dt / tau = 2e-4 the discrete steady state differs from sigma^2 by O(a^2).
  const double phi = Phi(err::kBg, err::kBg), qd = Qd(err::kBg, err::kBg);
  double P = 0.0;
  for (int k = 0; k < 200000; ++k) P = phi * P * phi + qd;  // 40 tau
  EXPECT_NEAR(P, 1e-8, 1e-8 * 1e-6);
}

TEST(ErrorDynamics, CorrectionAndDifferenceAreInverse) {
  const Scenario sc = NorthernTurn();
  Eigen::VectorXd dx(21);
  dx << 12.0, -7.0, 3.0, 0.4, -0.2, 0.1, 0.02, -0.01, 0.03, 1e-4, -2e-4, 3e-4, 0.01, 0.02,
      -0.03, 1e-3, -2e-3, 3e-3, -1e-3, 2e-3, 1e-3;
  const InsState y = ApplyCorrection(sc.x0, dx);
  // Position round trip through lat/lon: one ulp of 0.8 rad is 1.1e-16 rad = 7e-10 m;
  // everything else is exact to rounding of O(1) numbers.
  const Eigen::VectorXd back21 = StateDifference(y, sc.x0, 21) - dx;
  EXPECT_LT(back21.head(3).cwiseAbs().maxCoeff(), 2e-9);
  EXPECT_LT(back21.tail(18).cwiseAbs().maxCoeff(), 1e-12);
  // Position part = the position manifold's Plus (factors/position_manifold.h).
  const double p[3] = {sc.x0.nav.lat_rad, sc.x0.nav.lon_rad, sc.x0.nav.h_m};
  double p_plus[3];
  ASSERT_TRUE(PositionManifold().Plus(p, dx.data(), p_plus));
  EXPECT_EQ(y.nav.lat_rad, p_plus[0]);
  EXPECT_EQ(y.nav.lon_rad, p_plus[1]);
  EXPECT_EQ(y.nav.h_m, p_plus[2]);
  // Attitude: R_true = Exp(phi) R_est.
  const Eigen::Matrix3d R_expected =
      ExpSO3<double>(dx.segment<3>(err::kAtt)) * DcmFromQuat(sc.x0.nav.q_n_b);
  EXPECT_LT((DcmFromQuat(y.nav.q_n_b) - R_expected).cwiseAbs().maxCoeff(), 1e-15);
  // 15 states leave the scale factors alone.
  const InsState y15 = ApplyCorrection(sc.x0, dx.head(15));
  EXPECT_EQ(y15.imu.sg, sc.x0.imu.sg);
  EXPECT_EQ(y15.imu.sa, sc.x0.imu.sa);
  const Eigen::VectorXd back15 = StateDifference(y15, sc.x0, 15) - dx.head(15);
  EXPECT_LT(back15.head(3).cwiseAbs().maxCoeff(), 2e-9);
  EXPECT_LT(back15.tail(12).cwiseAbs().maxCoeff(), 1e-12);
  // And the other way round: Apply(x, Diff(y, x)) = y.
  const InsState back = ApplyCorrection(sc.x0, StateDifference(y, sc.x0, 21));
  EXPECT_NEAR(back.nav.lat_rad, y.nav.lat_rad, 1e-15);
  EXPECT_NEAR(back.nav.lon_rad, y.nav.lon_rad, 1e-15);
  EXPECT_NEAR(back.nav.h_m, y.nav.h_m, 1e-9);
  EXPECT_LT(AttitudeError(back.nav.q_n_b, y.nav.q_n_b).norm(), 1e-15);
}

// --------------------------------------------------------------- covariance propagation

/// Random symmetric positive definite n x n matrix with entries of order `scale`.
Eigen::MatrixXd RandomSpd(int n, std::mt19937* rng) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd L(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) L(i, j) = normal(*rng);
  return L * L.transpose() / n + Eigen::MatrixXd::Identity(n, n);
}

/// A climbing, turning state with every IMU error non-zero, and its noise model, for the
/// covariance-propagation checks.
InsState ClimbingTurnState() {
  InsState x;
  x.nav.lat_rad = 0.7;
  x.nav.h_m = 1200.0;
  x.nav.v_n_mps = Eigen::Vector3d(40.0, -25.0, 3.0);
  x.nav.q_n_b = QuatFromEuler(0.2, -0.1, 2.5);
  x.imu.bg_radps = Eigen::Vector3d(1e-4, -2e-4, 3e-4);
  x.imu.ba_mps2 = Eigen::Vector3d(0.05, -0.02, 0.03);
  x.imu.sg = Eigen::Vector3d(1e-3, -2e-3, 5e-4);
  x.imu.sa = Eigen::Vector3d(-1e-3, 3e-3, 2e-3);
  return x;
}

ImuNoise PropagationNoise() {
  ImuNoise noise;
  noise.gyro_arw_rad_per_sqrt_s = 1e-3;
  noise.accel_vrw_mps_per_sqrt_s = 2e-2;
  noise.gyro_bias_std_radps = 1e-3;
  noise.accel_bias_std_mps2 = 0.2;
  noise.gyro_scale_std = 1e-3;
  noise.accel_scale_std = 2e-3;
  noise.correlation_time_s = 300.0;
  return noise;
}

TEST(PropagateCovariance, BlockFormEqualsDenseForm) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (const int n : {err::kSize15, err::kSize21}) {
    SCOPED_TRACE(n);
    const InsState x = ClimbingTurnState();
    const ImuNoise noise = PropagationNoise();
    const Eigen::Vector3d f(1.5, -2.0, -9.6), w(0.1, -0.05, 0.2);
    const double dt = 0.02;
    // Scale the random covariance to realistic magnitudes per block (m, m/s, rad, ...).
    Eigen::VectorXd s(n);
    s << 3, 3, 3, 0.1, 0.1, 0.1, 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4, 0.01, 0.01, 0.01;
    if (n == err::kSize21) s.tail<6>().setConstant(1e-3);
    const Eigen::MatrixXd P0 = s.asDiagonal() * RandomSpd(n, &rng) * s.asDiagonal();
    Eigen::MatrixXd X0 = Eigen::MatrixXd::Identity(n, n);
    X0.topRows(9) += 0.1 * Eigen::MatrixXd::NullaryExpr(9, n, [&]() { return normal(rng); });

    Eigen::MatrixXd Phi, Qd;
    DiscreteErrorDynamics(x, f, w, noise, n, dt, &Phi, &Qd);
    ErrorStateKalmanFilter kf(P0);
    kf.Predict(Phi, Qd);
    const Eigen::MatrixXd X_ref = Phi * X0;

    Eigen::MatrixXd P = P0, X = X0;
    PropagateCovariance(x, f, w, noise, dt, &P, &X);
    // Same formulas, different summation order: agreement to rounding (1e-13 of the
    // largest entry; P's entries span 1e-8 .. 10).
    EXPECT_LT((P - kf.P()).cwiseAbs().maxCoeff(), 1e-13 * kf.P().cwiseAbs().maxCoeff());
    EXPECT_LT((X - X_ref).cwiseAbs().maxCoeff(), 1e-13 * X_ref.cwiseAbs().maxCoeff());
  }
}


// Auxiliary states of aiding sources (random constants appended to the error state): the
// block form equals the dense one with Phi_aug = blockdiag(Phi, I), Qd_aug = blockdiag(Qd,
// q dt), including their correlations with the INS states and the RTS transition product.
TEST(PropagateCovariance, AuxiliaryStatesFollowTheAugmentedDenseForm) {
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  const int n = err::kSize15, n_aux = 2, total = n + n_aux;
  const InsState x = ClimbingTurnState();
  const ImuNoise noise = PropagationNoise();
  const Eigen::Vector3d f(1.5, -2.0, -9.6), w(0.1, -0.05, 0.2);
  const double dt = 0.02;
  const Eigen::VectorXd aux_psd = Eigen::Vector2d(1e-6, 0.0);
  Eigen::VectorXd s(total);
  s << 3, 3, 3, 0.1, 0.1, 0.1, 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4, 0.01, 0.01, 0.01, 0.01, 0.05;
  const Eigen::MatrixXd P0 = s.asDiagonal() * RandomSpd(total, &rng) * s.asDiagonal();
  Eigen::MatrixXd X0 = Eigen::MatrixXd::Identity(total, total);
  X0.block(0, 0, 9, n) += 0.1 * Eigen::MatrixXd::NullaryExpr(9, n, [&]() { return normal(rng); });

  Eigen::MatrixXd Phi, Qd;
  DiscreteErrorDynamics(x, f, w, noise, n, dt, &Phi, &Qd);
  Eigen::MatrixXd Phi_aug = Eigen::MatrixXd::Identity(total, total), Qd_aug = Eigen::MatrixXd::Zero(total, total);
  Phi_aug.topLeftCorner(n, n) = Phi;
  Qd_aug.topLeftCorner(n, n) = Qd;
  Qd_aug.bottomRightCorner(n_aux, n_aux).diagonal() = aux_psd * dt;
  const Eigen::MatrixXd P_ref = Phi_aug * P0 * Phi_aug.transpose() + Qd_aug;
  const Eigen::MatrixXd X_ref = Phi_aug * X0;

  Eigen::MatrixXd P = P0, X = X0;
  PropagateCovariance(x, f, w, noise, dt, &P, &X, aux_psd);
  EXPECT_LT((P - P_ref).cwiseAbs().maxCoeff(), 1e-13 * P_ref.cwiseAbs().maxCoeff());
  EXPECT_LT((X - X_ref).cwiseAbs().maxCoeff(), 1e-13 * X_ref.cwiseAbs().maxCoeff());
  // A size that fits neither 15 nor 21 INS states plus the auxiliary ones is refused.
  Eigen::MatrixXd wrong = Eigen::MatrixXd::Identity(total + 1, total + 1);
  EXPECT_THROW(PropagateCovariance(x, f, w, noise, dt, &wrong, nullptr, aux_psd), std::invalid_argument);
}

}  // namespace ins_error_dynamics_test
}  // namespace navtwin::ins
