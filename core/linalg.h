// Dense decompositions of dynamic size, compiled once (core/linalg.cc).
//
// Eigen's decompositions are templates: every translation unit that names
// SelfAdjointEigenSolver or ColPivHouseholderQR for a new matrix type compiles the whole
// algorithm again (4-6 s of g++ 12 each for 9x9 or dynamic size; docs/building.md). The
// calibration and batch code calls these functions instead. They are Eigen's own
// algorithms on Eigen::MatrixXd, so the results are Eigen's; fixed-size callers pass their
// matrices (converted implicitly) and copy back the few numbers they need.
#pragma once

#include <Eigen/Core>

namespace navtwin {

/// Eigen-decomposition A = V diag(values) V^T of a symmetric matrix (its lower triangle is
/// read): eigenvalues ascending, eigenvectors in the columns of V.
struct SymmetricEigen {
  Eigen::VectorXd values;
  Eigen::MatrixXd vectors;
};
SymmetricEigen SymmetricEigenDecomposition(const Eigen::MatrixXd& A);

/// The least-squares solution x of A x = b by column-pivoting Householder QR (rank-revealing;
/// A may have more rows than columns).
Eigen::VectorXd LeastSquaresColPivQr(const Eigen::MatrixXd& A, const Eigen::VectorXd& b);

}  // namespace navtwin
