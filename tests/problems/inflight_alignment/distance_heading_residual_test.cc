// DistanceHeadingResidual, DistanceHeadingTiltWalkResidual and VectorPrior2
// (problems/inflight_alignment/distance_heading_residual.h): the Jacobians against central differences at
// zero, a tiny perturbation and a random point, a zero residual for data made by the model
// (rotation built independently with Eigen::Rotation2D), the first-order (equation 8) form
// at small heading errors, the level steps' sign and linearity, and the constructors' checks.
#include "problems/inflight_alignment/distance_heading_residual.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "tests/factors/tangent_jacobian_check.h"
#include "core/units.h"

namespace navtwin::inflight {
namespace inflight_alignment_distance_heading_residual_test {

using tangent_check::Block;
using tangent_check::ExpectTangentJacobiansMatch;

constexpr double kG = 9.80;
constexpr double kSigma = 17.0;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Schuler basis at t = 300 s for w t << 1 (t, t^2/2, t^3/6): the functor takes any values;
// these give the sizes of a 300 s flight.
constexpr double kB1 = 300.0, kB2 = 45000.0, kB3 = 4.5e6;

// The unknowns of one evaluation, in the functor's block order.
struct Unknowns {
  double dh = 0.0;
  Eigen::Vector2d eps = Eigen::Vector2d::Zero(), df = Eigen::Vector2d::Zero(), dw = Eigen::Vector2d::Zero();
  Eigen::Vector2d p0 = Eigen::Vector2d::Zero(), v0 = Eigen::Vector2d::Zero();
};

std::vector<double> Std2(const Eigen::Vector2d& v) { return {v[0], v[1]}; }

// Steps: the residual is linear in every block but the heading, so central differences
// have only rounding there (~eps |r| / h); the heading's truncation is h^2/6 |D| / sigma.
std::vector<Block> Blocks(const Unknowns& u) {
  return {{{u.dh}, nullptr, 1e-6},       {Std2(u.eps), nullptr, 1e-6}, {Std2(u.df), nullptr, 1e-6},
          {Std2(u.dw), nullptr, 1e-9},   {Std2(u.p0), nullptr, 1e-3},  {Std2(u.v0), nullptr, 1e-3}};
}

// The model written out independently: Rz(dH) from Eigen::Rotation2D on (N, E) (a
// rotation by +dH turns north towards east), the Schuler part from the header's formula.
Eigen::Vector2d ModelError(const Unknowns& u, const Eigen::Vector2d& d_ne) {
  const Eigen::Matrix2d rz = Eigen::Rotation2Dd(u.dh).toRotationMatrix();
  const Eigen::Vector2d s(u.p0[0] + u.v0[0] * kB1 + (u.df[0] + kG * u.eps[1]) * kB2 + kG * u.dw[1] * kB3,
                          u.p0[1] + u.v0[1] * kB1 + (u.df[1] - kG * u.eps[0]) * kB2 - kG * u.dw[0] * kB3);
  return (rz - Eigen::Matrix2d::Identity()) * d_ne + s;
}

// The three test points.
std::vector<std::pair<std::string, Unknowns>> Points() {
  std::vector<std::pair<std::string, Unknowns>> points;
  points.push_back({"zero", Unknowns()});
  Unknowns tiny;
  tiny.dh = 1e-9;
  tiny.eps = {1e-9, -2e-9};
  tiny.df = {-1e-9, 1e-9};
  tiny.dw = {1e-12, -1e-12};
  tiny.p0 = {1e-9, 2e-9};
  tiny.v0 = {-1e-9, 3e-9};
  points.push_back({"tiny", tiny});
  std::mt19937 rng(20240917);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Unknowns random;
  random.dh = 0.5 * u(rng);  // up to 29 deg: the exact rotation, far from the linear form
  random.eps = 3e-4 * Eigen::Vector2d(u(rng), u(rng));
  random.df = 3e-3 * Eigen::Vector2d(u(rng), u(rng));
  random.dw = 1e-7 * Eigen::Vector2d(u(rng), u(rng));
  random.p0 = 50.0 * Eigen::Vector2d(u(rng), u(rng));
  random.v0 = 0.3 * Eigen::Vector2d(u(rng), u(rng));
  points.push_back({"random", random});
  return points;
}

const Eigen::Vector2d kGained(-40000.0, 3000.0);  // m: mostly south, some east
const Eigen::Vector2d kError(12.0, 240.0);         // m

TEST(DistanceHeadingResidual, JacobianMatchesCentralDifferences) {
  const std::unique_ptr<ceres::CostFunction> f(
      DistanceHeadingResidual::Create(kB1, kB2, kB3, kGained, kError, kSigma, kG));
  ASSERT_EQ(f->num_residuals(), 2);
  ASSERT_EQ(f->parameter_block_sizes(), (std::vector<int32_t>{1, 2, 2, 2, 2, 2}));
  for (const auto& [name, u] : Points()) {
    SCOPED_TRACE(name);
    // Rounding of the differences: eps |r| / h <= 2.2e-16 x 3e3 / 1e-9 = 7e-4 for the gyro
    // block, whose Jacobian is g b3 / sigma = 2.6e6; for the others it is <= 1e-6 next to
    // Jacobians of 1 .. 3e4. Heading truncation (1e-6)^2 / 6 x 4e4 / 17 = 4e-10. All well
    // below 1e-8 of the block's largest entry.
    ExpectTangentJacobiansMatch(*f, Blocks(u), 1e-8);
  }
}

TEST(DistanceHeadingResidual, ZeroForDataFromTheModel) {
  for (const auto& [name, u] : Points()) {
    for (const double dh : {u.dh, 20.0 * kArcmin_rad, -M_PI / 2.0, 3.0}) {
      SCOPED_TRACE(name + " dh " + std::to_string(dh));
      Unknowns truth = u;
      truth.dh = dh;
      const Eigen::Vector2d err = ModelError(truth, kGained);
      const std::unique_ptr<ceres::CostFunction> f(
          DistanceHeadingResidual::Create(kB1, kB2, kB3, kGained, err, kSigma, kG));
      // Rounding of terms up to |D| = 4e4 m: 1e-11 m relative to sigma 17 m is < 1e-12.
      EXPECT_LT(tangent_check::Residual(*f, Blocks(truth)).norm(), 1e-10);
    }
  }
  // A quarter turn: a displacement north shows as the same distance east (and back).
  Unknowns quarter;
  quarter.dh = M_PI / 2.0;
  const Eigen::Vector2d d(1000.0, 0.0);
  const std::unique_ptr<ceres::CostFunction> f(
      DistanceHeadingResidual::Create(kB1, kB2, kB3, d, Eigen::Vector2d(-1000.0, 1000.0), 1.0, kG));
  EXPECT_LT(tangent_check::Residual(*f, Blocks(quarter)).norm(), 1e-12);
}

TEST(DistanceHeadingResidual, SmallHeadingGivesTheLinearFormToSecondOrder) {
  // East residual x sigma minus the linear form err_E - dH D_N - s_E is
  // -(sin dH - dH) D_N - (cos dH - 1) D_E = dH^3/6 D_N + dH^2/2 D_E: O(dH^2).
  Unknowns u = Points()[2].second;
  double previous = 0.0;
  for (const double dh : {20.0 * kArcmin_rad, 10.0 * kArcmin_rad, 5.0 * kArcmin_rad}) {
    SCOPED_TRACE(dh / kArcmin_rad);
    u.dh = dh;
    const std::unique_ptr<ceres::CostFunction> f(
        DistanceHeadingResidual::Create(kB1, kB2, kB3, kGained, kError, kSigma, kG));
    const double east_m = tangent_check::Residual(*f, Blocks(u))[1] * kSigma;
    const double s_e = u.p0[1] + u.v0[1] * kB1 + (u.df[1] - kG * u.eps[0]) * kB2 - kG * u.dw[0] * kB3;
    const double difference = east_m - (kError[1] - dh * kGained[0] - s_e);
    const double predicted = dh * dh * dh / 6.0 * kGained[0] + dh * dh / 2.0 * kGained[1];
    // The two terms above exactly up to the next order (dH^4 |D| / 24 < 1e-5 m) and rounding.
    EXPECT_NEAR(difference, predicted, 1e-5);
    EXPECT_GT(std::abs(difference), 0.0);
    // Halving dH divides the difference by 4: the dH^3 term (-2.6 % of the dH^2 term at
    // 20') moves the ratio to 3.95 for 20' -> 10' and 3.97 for 10' -> 5'.
    if (previous != 0.0) {
      EXPECT_NEAR(previous / difference, 4.0, 0.1);
    }
    previous = difference;
  }
}

TEST(DistanceHeadingResidual, RejectsBadInput) {
  const Eigen::Vector2d bad(kNaN, 0.0), inf(0.0, kInf);
  EXPECT_THROW(DistanceHeadingResidual(kNaN, kB2, kB3, kGained, kError, kSigma, kG), std::invalid_argument);
  EXPECT_THROW(DistanceHeadingResidual(kB1, kInf, kB3, kGained, kError, kSigma, kG), std::invalid_argument);
  EXPECT_THROW(DistanceHeadingResidual(kB1, kB2, kNaN, kGained, kError, kSigma, kG), std::invalid_argument);
  EXPECT_THROW(DistanceHeadingResidual(kB1, kB2, kB3, bad, kError, kSigma, kG), std::invalid_argument);
  EXPECT_THROW(DistanceHeadingResidual(kB1, kB2, kB3, kGained, inf, kSigma, kG), std::invalid_argument);
  for (const double sigma : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_THROW(DistanceHeadingResidual(kB1, kB2, kB3, kGained, kError, sigma, kG), std::invalid_argument) << sigma;
  }
  for (const double g : {0.0, -9.8, kNaN, kInf}) {
    EXPECT_THROW(DistanceHeadingResidual(kB1, kB2, kB3, kGained, kError, kSigma, g), std::invalid_argument) << g;
  }
}

// Level steps at tau = 30, 120, 270 s seen from t = 300 s: c_k = (t - tau_k)^2 / 2 (the
// small-angle form of SchulerBasis(t - tau)[2]; the class takes any values).
const std::vector<double> kStepBasis = {36450.0, 16200.0, 450.0};

// Step values at the three test points: zero, 1e-9 rad, and random at ~4 x ARW sqrt(30 s)
// of a 0.005 deg/sqrt(h) gyro (8e-6 rad).
std::vector<Eigen::Vector2d> StepValues(const std::string& point) {
  if (point == "zero") return std::vector<Eigen::Vector2d>(kStepBasis.size(), Eigen::Vector2d::Zero());
  if (point == "tiny") return {{1e-9, -1e-9}, {2e-9, 1e-9}, {-1e-9, 3e-9}};
  std::mt19937 rng(20240918);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Vector2d> steps;
  for (std::size_t k = 0; k < kStepBasis.size(); ++k) steps.push_back(3e-5 * Eigen::Vector2d(u(rng), u(rng)));
  return steps;
}

// The blocks of DistanceHeadingTiltWalkResidual: the six constant ones, then the steps. The
// residual is linear in the steps: central differences have rounding only, eps |r| / h <=
// 2.2e-16 x 1.2e3 / 1e-7 = 3e-6 (|r| is largest at the random point's 29 deg heading), 1e-10
// of the Jacobians c g / sigma = 260 .. 2.1e4.
std::vector<Block> WalkBlocks(const Unknowns& u, const std::vector<Eigen::Vector2d>& steps) {
  std::vector<Block> blocks = Blocks(u);
  for (const Eigen::Vector2d& d : steps) blocks.push_back({Std2(d), nullptr, 1e-7});
  return blocks;
}

// The walk's part written out from the header: s_N += c g d_eps_E, s_E -= c g d_eps_N.
Eigen::Vector2d WalkError(const std::vector<Eigen::Vector2d>& steps) {
  Eigen::Vector2d s = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < steps.size(); ++k) s += kStepBasis[k] * kG * Eigen::Vector2d(steps[k][1], -steps[k][0]);
  return s;
}

TEST(DistanceHeadingTiltWalkResidual, JacobianMatchesCentralDifferences) {
  const std::unique_ptr<ceres::CostFunction> f(
      DistanceHeadingTiltWalkResidual::Create(kB1, kB2, kB3, kGained, kError, kSigma, kG, kStepBasis));
  ASSERT_EQ(f->num_residuals(), 2);
  ASSERT_EQ(f->parameter_block_sizes(), (std::vector<int32_t>{1, 2, 2, 2, 2, 2, 2, 2, 2}));
  for (const auto& [name, u] : Points()) {
    SCOPED_TRACE(name);
    // The constant blocks as in DistanceHeadingResidual's test (1e-8 of the largest entry);
    // the steps: rounding only (above).
    ExpectTangentJacobiansMatch(*f, WalkBlocks(u, StepValues(name)), 1e-8);
  }
}

TEST(DistanceHeadingTiltWalkResidual, ZeroForDataFromTheModelAndTheConstantPartWithoutSteps) {
  for (const auto& [name, u] : Points()) {
    SCOPED_TRACE(name);
    const std::vector<Eigen::Vector2d> steps = StepValues(name);
    const Eigen::Vector2d err = ModelError(u, kGained) + WalkError(steps);
    const std::unique_ptr<ceres::CostFunction> f(
        DistanceHeadingTiltWalkResidual::Create(kB1, kB2, kB3, kGained, err, kSigma, kG, kStepBasis));
    // Terms up to |D| = 4e4 m: rounding 1e-11 m, < 1e-12 after whitening by 17 m.
    EXPECT_LT(tangent_check::Residual(*f, WalkBlocks(u, steps)).norm(), 1e-10);

    // Without steps it is DistanceHeadingResidual: the same evaluation, bit for bit.
    const std::unique_ptr<ceres::CostFunction> plain(
        DistanceHeadingResidual::Create(kB1, kB2, kB3, kGained, kError, kSigma, kG));
    const std::unique_ptr<ceres::CostFunction> no_steps(
        DistanceHeadingTiltWalkResidual::Create(kB1, kB2, kB3, kGained, kError, kSigma, kG, {}));
    ASSERT_EQ(no_steps->parameter_block_sizes(), plain->parameter_block_sizes());
    EXPECT_EQ(tangent_check::Residual(*no_steps, Blocks(u)), tangent_check::Residual(*plain, Blocks(u)));
  }
}

TEST(DistanceHeadingTiltWalkResidual, StepSignAndNoJacobianRequest) {
  // One step d_eps_N = 1e-5 rad with c = 450 s^2: s_E -= c g d_eps_N = -0.0441 m, so the
  // east residual grows by 0.0441 / 17 and the north one is unchanged (rounding only).
  const std::vector<double> basis = {450.0};
  const std::unique_ptr<ceres::CostFunction> f(
      DistanceHeadingTiltWalkResidual::Create(kB1, kB2, kB3, kGained, kError, kSigma, kG, basis));
  const Unknowns u = Points()[2].second;
  const Eigen::VectorXd r0 = tangent_check::Residual(*f, WalkBlocks(u, {Eigen::Vector2d::Zero()}));
  const Eigen::VectorXd r1 = tangent_check::Residual(*f, WalkBlocks(u, {Eigen::Vector2d(1e-5, 0.0)}));
  EXPECT_NEAR(r1[0] - r0[0], 0.0, 1e-13);
  EXPECT_NEAR(r1[1] - r0[1], 450.0 * kG * 1e-5 / kSigma, 1e-13);
  // Jacobians asked for some blocks only (nullptr for the others, as Ceres does for
  // constant blocks): those given are filled, the residual is the same.
  std::vector<Block> blocks = WalkBlocks(u, {Eigen::Vector2d(1e-5, -2e-5)});
  std::vector<const double*> parameters;
  for (const Block& b : blocks) parameters.push_back(b.x.data());
  double residual[2];
  double j_heading[2], j_step[4];
  double* jacobians[7] = {j_heading, nullptr, nullptr, nullptr, nullptr, nullptr, j_step};
  ASSERT_TRUE(f->Evaluate(parameters.data(), residual, jacobians));
  // With Jacobians the constant part runs in Jet arithmetic: equal up to rounding.
  const Eigen::VectorXd r = tangent_check::Residual(*f, blocks);
  EXPECT_NEAR(residual[0], r[0], 1e-14 * (1.0 + r.norm()));
  EXPECT_NEAR(residual[1], r[1], 1e-14 * (1.0 + r.norm()));
  const double a = 450.0 * kG / kSigma;
  EXPECT_EQ(j_step[0], 0.0);
  EXPECT_EQ(j_step[1], -a);
  EXPECT_EQ(j_step[2], a);
  EXPECT_EQ(j_step[3], 0.0);
}

TEST(DistanceHeadingTiltWalkResidual, RejectsBadInput) {
  for (const double bad : {kNaN, kInf}) {
    EXPECT_THROW(DistanceHeadingTiltWalkResidual(kB1, kB2, kB3, kGained, kError, kSigma, kG, {1.0, bad}),
                 std::invalid_argument)
        << bad;
  }
  // The constant part's checks apply.
  EXPECT_THROW(DistanceHeadingTiltWalkResidual(kB1, kB2, kB3, kGained, kError, 0.0, kG, {1.0}),
               std::invalid_argument);
  EXPECT_THROW(DistanceHeadingTiltWalkResidual(kB1, kB2, kB3, kGained, kError, kSigma, kNaN, {1.0}),
               std::invalid_argument);
}

TEST(VectorPrior2, ResidualJacobianAndChecks) {
  const std::unique_ptr<ceres::CostFunction> f(
      VectorPrior2::Create(Eigen::Vector2d(1.0, -2.0), Eigen::Vector2d(0.5, 4.0)));
  const std::vector<Block> blocks = {{{2.0, 2.0}, nullptr, 1e-3}};
  // (2 - 1) / 0.5 = 2 and (2 + 2) / 4 = 1, exact in binary.
  EXPECT_EQ(tangent_check::Residual(*f, blocks), Eigen::Vector2d(2.0, 1.0));
  // Linear: central differences exact up to rounding (eps x 2 / 1e-3 ~ 5e-13).
  ExpectTangentJacobiansMatch(*f, blocks, 1e-9);
  for (const double bad : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_THROW(VectorPrior2(Eigen::Vector2d::Zero(), Eigen::Vector2d(1.0, bad)), std::invalid_argument) << bad;
  }
  EXPECT_THROW(VectorPrior2(Eigen::Vector2d(kNaN, 0.0), Eigen::Vector2d::Ones()), std::invalid_argument);
}

}  // namespace inflight_alignment_distance_heading_residual_test
}  // namespace navtwin::inflight
