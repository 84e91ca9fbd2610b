// BaroHeight, ZeroVelocity, BiasGaussMarkov / BiasRandomWalk, PositionPrior and
// VectorPrior3: meaning, tangent-space Jacobians (through Linearize) against central
// differences at zero, a tiny perturbation and a random state, and the constructors' checks.
#include "factors/baro_height.h"
#include "factors/bias_process.h"
#include "factors/state_prior.h"
#include "factors/zero_velocity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/units.h"
#include "factors/position_manifold.h"
#include "solvers/linearize.h"
#include "tests/factors/tangent_jacobian_check.h"

namespace navtwin {
namespace factors_misc_models_test {

using namespace tangent_check;  // Block, States, ExpectTangentJacobiansMatch, Std

const PositionManifold kPositionManifold;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// All these residuals are linear in the tangent (position: linear in (lat, lon, h) and the
// chart is linear in dp_ned), so central differences have no truncation error; steps
// 1 m / 1e-3 keep rounding (~eps |x| / h relative) below 1e-9, hence 1e-7.
constexpr double kPosStep = 1.0, kVecStep = 1e-3;
constexpr double kJacobianTol = 1e-7;

Eigen::Vector3d Offset(const Eigen::Vector3d& p, const Eigen::Vector3d& d_ned_m) {
  const wgs84::Geodetic g = wgs84::NedToGeodetic(d_ned_m, {p[0], p[1], p[2]});
  return Eigen::Vector3d(g.lat_rad, g.lon_rad, g.h_m);
}

TEST(BaroHeight, ResidualAndTangentJacobian) {
  const std::unique_ptr<ceres::CostFunction> f(BaroHeight::Create(100.0, 2.0));
  const Eigen::Vector3d pos(0.7, -1.2, 103.0);
  // 3 m above the baro height: +1.5 sigma (exact in binary).
  EXPECT_EQ(Residual(*f, {{Std(pos), nullptr, 0.0}})[0], 1.5);
  for (const State& s : States()) {
    SCOPED_TRACE(s.name);
    const std::unique_ptr<ceres::CostFunction> g(BaroHeight::Create(s.pos.z() - 1.0, 2.0));
    const std::vector<Block> blocks = {{Std(s.pos), &kPositionManifold, kPosStep}};
    ExpectTangentJacobiansMatch(*g, blocks, kJacobianTol);
    // h = h_est - d_d: d r / d dp = (0, 0, -1/sigma), exactly.
    const Linearization lin = LinearizeAt(*g, blocks);
    EXPECT_EQ(lin.jacobians[0], Eigen::RowVector3d(0.0, 0.0, -0.5));
  }
}

TEST(BaroHeight, RejectsBadSigma) {
  for (const double bad : {0.0, -1.0, kNaN, kInf}) EXPECT_THROW(BaroHeight(10.0, bad), std::invalid_argument) << bad;
  EXPECT_THROW(BaroHeight(kNaN, 1.0), std::invalid_argument);
}

TEST(ZeroVelocity, ResidualAndTangentJacobian) {
  const std::unique_ptr<ceres::CostFunction> f(ZeroVelocity::Create(0.01));
  for (const State& s : States()) {
    SCOPED_TRACE(s.name);
    const std::vector<Block> blocks = {{Std(s.v_n_mps), nullptr, kVecStep}};
    EXPECT_LT((Residual(*f, blocks) - s.v_n_mps / 0.01).norm(), 1e-12 * (1.0 + s.v_n_mps.norm() / 0.01));
    ExpectTangentJacobiansMatch(*f, blocks, kJacobianTol);
    EXPECT_LT((LinearizeAt(*f, blocks).jacobians[0] - Eigen::Matrix3d::Identity() / 0.01).norm(), 1e-12);
  }
}

TEST(ZeroVelocity, RejectsBadSigma) {
  for (const double bad : {0.0, -1.0, kNaN, kInf}) EXPECT_THROW(ZeroVelocity{bad}, std::invalid_argument) << bad;
}

TEST(BiasGaussMarkov, ExactDiscretisation) {
  // dt = 1 s, tau = 100 s, s = 0.01: phi = exp(-0.01), sigma_d = s sqrt(1 - exp(-0.02)).
  const double dt = 1.0, tau = 100.0, s = 0.01;
  const BiasGaussMarkov gm(dt, tau, s);
  EXPECT_NEAR(gm.phi(), std::exp(-0.01), 1e-16);
  EXPECT_NEAR(1.0 / gm.inv_sigma(), s * std::sqrt(1.0 - std::exp(-0.02)), 1e-17);
  const std::unique_ptr<ceres::CostFunction> f(BiasGaussMarkov::Create(dt, tau, s));
  const Eigen::Vector3d b_i(0.02, -0.01, 0.005);
  // The mean propagation b_j = phi b_i gives zero; an extra 1 sigma_d on x gives (1, 0, 0).
  const Eigen::Vector3d b_j = gm.phi() * b_i + Eigen::Vector3d(1.0 / gm.inv_sigma(), 0.0, 0.0);
  const Eigen::Vector3d r = Residual(*f, {{Std(b_i), nullptr, 0.0}, {Std(b_j), nullptr, 0.0}});
  EXPECT_LT((r - Eigen::Vector3d(1.0, 0.0, 0.0)).norm(), 1e-12);  // rounding of O(1) terms
  // Steady state is preserved: phi^2 s^2 + sigma_d^2 = s^2.
  EXPECT_NEAR(gm.phi() * gm.phi() * s * s + 1.0 / (gm.inv_sigma() * gm.inv_sigma()), s * s, 1e-18);
}

TEST(BiasGaussMarkov, LongCorrelationTimeIsTheRandomWalkLimit) {
  // tau -> inf with the white-noise PSD q = 2 s^2 / tau held fixed is a random walk of PSD q.
  // The relative differences are O(dt / tau) = 1e-8 (phi = 1 - dt/tau, and the variance
  // s^2 (1 - e^{-2dt/tau}) = q dt (1 - dt/tau + ...)).
  const double dt = 0.5, q = 4e-10, tau = 5e7;
  const double s = std::sqrt(q * tau / 2.0);
  const std::unique_ptr<ceres::CostFunction> gm(BiasGaussMarkov::Create(dt, tau, s));
  const std::unique_ptr<ceres::CostFunction> rw(BiasRandomWalk::Create(dt, q));
  const Eigen::Vector3d b_i(1e-4, -2e-4, 5e-5), b_j(1.1e-4, -2.2e-4, 4e-5);
  const std::vector<Block> blocks = {{Std(b_i), nullptr, kVecStep}, {Std(b_j), nullptr, kVecStep}};
  const Eigen::Vector3d r_gm = Residual(*gm, blocks), r_rw = Residual(*rw, blocks);
  EXPECT_LT((r_gm - r_rw).norm(), 1e-6 * r_rw.norm()) << r_gm.transpose() << " vs " << r_rw.transpose();
  const Linearization l_gm = LinearizeAt(*gm, blocks), l_rw = LinearizeAt(*rw, blocks);
  for (int k = 0; k < 2; ++k) {
    EXPECT_LT((l_gm.jacobians[k] - l_rw.jacobians[k]).norm(), 1e-6 * l_rw.jacobians[k].norm());
  }
  // Random walk: r = (b_j - b_i) / sqrt(q dt).
  EXPECT_LT((r_rw - (b_j - b_i) / std::sqrt(q * dt)).norm(), 1e-12 * r_rw.norm());
  // tau = inf itself is refused with a pointer to BiasRandomWalk.
  EXPECT_THROW(BiasGaussMarkov(dt, kInf, s), std::invalid_argument);
}

TEST(BiasProcess, TangentJacobiansMatchCentralDifferences) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random3 = [&]() -> Eigen::Vector3d { return Eigen::Vector3d(u(rng), u(rng), u(rng)); };
  const std::unique_ptr<ceres::CostFunction> gm(BiasGaussMarkov::Create(0.01, 3600.0, 1e-4));
  const std::unique_ptr<ceres::CostFunction> rw(BiasRandomWalk::Create(0.01, 1e-8));
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> points = {
      {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()},
      {Eigen::Vector3d::Constant(1e-9), Eigen::Vector3d::Constant(-1e-9)},
      {1e-4 * random3(), 1e-4 * random3()}};
  for (const auto& [b_i, b_j] : points) {
    // Step 1e-6 on biases of ~1e-4 (the residuals are linear; rounding ~eps |b| / h).
    const std::vector<Block> blocks = {{Std(b_i), nullptr, 1e-6}, {Std(b_j), nullptr, 1e-6}};
    ExpectTangentJacobiansMatch(*gm, blocks, kJacobianTol);
    ExpectTangentJacobiansMatch(*rw, blocks, kJacobianTol);
  }
}

TEST(BiasProcess, RejectsBadParameters) {
  for (const double bad : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_THROW(BiasGaussMarkov(bad, 100.0, 0.1), std::invalid_argument) << bad;
    EXPECT_THROW(BiasGaussMarkov(1.0, bad, 0.1), std::invalid_argument) << bad;
    EXPECT_THROW(BiasGaussMarkov(1.0, 100.0, bad), std::invalid_argument) << bad;
    EXPECT_THROW(BiasRandomWalk(bad, 1e-6), std::invalid_argument) << bad;
    EXPECT_THROW(BiasRandomWalk(1.0, bad), std::invalid_argument) << bad;
  }
}

TEST(PositionPrior, ResidualIsTheWhitenedNedOffset) {
  const Eigen::Vector3d p0(52.0 * kDegToRad, 4.4 * kDegToRad, 12.0), sigma(2.0, 4.0, 8.0);
  const std::unique_ptr<ceres::CostFunction> f(PositionPrior::Create(p0, sigma));
  EXPECT_EQ(Residual(*f, {{Std(p0), nullptr, 0.0}}).norm(), 0.0);
  // 1 m east of p0 (exact, through ECEF): (0, 1/4, 0) up to the chart's ~|d|^2/R ~ 2e-7 m.
  const Eigen::Vector3d r = Residual(*f, {{Std(Offset(p0, Eigen::Vector3d(0.0, 1.0, 0.0))), nullptr, 0.0}});
  EXPECT_LT((r - Eigen::Vector3d(0.0, 0.25, 0.0)).norm(), 1e-6);
  for (const State& s : States()) {
    SCOPED_TRACE(s.name);
    const std::unique_ptr<ceres::CostFunction> g(PositionPrior::Create(Offset(s.pos, Eigen::Vector3d(3.0, -4.0, 1.0)), 5.0));
    const std::vector<Block> blocks = {{Std(s.pos), &kPositionManifold, kPosStep}};
    ExpectTangentJacobiansMatch(*g, blocks, kJacobianTol);
    // Radii at p0 vs pos (5 m apart): the tangent Jacobian is I / sigma to ~1e-6.
    EXPECT_LT((LinearizeAt(*g, blocks).jacobians[0] - Eigen::Matrix3d::Identity() / 5.0).norm(), 1e-6);
  }
}

TEST(VectorPrior3, ResidualAndTangentJacobian) {
  const Eigen::Vector3d x0(1.0, -2.0, 3.0), sigma(0.5, 0.25, 2.0);
  const std::unique_ptr<ceres::CostFunction> f(VectorPrior3::Create(x0, sigma));
  const Eigen::Vector3d x(2.0, -2.0, 2.0);
  EXPECT_EQ(Residual(*f, {{Std(x), nullptr, 0.0}}), Eigen::VectorXd(Eigen::Vector3d(2.0, 0.0, -0.5)));
  for (const State& s : States()) {
    SCOPED_TRACE(s.name);
    const std::vector<Block> blocks = {{Std(s.v_n_mps), nullptr, kVecStep}};
    ExpectTangentJacobiansMatch(*f, blocks, kJacobianTol);
    EXPECT_LT((LinearizeAt(*f, blocks).jacobians[0] - Eigen::Matrix3d(sigma.cwiseInverse().asDiagonal())).norm(), 1e-12);
  }
}

// (x - x0) / sigma on six entries; its Jacobian is I / sigma (Linearize against the value).
TEST(IsotropicPrior, ResidualAndJacobian) {
  Eigen::Matrix<double, 6, 1> x0, x;
  x0 << 1, -2, 3, 0, 0.5, -1;
  x << 2, -2, 2, 1, 0.5, -3;
  const std::unique_ptr<ceres::CostFunction> f(IsotropicPrior<6>::Create(x0, 0.5));
  const std::vector<Block> blocks = {{std::vector<double>(x.data(), x.data() + 6), nullptr, kVecStep}};
  Eigen::Matrix<double, 6, 1> expected;
  expected << 2, 0, -2, 2, 0, -4;
  EXPECT_EQ(Residual(*f, blocks), Eigen::VectorXd(expected));
  ExpectTangentJacobiansMatch(*f, blocks, kJacobianTol);
  EXPECT_LT((LinearizeAt(*f, blocks).jacobians[0] - 2.0 * Eigen::MatrixXd::Identity(6, 6)).norm(), 1e-12);
  for (const double bad : {0.0, -1.0, kNaN, kInf}) EXPECT_THROW(IsotropicPrior<6>(x0, bad), std::invalid_argument);
  x0(2) = kNaN;
  EXPECT_THROW(IsotropicPrior<6>(x0, 1.0), std::invalid_argument);
}

TEST(StatePrior, RejectsBadSigma) {
  const Eigen::Vector3d p0(0.5, 0.5, 0.0);
  for (const double bad : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_THROW(PositionPrior(p0, bad), std::invalid_argument) << bad;
    EXPECT_THROW(PositionPrior(p0, Eigen::Vector3d(1.0, 1.0, bad)), std::invalid_argument) << bad;
    EXPECT_THROW(VectorPrior3(p0, bad), std::invalid_argument) << bad;
    EXPECT_THROW(VectorPrior3(p0, Eigen::Vector3d(bad, 1.0, 1.0)), std::invalid_argument) << bad;
  }
  EXPECT_THROW(PositionPrior(Eigen::Vector3d(kNaN, 0, 0), 1.0), std::invalid_argument);
}

}  // namespace factors_misc_models_test
}  // namespace navtwin
