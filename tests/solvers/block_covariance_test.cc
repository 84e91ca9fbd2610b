// ComputeBlockDiagonalCovariance (solvers/batch_driver.h): the diagonal blocks of
// (J^T J)^-1 by selected inversion and by ceres::Covariance's sparse QR, checked against a
// dense inverse on small problems, with a manifold block, a constant block and a rank
// deficient problem.
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/problem.h>
#include <gtest/gtest.h>

#include "core/rotation.h"
#include "factors/attitude_manifold.h"
#include "factors/vector_direction.h"
#include "solvers/batch_driver.h"

namespace navtwin {
namespace solvers_block_covariance_test {

using Algorithm = BlockCovarianceOptions::Algorithm;

/// r = A [x_1; ...; x_k] - b with a fixed matrix A (columns split over the blocks).
class LinearCost final : public ceres::CostFunction {
 public:
  LinearCost(const Eigen::MatrixXd& a, const std::vector<int>& sizes) : a_(a) {
    set_num_residuals(static_cast<int>(a.rows()));
    for (int size : sizes) mutable_parameter_block_sizes()->push_back(size);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    Eigen::Map<Eigen::VectorXd> r(residuals, a_.rows());
    r.setConstant(-1.0);
    int offset = 0;
    for (std::size_t k = 0; k < parameter_block_sizes().size(); ++k) {
      const int size = parameter_block_sizes()[k];
      r += a_.middleCols(offset, size) * Eigen::Map<const Eigen::VectorXd>(parameters[k], size);
      if (jacobians != nullptr && jacobians[k] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[k], a_.rows(),
                                                                                          size) =
            a_.middleCols(offset, size);
      }
      offset += size;
    }
    return true;
  }

 private:
  Eigen::MatrixXd a_;
};

Eigen::MatrixXd RandomMatrix(int rows, int cols, std::mt19937& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd m(rows, cols);
  for (int i = 0; i < m.size(); ++i) m.data()[i] = normal(rng);
  return m;
}

/// A chain of blocks of varied sizes: a prior on the first, a factor between consecutive
/// blocks (like an IMU factor) and a factor on each block alone (like a GNSS fix), with
/// scales from 1e-3 to 1e3 so that the Jacobi scaling matters. Also returns the dense J.
struct Chain {
  std::vector<std::vector<double>> x;
  std::vector<int> offsets;
  int columns = 0;
  Eigen::MatrixXd J;
  ceres::Problem problem;
};

void BuildChain(int count, std::mt19937& rng, Chain* chain) {
  std::vector<int> sizes;
  for (int i = 0; i < count; ++i) {
    sizes.push_back(1 + i % 4);
    chain->x.emplace_back(sizes.back(), 0.0);
    chain->offsets.push_back(chain->columns);
    chain->columns += sizes.back();
  }
  std::vector<Eigen::MatrixXd> rows;
  std::vector<std::vector<int>> touched;
  const auto add = [&](const Eigen::MatrixXd& a, const std::vector<int>& which) {
    std::vector<int> block_sizes;
    std::vector<double*> parameters;
    for (int w : which) {
      block_sizes.push_back(sizes[w]);
      parameters.push_back(chain->x[w].data());
    }
    chain->problem.AddResidualBlock(new LinearCost(a, block_sizes), nullptr, parameters);
    rows.push_back(a);
    touched.push_back(which);
  };
  add(RandomMatrix(sizes[0], sizes[0], rng), {0});
  for (int i = 1; i < count; ++i) {
    Eigen::MatrixXd between = RandomMatrix(sizes[i], sizes[i - 1] + sizes[i], rng);
    between *= std::pow(10.0, (i % 7) - 3.0);
    add(between, {i - 1, i});
    add(RandomMatrix(1, sizes[i], rng), {i});
  }
  int total_rows = 0;
  for (const Eigen::MatrixXd& a : rows) total_rows += static_cast<int>(a.rows());
  chain->J = Eigen::MatrixXd::Zero(total_rows, chain->columns);
  int row = 0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    int column = 0;
    for (int w : touched[r]) {
      chain->J.block(row, chain->offsets[w], rows[r].rows(), sizes[w]) = rows[r].middleCols(column, sizes[w]);
      column += sizes[w];
    }
    row += static_cast<int>(rows[r].rows());
  }
}

std::vector<const double*> AllBlocks(const Chain& chain) {
  std::vector<const double*> blocks;
  for (const auto& x : chain.x) blocks.push_back(x.data());
  return blocks;
}

/// Largest |difference| relative to the largest |entry| of the reference, over all blocks.
double BlockError(const Chain& chain, const BlockCovarianceResult& result, const Eigen::MatrixXd& reference) {
  double error = 0.0;
  for (std::size_t i = 0; i < chain.x.size(); ++i) {
    const int size = static_cast<int>(chain.x[i].size());
    const Eigen::MatrixXd expected = reference.block(chain.offsets[i], chain.offsets[i], size, size);
    EXPECT_TRUE(result.covariances[i].has_value()) << "block " << i;
    if (!result.covariances[i]) return HUGE_VAL;
    error = std::max(error, (*result.covariances[i] - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff());
  }
  return error;
}

TEST(BlockCovariance, EqualsDiagonalBlocksOfDenseInverse) {
  for (const Algorithm algorithm : {Algorithm::kSelectedInversion, Algorithm::kSparseQr}) {
    std::mt19937 rng(7);
    Chain chain;
    BuildChain(40, rng, &chain);
    const Eigen::MatrixXd H = chain.J.transpose() * chain.J;
    const Eigen::MatrixXd inverse = H.ldlt().solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
    BlockCovarianceOptions options;
    options.algorithm = algorithm;
    const BlockCovarianceResult result = ComputeBlockDiagonalCovariance(chain.problem, AllBlocks(chain), options);
    EXPECT_TRUE(result.message.empty()) << result.message;
    ASSERT_EQ(result.covariances.size(), chain.x.size());
    // The factors span 1e-3..1e3 (H up to ~1e12 in condition): double rounding in either
    // the reference or the tested inverse stays far below 1e-7 relative.
    EXPECT_LT(BlockError(chain, result, inverse), 1e-7) << static_cast<int>(algorithm);
    EXPECT_GE(result.run_time_s, 0.0);
  }
}

TEST(BlockCovariance, SubsetAndOrderOfRequestedBlocks) {
  std::mt19937 rng(11);
  Chain chain;
  BuildChain(25, rng, &chain);
  const Eigen::MatrixXd H = chain.J.transpose() * chain.J;
  const Eigen::MatrixXd inverse = H.ldlt().solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
  const std::vector<int> wanted = {17, 3, 24, 0};
  std::vector<const double*> blocks;
  for (int w : wanted) blocks.push_back(chain.x[w].data());
  const BlockCovarianceResult result = ComputeBlockDiagonalCovariance(chain.problem, blocks);
  ASSERT_EQ(result.covariances.size(), wanted.size());
  for (std::size_t i = 0; i < wanted.size(); ++i) {
    const int size = static_cast<int>(chain.x[wanted[i]].size());
    ASSERT_TRUE(result.covariances[i].has_value());
    const Eigen::MatrixXd expected = inverse.block(chain.offsets[wanted[i]], chain.offsets[wanted[i]], size, size);
    // Same reasoning as above: rounding only.
    EXPECT_LT((*result.covariances[i] - expected).cwiseAbs().maxCoeff(), 1e-7 * expected.cwiseAbs().maxCoeff());
  }
}

TEST(BlockCovariance, ConstantBlockHasZeroCovarianceAndConditionsTheOthers) {
  std::mt19937 rng(3);
  Chain chain;
  BuildChain(10, rng, &chain);
  chain.problem.SetParameterBlockConstant(chain.x[4].data());
  // With block 4 held, the covariance of the rest is the inverse of J^T J without its columns.
  std::vector<int> free_columns;
  for (int c = 0; c < chain.columns; ++c) {
    if (c < chain.offsets[4] || c >= chain.offsets[4] + static_cast<int>(chain.x[4].size())) free_columns.push_back(c);
  }
  Eigen::MatrixXd Jf(chain.J.rows(), free_columns.size());
  for (std::size_t k = 0; k < free_columns.size(); ++k) Jf.col(k) = chain.J.col(free_columns[k]);
  const Eigen::MatrixXd Hf = Jf.transpose() * Jf;
  const Eigen::MatrixXd inverse = Hf.ldlt().solve(Eigen::MatrixXd::Identity(Hf.rows(), Hf.cols()));
  const BlockCovarianceResult result = ComputeBlockDiagonalCovariance(chain.problem, {chain.x[4].data(), chain.x[7].data()});
  EXPECT_TRUE(result.message.empty()) << result.message;
  ASSERT_TRUE(result.covariances[0].has_value());
  EXPECT_EQ(result.covariances[0]->rows(), static_cast<int>(chain.x[4].size()));
  EXPECT_EQ(result.covariances[0]->norm(), 0.0);
  ASSERT_TRUE(result.covariances[1].has_value());
  const int shift = static_cast<int>(chain.x[4].size());  // block 7 lies after block 4
  const int size7 = static_cast<int>(chain.x[7].size());
  const Eigen::MatrixXd expected = inverse.block(chain.offsets[7] - shift, chain.offsets[7] - shift, size7, size7);
  EXPECT_LT((*result.covariances[1] - expected).cwiseAbs().maxCoeff(), 1e-7 * expected.cwiseAbs().maxCoeff());
}

TEST(BlockCovariance, AttitudeManifoldBlockMatchesJointTangentCovariance) {
  // Wahba's problem (one attitude seen through 10 directions) next to a linear chain: the
  // attitude block's tangent covariance must equal ComputeTangentCovariance's (dense SVD).
  std::mt19937 rng(5);
  Chain chain;
  BuildChain(6, rng, &chain);
  Eigen::Vector4d q = QuatFromEuler(0.2, -0.4, 1.0).coeffs();
  chain.problem.AddParameterBlock(q.data(), 4, new AttitudeManifold);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < 10; ++i) {
    const Eigen::Vector3d r_n = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
    const Eigen::Vector3d u_b = (Eigen::Quaterniond(q).conjugate() * r_n + 0.01 * Eigen::Vector3d::Random()).normalized();
    chain.problem.AddResidualBlock(VectorDirection::Create(u_b, r_n, 0.01), nullptr, q.data());
  }
  const CovarianceResult joint = ComputeTangentCovariance(chain.problem, {q.data(), chain.x[2].data()});
  ASSERT_TRUE(joint.covariance.has_value()) << joint.message;
  for (const Algorithm algorithm : {Algorithm::kSelectedInversion, Algorithm::kSparseQr}) {
    BlockCovarianceOptions options;
    options.algorithm = algorithm;
    const BlockCovarianceResult result = ComputeBlockDiagonalCovariance(chain.problem, {q.data(), chain.x[2].data()}, options);
    ASSERT_TRUE(result.covariances[0].has_value()) << result.message;
    ASSERT_EQ(result.covariances[0]->rows(), 3);
    const Eigen::Matrix3d expected = joint.covariance->topLeftCorner(3, 3);
    // Different factorisations of the same well-conditioned matrix: rounding only.
    EXPECT_LT((*result.covariances[0] - expected).cwiseAbs().maxCoeff(), 1e-9 * expected.cwiseAbs().maxCoeff());
    const int size2 = static_cast<int>(chain.x[2].size());
    const Eigen::MatrixXd expected2 = joint.covariance->bottomRightCorner(size2, size2);
    EXPECT_LT((*result.covariances[1] - expected2).cwiseAbs().maxCoeff(), 1e-9 * expected2.cwiseAbs().maxCoeff());
  }
}

TEST(BlockCovariance, RankDeficientProblemGivesMessageAndNoCovariance) {
  // Two scalars observed only through their difference: J^T J is singular.
  double a = 0.0, b = 0.0;
  ceres::Problem problem;
  Eigen::MatrixXd row(1, 2);
  row << 1.0, -1.0;
  problem.AddResidualBlock(new LinearCost(row, {1, 1}), nullptr, &a, &b);
  for (const Algorithm algorithm : {Algorithm::kSelectedInversion, Algorithm::kSparseQr}) {
    BlockCovarianceOptions options;
    options.algorithm = algorithm;
    const BlockCovarianceResult result = ComputeBlockDiagonalCovariance(problem, {&a, &b}, options);
    EXPECT_FALSE(result.message.empty());
    ASSERT_EQ(result.covariances.size(), 2u);
    EXPECT_FALSE(result.covariances[0].has_value());
    EXPECT_FALSE(result.covariances[1].has_value());
  }
}

TEST(BlockCovariance, NearlyCollinearColumnsFail) {
  // x, y observed as x + y and (1 + 1e-9) x + (1 - 1e-9) y: J^T J has the eigenvalue ratio
  // ~5e-19, below the rounding of J^T J itself, so the pivot of the scaled LDL^T is
  // rounding noise: either not positive (everything fails) or tiny (x and y rejected for
  // their inflation); x and y have no covariance either way.
  double x = 0.0, y = 0.0, z = 0.0;
  ceres::Problem problem;
  Eigen::MatrixXd rows(2, 2);
  rows << 1.0, 1.0, 1.0 + 1e-9, 1.0 - 1e-9;
  problem.AddResidualBlock(new LinearCost(rows, {1, 1}), nullptr, &x, &y);
  problem.AddResidualBlock(new LinearCost(Eigen::MatrixXd::Ones(1, 1), {1}), nullptr, &z);
  const BlockCovarianceResult result = ComputeBlockDiagonalCovariance(problem, {&x, &y, &z});
  EXPECT_FALSE(result.message.empty());
  EXPECT_FALSE(result.covariances[0].has_value());
  EXPECT_FALSE(result.covariances[1].has_value());
}

TEST(BlockCovariance, PoorlyObservedBlockIsRejectedAlone) {
  // x, y observed as x + y and (1 + 1e-6) x + (1 - 1e-6) y: variance inflation ~1e12
  // (pivot ~1e-12, still resolved by double rounding of J^T J to ~1e-4 relative), so with
  // min_reciprocal_condition_number = 1e-10 x and y are rejected while z, observed alone,
  // keeps its variance 1.
  double x = 0.0, y = 0.0, z = 0.0;
  ceres::Problem problem;
  Eigen::MatrixXd rows(2, 2);
  rows << 1.0, 1.0, 1.0 + 1e-6, 1.0 - 1e-6;
  problem.AddResidualBlock(new LinearCost(rows, {1, 1}), nullptr, &x, &y);
  problem.AddResidualBlock(new LinearCost(Eigen::MatrixXd::Ones(1, 1), {1}), nullptr, &z);
  BlockCovarianceOptions options;
  options.min_reciprocal_condition_number = 1e-10;
  const BlockCovarianceResult result = ComputeBlockDiagonalCovariance(problem, {&x, &y, &z}, options);
  EXPECT_FALSE(result.message.empty());
  EXPECT_FALSE(result.covariances[0].has_value());
  EXPECT_FALSE(result.covariances[1].has_value());
  ASSERT_TRUE(result.covariances[2].has_value()) << result.message;
  EXPECT_NEAR((*result.covariances[2])(0, 0), 1.0, 1e-12);  // 1 / 1^2, exact up to rounding
}

TEST(BlockCovariance, InvalidRequestsThrow) {
  double a = 0.0, b = 0.0;
  ceres::Problem problem;
  problem.AddResidualBlock(new LinearCost(Eigen::MatrixXd::Ones(1, 1), {1}), nullptr, &a);
  EXPECT_THROW(ComputeBlockDiagonalCovariance(problem, {}), std::invalid_argument);
  EXPECT_THROW(ComputeBlockDiagonalCovariance(problem, {&b}), std::invalid_argument);
  EXPECT_THROW(ComputeBlockDiagonalCovariance(problem, {&a, &a}), std::invalid_argument);
}

// ComputeResidualLeverages: h_i = J_i (J^T J)^-1 J_i^T of every row against the dense
// formula, on the same chain (scales 1e-3 to 1e3); they sum to the number of parameters
// (the trace of the hat matrix). Tolerance 1e-8: the dense inverse of a matrix whose
// condition number reaches ~1e12 loses about that much.
TEST(ResidualLeverages, EqualDenseHatMatrixDiagonal) {
  std::mt19937 rng(11);
  Chain chain;
  BuildChain(30, rng, &chain);
  std::vector<ceres::ResidualBlockId> ids;
  chain.problem.GetResidualBlocks(&ids);
  const LeverageResult result = ComputeResidualLeverages(chain.problem, ids);
  ASSERT_TRUE(result.message.empty()) << result.message;
  ASSERT_EQ(result.leverages.size(), ids.size());
  const Eigen::MatrixXd hat = chain.J * (chain.J.transpose() * chain.J).inverse() * chain.J.transpose();
  int row = 0;
  double sum = 0.0;
  for (const Eigen::VectorXd& h : result.leverages) {
    for (Eigen::Index r = 0; r < h.size(); ++r, ++row) {
      EXPECT_NEAR(h(r), hat(row, row), 1e-8) << "row " << row;
      EXPECT_GE(h(r), -1e-8);
      EXPECT_LE(h(r), 1.0 + 1e-8);
      sum += h(r);
    }
  }
  EXPECT_EQ(row, chain.J.rows());
  EXPECT_NEAR(sum, chain.columns, 1e-6);
}

// A constant block adds no column: a residual on it alone has leverage 0, and the others
// sum to the free parameters.
TEST(ResidualLeverages, ConstantBlockHasNoLeverage) {
  std::mt19937 rng(12);
  Chain chain;
  BuildChain(6, rng, &chain);
  chain.problem.SetParameterBlockConstant(chain.x[0].data());
  std::vector<ceres::ResidualBlockId> ids;
  chain.problem.GetResidualBlocks(&ids);
  const LeverageResult result = ComputeResidualLeverages(chain.problem, ids);
  ASSERT_TRUE(result.message.empty()) << result.message;
  EXPECT_NEAR(result.leverages.front().sum(), 0.0, 1e-12);  // the prior on block 0
  double sum = 0.0;
  for (const Eigen::VectorXd& h : result.leverages) sum += h.sum();
  EXPECT_NEAR(sum, chain.columns - static_cast<int>(chain.x[0].size()), 1e-8);
}

}  // namespace solvers_block_covariance_test
}  // namespace navtwin
