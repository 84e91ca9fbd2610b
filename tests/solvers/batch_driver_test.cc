// SolveBatch and the tangent-space covariance on Wahba's problem: one attitude q_n_b
// observed through body-frame unit vectors of known NED reference directions
// (VectorDirection residuals, AttitudeManifold).
#include "solvers/batch_driver.h"

#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <ceres/autodiff_cost_function.h>
#include <gtest/gtest.h>

#include "core/rotation.h"
#include "factors/attitude_manifold.h"
#include "factors/vector_direction.h"

namespace navtwin {
namespace solvers_batch_driver_test {

constexpr double kSigma = 0.01;  // noise of each unit-vector component (~rad)
constexpr int kNumDirections = 20;

const Eigen::Quaterniond& TrueAttitude() {
  static const Eigen::Quaterniond q = QuatFromEuler(0.3, -0.5, 2.0);
  return q;
}

/// A start about 30 deg away from the truth.
Eigen::Quaterniond InitialGuess() { return ApplyAttitudeError<double>(Eigen::Vector3d(0.3, -0.2, 0.4), TrueAttitude()); }

std::vector<Eigen::Vector3d> ReferenceDirections(int count, std::mt19937& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Eigen::Vector3d> r_n;
  for (int i = 0; i < count; ++i) r_n.push_back(Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized());
  return r_n;
}

/// u_b = normalize(R_n_b^T r_n + noise), noise N(0, sigma^2 I) per component (sigma = 0:
/// exact observations).
std::vector<Eigen::Vector3d> Observations(const std::vector<Eigen::Vector3d>& r_n, double sigma, std::mt19937& rng) {
  std::normal_distribution<double> normal(0.0, sigma);
  std::vector<Eigen::Vector3d> u_b;
  for (const Eigen::Vector3d& r : r_n) {
    const Eigen::Vector3d noise(normal(rng), normal(rng), normal(rng));
    u_b.push_back((TrueAttitude().conjugate() * r + noise).normalized());
  }
  return u_b;
}

/// Adds one attitude block (coefficients x, y, z, w in q) with its direction residuals.
void AddWahba(ceres::Problem& problem, double* q, const std::vector<Eigen::Vector3d>& r_n,
              const std::vector<Eigen::Vector3d>& u_b) {
  problem.AddParameterBlock(q, 4, new AttitudeManifold);
  for (std::size_t i = 0; i < r_n.size(); ++i) {
    problem.AddResidualBlock(VectorDirection::Create(u_b[i], r_n[i], kSigma), nullptr, q);
  }
}

struct WahbaSolution {
  Eigen::Quaterniond q_n_b;
  BatchReport report;
  CovarianceResult covariance;
};

WahbaSolution SolveWahba(const std::vector<Eigen::Vector3d>& r_n, const std::vector<Eigen::Vector3d>& u_b,
                         const BatchOptions& options, std::ostream* progress,
                         const CovarianceOptions& covariance_options = CovarianceOptions()) {
  Eigen::Vector4d q = InitialGuess().coeffs();
  ceres::Problem problem;
  AddWahba(problem, q.data(), r_n, u_b);
  WahbaSolution solution;
  solution.report = SolveBatch(problem, options, progress);
  solution.covariance = ComputeTangentCovariance(problem, {q.data()}, covariance_options);
  solution.q_n_b = Eigen::Quaterniond(q);
  return solution;
}

BatchOptions Quiet() {
  BatchOptions options;
  options.progress = false;
  return options;
}

/// phi_n with R_true = Exp(phi_n) R_est: the estimation error in the manifold's tangent.
Eigen::Vector3d Error(const Eigen::Quaterniond& q_est) { return AttitudeError(TrueAttitude(), q_est); }

TEST(BatchDriver, WahbaEstimateWithinFourSigmaOfTruth) {
  std::mt19937 rng(7);
  const std::vector<Eigen::Vector3d> r_n = ReferenceDirections(kNumDirections, rng);
  const WahbaSolution s = SolveWahba(r_n, Observations(r_n, kSigma, rng), Quiet(), nullptr);
  EXPECT_TRUE(s.report.converged) << s.report.brief_report;
  EXPECT_LT(s.report.final_cost, s.report.initial_cost);
  ASSERT_TRUE(s.covariance.covariance.has_value()) << s.covariance.message;
  const Eigen::Matrix3d P = *s.covariance.covariance;
  const Eigen::Vector3d phi_n = Error(s.q_n_b);
  for (int axis = 0; axis < 3; ++axis) {
    // 4 sigma: a correct estimate fails this with probability ~6e-5 per axis.
    EXPECT_LT(std::abs(phi_n(axis)), 4.0 * std::sqrt(P(axis, axis))) << "axis " << axis;
  }
  // First-order theory: J_i = -[r_n,i]x / sigma, so P = sigma^2 (sum_i (I - r_i r_i^T))^-1.
  // The solver's J uses R_est u_b,i instead of r_n,i, which differ by O(sigma) = 1 %, so
  // the two agree to a few percent; 5 % is that margin.
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& r : r_n) information += Eigen::Matrix3d::Identity() - r * r.transpose();
  const Eigen::Matrix3d P_theory = kSigma * kSigma * information.inverse();
  EXPECT_LT((P - P_theory).norm(), 0.05 * P_theory.norm()) << P << "\n" << P_theory;
}

TEST(BatchDriver, CovarianceAlgorithmsAgree) {
  std::mt19937 rng(13);
  const std::vector<Eigen::Vector3d> r_n = ReferenceDirections(kNumDirections, rng);
  const std::vector<Eigen::Vector3d> u_b = Observations(r_n, kSigma, rng);
  CovarianceOptions sparse, dense;
  sparse.algorithm = CovarianceOptions::Algorithm::kSparseQr;
  dense.algorithm = CovarianceOptions::Algorithm::kDenseSvd;
  const WahbaSolution a = SolveWahba(r_n, u_b, Quiet(), nullptr, sparse);
  const WahbaSolution b = SolveWahba(r_n, u_b, Quiet(), nullptr, dense);
  ASSERT_TRUE(a.covariance.covariance.has_value()) << a.covariance.message;
  ASSERT_TRUE(b.covariance.covariance.has_value()) << b.covariance.message;
  // Same J (same data, same deterministic solve), two factorizations of a well-conditioned
  // 3x3 problem: they agree to rounding.
  EXPECT_LT((*a.covariance.covariance - *b.covariance.covariance).norm(), 1e-12 * b.covariance.covariance->norm());
  EXPECT_TRUE(a.covariance.message.empty());
}

TEST(BatchDriver, CovarianceAgreesWithMonteCarloScatter) {
  std::mt19937 rng(11);
  const std::vector<Eigen::Vector3d> r_n = ReferenceDirections(kNumDirections, rng);
  constexpr int kTrials = 200;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d mean_covariance = Eigen::Matrix3d::Zero();
  for (int trial = 0; trial < kTrials; ++trial) {
    const WahbaSolution s = SolveWahba(r_n, Observations(r_n, kSigma, rng), Quiet(), nullptr);
    ASSERT_TRUE(s.report.converged) << s.report.brief_report;
    ASSERT_TRUE(s.covariance.covariance.has_value()) << s.covariance.message;
    const Eigen::Vector3d phi_n = Error(s.q_n_b);
    scatter += phi_n * phi_n.transpose() / kTrials;  // the true mean error is 0
    mean_covariance += *s.covariance.covariance / kTrials;
  }
  for (int axis = 0; axis < 3; ++axis) {
    // A variance estimated from N = 200 samples has a relative standard deviation of
    // sqrt(2 / N) = 10 %; 20 % is two of those (plus the O(sigma) nonlinearity).
    EXPECT_NEAR(scatter(axis, axis) / mean_covariance(axis, axis), 1.0, 0.2) << "axis " << axis;
  }
}

TEST(BatchDriver, WritesOneProgressLinePerIteration) {
  std::mt19937 rng(3);
  const std::vector<Eigen::Vector3d> r_n = ReferenceDirections(kNumDirections, rng);
  const std::vector<Eigen::Vector3d> u_b = Observations(r_n, kSigma, rng);
  std::ostringstream progress;
  const WahbaSolution s = SolveWahba(r_n, u_b, BatchOptions(), &progress);
  std::istringstream lines(progress.str());
  std::string line;
  int count = 0;
  while (std::getline(lines, line)) {
    EXPECT_EQ(line.rfind("batch iter " + std::to_string(count) + " cost ", 0), 0u) << line;
    EXPECT_NE(line.find(" |gradient| "), std::string::npos) << line;
    EXPECT_NE(line.find(" elapsed_s "), std::string::npos) << line;
    ++count;
  }
  EXPECT_GT(s.report.iterations, 0);
  EXPECT_EQ(count, s.report.iterations + 1);  // iteration 0 is the initial point

  std::ostringstream silent;
  SolveWahba(r_n, u_b, Quiet(), &silent);
  EXPECT_TRUE(silent.str().empty());
}

TEST(BatchDriver, LinearSolversAgree) {
  std::mt19937 rng(5);
  const std::vector<Eigen::Vector3d> r_n = ReferenceDirections(kNumDirections, rng);
  const std::vector<Eigen::Vector3d> u_b = Observations(r_n, kSigma, rng);
  BatchOptions dense = Quiet(), sparse = Quiet();
  dense.linear_solver = BatchOptions::LinearSolver::kDenseQr;
  sparse.linear_solver = BatchOptions::LinearSolver::kSparseNormalCholesky;
  const WahbaSolution a = SolveWahba(r_n, u_b, dense, nullptr);
  const WahbaSolution b = SolveWahba(r_n, u_b, sparse, nullptr);
  EXPECT_TRUE(a.report.converged && b.report.converged);
  // Both converge to the same minimum; the tolerances stop them within ~1e-9 rad of it,
  // far below sigma_est ~ 3e-3 rad.
  EXPECT_LT(AttitudeError(a.q_n_b, b.q_n_b).norm(), 1e-8);
}

TEST(BatchDriver, SingleDirectionIsReportedUnobservable) {
  // 20 exact observations of one direction: the rotation about it is not observable.
  const Eigen::Vector3d r = Eigen::Vector3d(0.2, -0.6, 0.7).normalized();
  const std::vector<Eigen::Vector3d> r_n(kNumDirections, r);
  std::mt19937 rng(1);
  const std::vector<Eigen::Vector3d> u_b = Observations(r_n, 0.0, rng);
  for (const auto algorithm : {CovarianceOptions::Algorithm::kSparseQr, CovarianceOptions::Algorithm::kDenseSvd}) {
    CovarianceOptions options;
    options.algorithm = algorithm;
    const WahbaSolution s = SolveWahba(r_n, u_b, Quiet(), nullptr, options);
    EXPECT_FALSE(s.covariance.covariance.has_value());
    EXPECT_NE(s.covariance.message.find("unobservable requested blocks: 0"), std::string::npos)
        << s.covariance.message;
    ASSERT_EQ(s.covariance.unobservable_blocks, std::vector<int>{0});
    ASSERT_EQ(s.covariance.null_space.rows(), 3);
    ASSERT_EQ(s.covariance.null_space.cols(), 1);
    // The null direction is the rotation about r (nav frame) = R_est u_b, which the solver
    // matches to r within its tolerances (~1e-9 rad); 1e-6 leaves a wide margin.
    EXPECT_GT(std::abs(s.covariance.null_space.col(0).dot(r)), 1.0 - 1e-6) << s.covariance.null_space;
  }
}

TEST(BatchDriver, JointCovarianceNamesTheUnobservableBlock) {
  std::mt19937 rng(9);
  const std::vector<Eigen::Vector3d> r_good = ReferenceDirections(kNumDirections, rng);
  const std::vector<Eigen::Vector3d> u_good = Observations(r_good, kSigma, rng);
  const std::vector<Eigen::Vector3d> r_bad(kNumDirections, Eigen::Vector3d::UnitX());
  const std::vector<Eigen::Vector3d> u_bad = Observations(r_bad, 0.0, rng);

  Eigen::Vector4d q_good = InitialGuess().coeffs(), q_bad = InitialGuess().coeffs();
  ceres::Problem problem;
  AddWahba(problem, q_good.data(), r_good, u_good);
  AddWahba(problem, q_bad.data(), r_bad, u_bad);
  SolveBatch(problem, Quiet(), nullptr);

  const CovarianceResult both = ComputeTangentCovariance(problem, {q_good.data(), q_bad.data()});
  EXPECT_FALSE(both.covariance.has_value());
  EXPECT_EQ(both.unobservable_blocks, std::vector<int>{1});
  EXPECT_EQ(both.null_space.rows(), 6);
  EXPECT_FALSE(TangentCovariance(problem, {q_good.data(), q_bad.data()}).has_value());
  // Ceres factorizes the whole J (dense SVD here, kAuto on 6 parameters), so even the
  // observable block alone fails; the report says the null space lies elsewhere.
  const CovarianceResult good_only = ComputeTangentCovariance(problem, {q_good.data()});
  EXPECT_FALSE(good_only.covariance.has_value());
  EXPECT_TRUE(good_only.unobservable_blocks.empty());
  EXPECT_NE(good_only.message.find("not requested"), std::string::npos) << good_only.message;

  // With the bad block held constant, the joint covariance exists and that block's is zero.
  problem.SetParameterBlockConstant(q_bad.data());
  const std::optional<Eigen::MatrixXd> joint = TangentCovariance(problem, {q_good.data(), q_bad.data()});
  ASSERT_TRUE(joint.has_value());
  const std::optional<Eigen::MatrixXd> single = TangentCovariance(problem, q_good.data());
  ASSERT_TRUE(single.has_value());
  EXPECT_LT((joint->topLeftCorner<3, 3>() - *single).norm(), 1e-12 * single->norm());  // same computation
  EXPECT_EQ(joint->bottomRows<3>().norm(), 0.0);
}

/// r = a x1 + b x2: one row of a linear problem in two scalar blocks.
struct LinearRow {
  template <typename T>
  bool operator()(const T* x1, const T* x2, T* residual) const {
    residual[0] = T(a) * x1[0] + T(b) * x2[0];
    return true;
  }
  double a, b;
};

TEST(BatchDriver, NearlyCollinearColumnsAreRejectedBySparseQrToo) {
  // J = [1 1; 1+d 1-d]: cond(J) ~ 1/d. Sparse QR's rank test (tolerance ~1e-14 here) calls
  // it full rank; the variance inflation check (~1/d^2 = 1e18 > 1e14) must reject it.
  constexpr double d = 1e-9;
  double x1 = 0.0, x2 = 0.0;
  ceres::Problem problem;
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LinearRow, 1, 1, 1>(new LinearRow{1.0, 1.0}), nullptr,
                           &x1, &x2);
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LinearRow, 1, 1, 1>(new LinearRow{1.0 + d, 1.0 - d}),
                           nullptr, &x1, &x2);
  for (const auto algorithm : {CovarianceOptions::Algorithm::kSparseQr, CovarianceOptions::Algorithm::kDenseSvd}) {
    CovarianceOptions options;
    options.algorithm = algorithm;
    const CovarianceResult result = ComputeTangentCovariance(problem, {&x1, &x2}, options);
    EXPECT_FALSE(result.covariance.has_value());
    EXPECT_EQ(result.unobservable_blocks, (std::vector<int>{0, 1})) << result.message;
    ASSERT_EQ(result.null_space.cols(), 1);
    // The null direction is (1, -1) / sqrt(2) up to O(d).
    EXPECT_NEAR(std::abs(result.null_space(0, 0) - result.null_space(1, 0)), std::sqrt(2.0), 1e-6);
  }
  // A well-conditioned version of the same problem passes: J = [1 1; 1 -1], P = I / 2.
  double y1 = 0.0, y2 = 0.0;
  ceres::Problem good;
  good.AddResidualBlock(new ceres::AutoDiffCostFunction<LinearRow, 1, 1, 1>(new LinearRow{1.0, 1.0}), nullptr,
                        &y1, &y2);
  good.AddResidualBlock(new ceres::AutoDiffCostFunction<LinearRow, 1, 1, 1>(new LinearRow{1.0, -1.0}), nullptr,
                        &y1, &y2);
  CovarianceOptions sparse;
  sparse.algorithm = CovarianceOptions::Algorithm::kSparseQr;
  const CovarianceResult result = ComputeTangentCovariance(good, {&y1, &y2}, sparse);
  ASSERT_TRUE(result.covariance.has_value()) << result.message;
  EXPECT_LT((*result.covariance - 0.5 * Eigen::Matrix2d::Identity()).norm(), 1e-15);  // exact in binary
}

TEST(BatchDriver, RejectsBadArguments) {
  Eigen::Vector4d q = Eigen::Quaterniond::Identity().coeffs();
  Eigen::Vector4d other = q;
  ceres::Problem problem;
  AddWahba(problem, q.data(), {Eigen::Vector3d::UnitX()}, {Eigen::Vector3d::UnitX()});
  BatchOptions options = Quiet();
  options.max_iterations = -1;
  EXPECT_THROW(SolveBatch(problem, options, nullptr), std::invalid_argument);
  EXPECT_THROW(ComputeTangentCovariance(problem, {other.data()}), std::invalid_argument);
  EXPECT_THROW(ComputeTangentCovariance(problem, {q.data(), q.data()}), std::invalid_argument);
  EXPECT_THROW(ComputeTangentCovariance(problem, {}), std::invalid_argument);
}

}  // namespace solvers_batch_driver_test
}  // namespace navtwin
