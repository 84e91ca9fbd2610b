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

/// True when every dense block's square is already on the pattern of H (as when one row of
/// J touches all of a block's columns).
bool HasDenseBlocks(const Eigen::SparseMatrix<double>& H, const std::vector<std::pair<int, int>>& dense_blocks) {
  for (const auto& [first, size] : dense_blocks) {
    for (int c = first; c < first + size; ++c) {
      int inside = 0;
      for (Eigen::SparseMatrix<double>::InnerIterator it(H, c); it; ++it) {
        inside += it.row() >= first && it.row() < first + size;
      }
      if (inside != size) return false;
    }
  }
  return true;
}

/// H = J^T J, plus explicit zeros that make each dense block's square part of the pattern
/// where it is not already.
Eigen::SparseMatrix<double> NormalMatrix(const ceres::CRSMatrix& crs,
                                         const std::vector<std::pair<int, int>>& dense_blocks) {
  const Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor>> J(
      crs.num_rows, crs.num_cols, static_cast<Eigen::Index>(crs.values.size()), crs.rows.data(), crs.cols.data(),
      crs.values.data());
  Eigen::SparseMatrix<double> H = Eigen::SparseMatrix<double>(J.transpose()) * J;
  if (HasDenseBlocks(H, dense_blocks)) return H;
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

/// The elimination order of the columns: approximate minimum degree (Amestoy, Davis and
/// Duff 1996) on the graph of the blocks (each dense block one node, every other column
/// its own), each block's columns kept together. Returns P with P.indices()(a) the
/// position of column a in the order. Ordering the block graph, not the columns, keeps the
/// work and memory of the ordering small beside the factorisation.
Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> BlockOrdering(
    const ceres::CRSMatrix& crs, const std::vector<std::pair<int, int>>& dense_blocks) {
  const int n = crs.num_cols;
  std::vector<int> block_of(n, -1);
  std::vector<int> first_col, size;
  for (const auto& [first, cols] : dense_blocks) {
    for (int c = first; c < first + cols; ++c) block_of[c] = static_cast<int>(first_col.size());
    first_col.push_back(first);
    size.push_back(cols);
  }
  for (int c = 0; c < n; ++c) {
    if (block_of[c] >= 0) continue;
    block_of[c] = static_cast<int>(first_col.size());
    first_col.push_back(c);
    size.push_back(1);
  }
  const int nb = static_cast<int>(first_col.size());
  // Block pairs sharing a row of J; the rows of one residual block repeat their set.
  std::vector<Eigen::Triplet<double>> edges;
  std::vector<int> row_blocks, previous;
  for (int r = 0; r < crs.num_rows; ++r) {
    row_blocks.clear();
    for (int a = crs.rows[r]; a < crs.rows[r + 1]; ++a) row_blocks.push_back(block_of[crs.cols[a]]);
    std::sort(row_blocks.begin(), row_blocks.end());
    row_blocks.erase(std::unique(row_blocks.begin(), row_blocks.end()), row_blocks.end());
    if (row_blocks == previous) continue;
    for (std::size_t i = 0; i < row_blocks.size(); ++i) {
      for (std::size_t j = 0; j < row_blocks.size(); ++j) edges.emplace_back(row_blocks[i], row_blocks[j], 1.0);
    }
    previous = row_blocks;
  }
  for (int b = 0; b < nb; ++b) edges.emplace_back(b, b, 1.0);
  Eigen::SparseMatrix<double> graph(nb, nb);
  graph.setFromTriplets(edges.begin(), edges.end());
  edges.clear();
  edges.shrink_to_fit();
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order;  // order.indices()(k): k-th block eliminated
  Eigen::AMDOrdering<int>()(graph, order);
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> P(n);
  int next = 0;
  for (int k = 0; k < nb; ++k) {
    const int b = order.indices()(k);
    for (int c = first_col[b]; c < first_col[b] + size[b]; ++c) P.indices()(c) = next++;
  }
  return P;
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
  // Permuted to the block elimination order, upper triangle only, with Eigen::Index
  // indices: with those (and NaturalOrdering<Eigen::Index>) the factorisation reads the
  // matrix in place instead of copying it for an ordering and a transposition.
  using IndexMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, Eigen::Index>;
  const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> P = BlockOrdering(jacobian, dense_blocks);
  IndexMatrix Hp;
  {
    Eigen::SparseMatrix<double> upper(n, n);
    upper.selfadjointView<Eigen::Upper>() = H.selfadjointView<Eigen::Upper>().twistedBy(P);
    Eigen::SparseMatrix<double>().swap(H);  // freed (assigning an empty matrix keeps the storage)
    Hp = upper;
  }
  Eigen::VectorXd d;
  {
    Eigen::SimplicialLDLT<IndexMatrix, Eigen::Upper, Eigen::NaturalOrdering<Eigen::Index>> ldlt(Hp);
    if (ldlt.info() != Eigen::Success) return "the LDL^T factorisation failed (J rank deficient)";
    // A pivot that is not positive: J^T J is singular (or indefinite by rounding). A tiny
    // positive one shows as a large variance inflation of the columns it touches.
    d = ldlt.vectorD();
    for (int j = 0; j < n; ++j) {
      if (!(d(j) > 0.0) || !std::isfinite(d(j))) {
        std::ostringstream text;
        text << "J is rank deficient (LDL^T pivot " << d(j) << " of the Jacobi-scaled J^T J)";
        return text.str();
      }
    }
    perm_ = P.indices();

    const IndexMatrix& factor = ldlt.matrixL().nestedExpression();
    start_.assign(n + 1, 0);
    rows_.clear();
    values_.clear();
    rows_.reserve(static_cast<std::size_t>(factor.nonZeros()));
    values_.reserve(static_cast<std::size_t>(factor.nonZeros()));
    std::vector<std::pair<int, double>> column;
    for (int j = 0; j < n; ++j) {
      column.clear();
      for (IndexMatrix::InnerIterator it(factor, j); it; ++it) {
        if (it.row() > j) column.emplace_back(static_cast<int>(it.row()), it.value());
      }
      std::sort(column.begin(), column.end());
      for (const auto& entry : column) {
        rows_.push_back(entry.first);
        values_.push_back(entry.second);
      }
      start_[j + 1] = static_cast<int>(rows_.size());
    }
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
