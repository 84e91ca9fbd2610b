// Entries of the inverse of a sparse normal matrix H = J^T J on the pattern of its filled
// Cholesky factor, without forming the inverse (selected inversion: Takahashi, Fagan and
// Chen 1973; Erisman and Tinney 1975).
//
// H is Jacobi-scaled, Hs = S H S with S = diag(1 / sqrt(H_ii)), factored Hs = P^T L D L^T P
// (Eigen's SimplicialLDLT), and Z = Hs^-1 computed on the pattern of L + L^T backwards over
// the columns j. P keeps each dense block's columns together and orders the blocks by
// approximate minimum degree on their graph; the upper triangle of P H P^T is assembled
// from the rows of J on the blocks' pattern (every pair of blocks that share a row of J
// dense) and factored in place: J^T J itself is never formed.
//   Z_jj = 1/d_j - sum_{k in L_j} l_kj Z_kj,   Z_ij = -sum_{k in L_j} l_kj Z_ik (i in L_j),
// L_j the rows below the diagonal of column j. (H^-1)_ab = S_a S_b Z_ab. The cost is that of
// the factorisation: linear in the number of states for a chain of states.
//
// Every pair of columns that share a row of J is an entry of H, hence on the pattern: the
// covariance of any residual block's parameters, and so its leverage J_i H^-1 J_i^T, is
// available. So are the diagonal blocks the caller makes dense (dense_blocks below).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace ceres {
struct CRSMatrix;
}  // namespace ceres

namespace navtwin {

class SelectedInverse {
 public:
  /// Factors J^T J of the sparse Jacobian (rows x tangent columns) and inverts it on the
  /// pattern. dense_blocks: (first column, size) of column ranges whose square is added to
  /// the pattern (each parameter block's own covariance). Returns an empty string on
  /// success, else why it failed (a zero or non-finite column, a non-positive pivot: J rank
  /// deficient); after a failure no entry may be read.
  std::string Compute(const ceres::CRSMatrix& jacobian, const std::vector<std::pair<int, int>>& dense_blocks);

  int size() const { return static_cast<int>(scale_.size()); }
  /// (J^T J)^-1 entry (a, b) in the Jacobian's column order; NaN when off the pattern.
  double Inverse(int a, int b) const;
  /// Variance inflation H_aa (H^-1)_aa of column a (unit free, >= 1).
  double Inflation(int a) const { return z_diag_[perm_(a)]; }

 private:
  void InvertOnPattern(const Eigen::VectorXd& d);
  double Z(int p, int q) const;  ///< Zs in the permuted indices, NaN off the pattern
  int Find(int row, int column) const;

  Eigen::VectorXd scale_;  ///< S
  Eigen::VectorXi perm_;   ///< perm_(a): index in the factored matrix of column a
  // The strict lower triangle of L by columns, rows increasing; z_offdiag_ aligned with it.
  std::vector<int> start_;
  std::vector<int> rows_;
  std::vector<double> values_;
  std::vector<double> z_diag_;
  std::vector<double> z_offdiag_;
};

}  // namespace navtwin
