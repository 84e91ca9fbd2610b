#include "core/linalg.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

namespace navtwin {

SymmetricEigen SymmetricEigenDecomposition(const Eigen::MatrixXd& A) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A);
  return {eig.eigenvalues(), eig.eigenvectors()};
}

Eigen::VectorXd LeastSquaresColPivQr(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) {
  return A.colPivHouseholderQr().solve(b);
}

}  // namespace navtwin
