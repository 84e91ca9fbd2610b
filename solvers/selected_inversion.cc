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

using IndexMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, Eigen::Index>;

/// The columns in blocks: the dense blocks, every other column a block of its own.
struct ColumnBlocks {
  std::vector<int> block_of;    ///< per column
  std::vector<int> first, size;  ///< per block
  std::vector<int> position;     ///< per block: its place in the elimination order
  std::vector<int> new_first;    ///< per block: its first column in the permuted matrix
  std::vector<std::vector<int>> adjacent;  ///< per block: the blocks sharing a row of J with it (itself included), sorted
};

ColumnBlocks MakeBlocks(int n, const std::vector<std::pair<int, int>>& dense_blocks) {
  ColumnBlocks b;
  b.block_of.assign(n, -1);
  for (const auto& [first, cols] : dense_blocks) {
    for (int c = first; c < first + cols; ++c) b.block_of[c] = static_cast<int>(b.first.size());
    b.first.push_back(first);
    b.size.push_back(cols);
  }
  for (int c = 0; c < n; ++c) {
    if (b.block_of[c] >= 0) continue;
    b.block_of[c] = static_cast<int>(b.first.size());
    b.first.push_back(c);
    b.size.push_back(1);
  }
  return b;
}

/// ColumnBlocks::adjacent from the rows of J (the rows of one residual block repeat their
/// set of blocks: each set is added once).
void FindAdjacentBlocks(const ceres::CRSMatrix& crs, ColumnBlocks* b) {
  b->adjacent.assign(b->first.size(), {});
  for (std::size_t k = 0; k < b->first.size(); ++k) b->adjacent[k].push_back(static_cast<int>(k));
  std::vector<int> row_blocks, previous;
  for (int r = 0; r < crs.num_rows; ++r) {
    row_blocks.clear();
    for (int a = crs.rows[r]; a < crs.rows[r + 1]; ++a) row_blocks.push_back(b->block_of[crs.cols[a]]);
    std::sort(row_blocks.begin(), row_blocks.end());
    row_blocks.erase(std::unique(row_blocks.begin(), row_blocks.end()), row_blocks.end());
    if (row_blocks == previous) continue;
    for (int x : row_blocks) {
      std::vector<int>& adjacent = b->adjacent[static_cast<std::size_t>(x)];
      adjacent.insert(adjacent.end(), row_blocks.begin(), row_blocks.end());
    }
    previous = row_blocks;
  }
  for (std::vector<int>& adjacent : b->adjacent) {
    std::sort(adjacent.begin(), adjacent.end());
    adjacent.erase(std::unique(adjacent.begin(), adjacent.end()), adjacent.end());
  }
}

/// The elimination order: approximate minimum degree (Amestoy, Davis and Duff 1996) on the
/// graph of the blocks, each block's columns kept together (ColumnBlocks::position and
/// new_first). Ordering the block graph, not the columns, keeps the work and memory of the
/// ordering small beside the factorisation.
void OrderBlocks(ColumnBlocks* b) {
  const int nb = static_cast<int>(b->first.size());
  Eigen::SparseMatrix<double> graph(nb, nb);
  Eigen::VectorXi per_column(nb);
  for (int k = 0; k < nb; ++k) per_column(k) = static_cast<int>(b->adjacent[static_cast<std::size_t>(k)].size());
  graph.reserve(per_column);
  for (int k = 0; k < nb; ++k) {
    for (int x : b->adjacent[static_cast<std::size_t>(k)]) graph.insert(x, k) = 1.0;
  }
  graph.makeCompressed();
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order;  // order.indices()(k): k-th block eliminated
  Eigen::AMDOrdering<int>()(graph, order);
  b->position.assign(nb, 0);
  b->new_first.assign(nb, 0);
  int next = 0;
  for (int k = 0; k < nb; ++k) {
    const int block = order.indices()(k);
    b->position[static_cast<std::size_t>(block)] = k;
    b->new_first[static_cast<std::size_t>(block)] = next;
    next += b->size[static_cast<std::size_t>(block)];
  }
}

/// The upper triangle of P J^T J P^T (P: the block order) on the block pattern (every pair
/// of adjacent blocks dense, so each block's own square is on it), assembled from the
/// rows of J without forming J^T J: entry (min(p_a, p_b), max(p_a, p_b)) gathers
/// J_ra J_rb over the rows r, p_a the permuted index of column a.
IndexMatrix PermutedNormalUpper(const ceres::CRSMatrix& crs, const ColumnBlocks& b, std::vector<int>* new_index) {
  const int n = crs.num_cols;
  new_index->assign(n, 0);
  for (int c = 0; c < n; ++c) {
    const int block = b.block_of[c];
    (*new_index)[c] = b.new_first[static_cast<std::size_t>(block)] + c - b.first[static_cast<std::size_t>(block)];
  }
  // Pattern: column j of block B holds the columns of the adjacent blocks earlier in the
  // order, then B's own columns up to j.
  std::vector<int> block_at(n);  // permuted column -> block
  for (std::size_t k = 0; k < b.first.size(); ++k) {
    for (int i = 0; i < b.size[k]; ++i) block_at[b.new_first[k] + i] = static_cast<int>(k);
  }
  // Per block, the adjacent blocks earlier in the order, by position: the same for each of
  // its columns, so found once.
  std::vector<std::vector<int>> earlier(b.first.size());
  for (std::size_t k = 0; k < b.first.size(); ++k) {
    std::vector<std::pair<int, int>> by_position;  // (position, block)
    for (int x : b.adjacent[k]) {
      const int position = b.position[static_cast<std::size_t>(x)];
      if (position < b.position[k]) by_position.emplace_back(position, x);
    }
    std::sort(by_position.begin(), by_position.end());
    for (const auto& [position, x] : by_position) earlier[k].push_back(x);
  }
  IndexMatrix H(n, n);
  Eigen::Index nnz = 0;
  for (int pass = 0; pass < 2; ++pass) {
    nnz = 0;
    for (int j = 0; j < n; ++j) {
      const auto block = static_cast<std::size_t>(block_at[j]);
      if (pass == 1) H.outerIndexPtr()[j] = nnz;
      for (int x : earlier[block]) {
        for (int i = 0; i < b.size[static_cast<std::size_t>(x)]; ++i) {
          if (pass == 1) H.innerIndexPtr()[nnz] = b.new_first[static_cast<std::size_t>(x)] + i;
          ++nnz;
        }
      }
      for (int i = b.new_first[block]; i <= j; ++i) {
        if (pass == 1) H.innerIndexPtr()[nnz] = i;
        ++nnz;
      }
    }
    if (pass == 0) H.resizeNonZeros(nnz);
  }
  H.outerIndexPtr()[n] = nnz;
  std::fill(H.valuePtr(), H.valuePtr() + nnz, 0.0);

  std::vector<std::pair<int, double>> row;  // (permuted column, value), by column
  for (int r = 0; r < crs.num_rows; ++r) {
    row.clear();
    for (int a = crs.rows[r]; a < crs.rows[r + 1]; ++a) row.emplace_back((*new_index)[crs.cols[a]], crs.values[a]);
    std::sort(row.begin(), row.end());
    for (std::size_t l = 0; l < row.size(); ++l) {
      const int j = row[l].first;
      const Eigen::Index* begin = H.innerIndexPtr() + H.outerIndexPtr()[j];
      const Eigen::Index* end = H.innerIndexPtr() + H.outerIndexPtr()[j + 1];
      const Eigen::Index* at = begin;
      for (std::size_t k = 0; k <= l; ++k) {
        at = std::lower_bound(at, end, static_cast<Eigen::Index>(row[k].first));
        H.valuePtr()[at - H.innerIndexPtr()] += row[k].second * row[l].second;
      }
    }
  }
  return H;
}

/// Jacobi scaling of the permuted H in place: unit diagonal, so the pivots of the LDL^T lie
/// in (0, 1] and the variance inflation of column a is Zs_aa. *scale: S in the Jacobian's
/// column order (perm(a): the permuted index of column a). Returns why it failed, or "".
std::string JacobiScale(const Eigen::VectorXi& perm, IndexMatrix* Hp, Eigen::VectorXd* scale) {
  const int n = static_cast<int>(Hp->cols());
  Eigen::VectorXd scale_permuted(n);
  for (int j = 0; j < n; ++j) {
    const double hjj = Hp->valuePtr()[Hp->outerIndexPtr()[j + 1] - 1];  // each column's last entry
    if (!(hjj > 0.0) || !std::isfinite(hjj)) {
      int column = 0;
      while (perm(column) != j) ++column;
      std::ostringstream text;
      text << "tangent column " << column << " of the Jacobian is zero or not finite";
      return text.str();
    }
    scale_permuted(j) = 1.0 / std::sqrt(hjj);
  }
  for (int j = 0; j < n; ++j) {
    for (IndexMatrix::InnerIterator it(*Hp, j); it; ++it) it.valueRef() *= scale_permuted(it.row()) * scale_permuted(j);
  }
  scale->resize(n);
  for (int a = 0; a < n; ++a) (*scale)(a) = scale_permuted(perm(a));
  return {};
}

}  // namespace

std::string SelectedInverse::Compute(const ceres::CRSMatrix& jacobian,
                                     const std::vector<std::pair<int, int>>& dense_blocks) {
  const int n = jacobian.num_cols;
  ColumnBlocks blocks = MakeBlocks(n, dense_blocks);
  FindAdjacentBlocks(jacobian, &blocks);
  OrderBlocks(&blocks);
  std::vector<int> new_index;
  // The permuted upper triangle with Eigen::Index indices: with those (and
  // NaturalOrdering<Eigen::Index>) the factorisation reads it in place instead of copying
  // it for an ordering and a transposition.
  IndexMatrix Hp = PermutedNormalUpper(jacobian, blocks, &new_index);
  perm_ = Eigen::Map<const Eigen::VectorXi>(new_index.data(), n);

  const std::string failure = JacobiScale(perm_, &Hp, &scale_);
  if (!failure.empty()) return failure;

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

  InvertOnPattern(d);
  return {};
}

/// Z on the pattern of L + L^T from L (start_, rows_, values_) and the pivots d.
void SelectedInverse::InvertOnPattern(const Eigen::VectorXd& d) {
  const int n = static_cast<int>(d.size());
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
