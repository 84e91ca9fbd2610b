#include "solvers/selected_inversion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <ceres/crs_matrix.h>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

namespace navtwin {
namespace {

/// H = J^T J plus explicit zeros that make each dense block's square part of the pattern.
Eigen::SparseMatrix<double> NormalMatrix(const ceres::CRSMatrix& crs,
                                         const std::vector<std::pair<int, int>>& dense_blocks) {
  const Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor>> J(
      crs.num_rows, crs.num_cols, static_cast<Eigen::Index>(crs.values.size()), crs.rows.data(), crs.cols.data(),
      crs.values.data());
  Eigen::SparseMatrix<double> H = Eigen::SparseMatrix<double>(J.transpose()) * J;
  std::vector<Eigen::Triplet<double>> pattern;
  for (const auto& [first, size] : dense_blocks) {
    for (int r = 0; r < size; ++r) {
      for (int c = 0; c < size; ++c) pattern.emplace_back(first + r, first + c, 0.0);
    }
  }
  Eigen::SparseMatrix<double> P(crs.num_cols, crs.num_cols);
  P.setFromTriplets(pattern.begin(), pattern.end());
  H = Eigen::SparseMatrix<double>(H + P);
  H.makeCompressed();
  return H;
}

}  // namespace

std::string SelectedInverse::Compute(const ceres::CRSMatrix& jacobian,
                                     const std::vector<std::pair<int, int>>& dense_blocks) {
  const int n = jacobian.num_cols;
  Eigen::SparseMatrix<double> H = NormalMatrix(jacobian, dense_blocks);

  // Jacobi scaling: unit diagonal, so the pivots of the LDL^T lie in (0, 1] and the
  // variance inflation of column a is Zs_aa.
  scale_.resize(n);
  for (int i = 0; i < n; ++i) {
    const double hii = H.coeff(i, i);
    if (!(hii > 0.0) || !std::isfinite(hii)) {
      std::ostringstream text;
      text << "tangent column " << i << " of the Jacobian is zero or not finite";
      return text.str();
    }
    scale_(i) = 1.0 / std::sqrt(hii);
  }
  for (int k = 0; k < H.outerSize(); ++k) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(H, k); it; ++it) {
      it.valueRef() *= scale_(it.row()) * scale_(it.col());
    }
  }
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt(H);
  if (ldlt.info() != Eigen::Success) return "the LDL^T factorisation failed (J rank deficient)";
  // A pivot that is not positive: J^T J is singular (or indefinite by rounding). A tiny
  // positive one shows as a large variance inflation of the columns it touches.
  const Eigen::VectorXd d = ldlt.vectorD();
  for (int j = 0; j < n; ++j) {
    if (!(d(j) > 0.0) || !std::isfinite(d(j))) {
      std::ostringstream text;
      text << "J is rank deficient (LDL^T pivot " << d(j) << " of the Jacobi-scaled J^T J)";
      return text.str();
    }
  }
  perm_ = ldlt.permutationP().indices();

  const Eigen::SparseMatrix<double> factor = ldlt.matrixL().nestedExpression();
  start_.assign(n + 1, 0);
  rows_.clear();
  values_.clear();
  std::vector<std::pair<int, double>> column;
  for (int j = 0; j < n; ++j) {
    column.clear();
    for (Eigen::SparseMatrix<double>::InnerIterator it(factor, j); it; ++it) {
      if (it.row() > j) column.emplace_back(static_cast<int>(it.row()), it.value());
    }
    std::sort(column.begin(), column.end());
    for (const auto& entry : column) {
      rows_.push_back(entry.first);
      values_.push_back(entry.second);
    }
    start_[j + 1] = static_cast<int>(rows_.size());
  }

  // Backwards over the columns. For column j with rows r_1 < ... < r_m every entry
  // Z_{r_a r_b} needed lies in column min(r_a, r_b) of the pattern (the rows of a column of
  // L form a clique of the filled graph), so iterating column r_b of Z and keeping the rows
  // marked as belonging to column j finds them all.
  z_diag_.assign(n, 0.0);
  z_offdiag_.assign(values_.size(), 0.0);
  std::vector<int> position(n, -1);  // position[r] = entry index in column j, -1 if absent
  for (int j = n - 1; j >= 0; --j) {
    const int begin = start_[j], end = start_[j + 1];
    for (int a = begin; a < end; ++a) position[rows_[a]] = a;
    for (int b = begin; b < end; ++b) {
      const int c = rows_[b];
      const double l_b = values_[b];
      z_offdiag_[b] -= z_diag_[c] * l_b;
      for (int e = start_[c]; e < start_[c + 1]; ++e) {
        const int a = position[rows_[e]];
        if (a < 0) continue;
        // Z_{r_a c} = Z_{c r_a} with r_a > c enters Z_{r_a j} (through l_cj) and Z_{c j}
        // (through l_{r_a j}).
        z_offdiag_[a] -= z_offdiag_[e] * l_b;
        z_offdiag_[b] -= z_offdiag_[e] * values_[a];
      }
    }
    double diag = 1.0 / d(j);
    for (int a = begin; a < end; ++a) {
      diag -= values_[a] * z_offdiag_[a];
      position[rows_[a]] = -1;
    }
    z_diag_[j] = diag;
  }
  return {};
}

int SelectedInverse::Find(int row, int column) const {
  const auto first = rows_.begin() + start_[column];
  const auto last = rows_.begin() + start_[column + 1];
  const auto it = std::lower_bound(first, last, row);
  return (it != last && *it == row) ? static_cast<int>(it - rows_.begin()) : -1;
}

double SelectedInverse::Z(int p, int q) const {
  if (p == q) return z_diag_[p];
  const int e = p > q ? Find(p, q) : Find(q, p);
  return e >= 0 ? z_offdiag_[e] : std::numeric_limits<double>::quiet_NaN();
}

double SelectedInverse::Inverse(int a, int b) const { return scale_(a) * scale_(b) * Z(perm_(a), perm_(b)); }

}  // namespace navtwin
