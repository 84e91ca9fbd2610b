// core/linalg: the decompositions the calibration and batch code share.
#include "core/linalg.h"

#include <random>

#include <gtest/gtest.h>

namespace navtwin {
namespace core_linalg_test {

Eigen::MatrixXd RandomMatrix(int rows, int cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::MatrixXd m(rows, cols);
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) m(i, j) = n(rng);
  }
  return m;
}

// A = V diag(values) V^T with V orthonormal and the values ascending; 1e-12 relative is a
// few hundred ulps of the entries (order 10) for a 9 x 9 matrix.
TEST(Linalg, SymmetricEigenReconstructsTheMatrixWithAscendingValues) {
  const Eigen::MatrixXd B = RandomMatrix(9, 9, 7);
  const Eigen::MatrixXd A = B * B.transpose();
  const SymmetricEigen e = SymmetricEigenDecomposition(A);
  ASSERT_EQ(e.values.size(), 9);
  for (int i = 1; i < 9; ++i) EXPECT_LE(e.values(i - 1), e.values(i));
  EXPECT_LT((e.vectors.transpose() * e.vectors - Eigen::MatrixXd::Identity(9, 9)).norm(), 1e-12);
  EXPECT_LT((e.vectors * e.values.asDiagonal() * e.vectors.transpose() - A).norm(), 1e-12 * A.norm());
}

// Only the lower triangle is read, as Eigen's solver does: the upper one may hold anything.
TEST(Linalg, SymmetricEigenReadsTheLowerTriangle) {
  Eigen::Matrix2d A;
  A << 2.0, 99.0,
       1.0, 2.0;
  const SymmetricEigen e = SymmetricEigenDecomposition(A);
  EXPECT_NEAR(e.values(0), 1.0, 1e-14);
  EXPECT_NEAR(e.values(1), 3.0, 1e-14);
}

// An overdetermined consistent system is solved exactly; an inconsistent one matches the
// normal equations (well conditioned here: 1e-10 is far above their rounding).
TEST(Linalg, ColPivQrLeastSquares) {
  const Eigen::MatrixXd A = RandomMatrix(20, 3, 11);
  const Eigen::Vector3d x(1.5, -2.0, 0.25);
  EXPECT_LT((LeastSquaresColPivQr(A, A * x) - x).norm(), 1e-12);
  const Eigen::VectorXd b = A * x + 0.1 * RandomMatrix(20, 1, 12);
  const Eigen::VectorXd normal = (A.transpose() * A).ldlt().solve(A.transpose() * b);
  EXPECT_LT((LeastSquaresColPivQr(A, b) - normal).norm(), 1e-10);
}

}  // namespace core_linalg_test
}  // namespace navtwin
