// Problem-agnostic driver for batch (nonlinear least-squares) problems: Ceres solver
// options, one progress line per iteration, and covariance extraction in the tangent
// space of each parameter block's manifold (for an attitude with AttitudeManifold, the
// covariance of the attitude error phi_n in rad^2, see docs/attitude-error.md).
//
// The covariance is the inverse of J^T J at the current parameter values, which is the
// estimator covariance only if every residual is whitened (unit covariance).
#pragma once

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <ceres/problem.h>
#include <Eigen/Core>

namespace navtwin {

struct BatchOptions {
  enum class LinearSolver {
    kAuto,                   ///< kDenseQr up to dense_max_tangent_size parameters, else sparse
    kSparseNormalCholesky,   ///< SuiteSparse (Eigen's sparse Cholesky if Ceres lacks SuiteSparse)
    kDenseQr,
  };
  int max_iterations = 100;
  int num_threads = 1;
  double function_tolerance = 1e-10;   ///< |cost change| / cost
  double gradient_tolerance = 1e-12;   ///< max-norm of the projected gradient
  double parameter_tolerance = 1e-10;  ///< |step| / (|x| + parameter_tolerance)
  LinearSolver linear_solver = LinearSolver::kAuto;
  int dense_max_tangent_size = 100;    ///< kAuto threshold on the sum of tangent sizes
  bool progress = true;                ///< print one line per iteration to the given stream
};

struct BatchReport {
  bool converged = false;   ///< Ceres stopped on a convergence criterion
  int iterations = 0;       ///< iterations after iteration 0 (the start): progress lines - 1
  double initial_cost = 0.0;
  double final_cost = 0.0;  ///< Ceres cost, 1/2 sum of squared (whitened) residuals
  double run_time_s = 0.0;
  std::string brief_report; ///< ceres::Solver::Summary::BriefReport()
};

/// Solves the problem in place. Progress (when options.progress and progress != nullptr):
/// one line per iteration, iteration 0 included:
///   "batch iter <k> cost <c> cost_change <dc> |gradient| <g> elapsed_s <t>"
/// Throws std::invalid_argument when the options are not valid for Ceres.
BatchReport SolveBatch(ceres::Problem& problem, const BatchOptions& options, std::ostream* progress);

struct CovarianceOptions {
  enum class Algorithm {
    kAuto,      ///< kDenseSvd up to dense_max_tangent_size free tangent parameters, else kSparseQr
    kSparseQr,  ///< scales to large problems; fails when QR finds J rank deficient (a numeric
                ///< rank test: a column that is tiny but not negligible next to the others passes)
    kDenseSvd,  ///< fails when sigma_min / sigma_max of J < sqrt(min_reciprocal_condition_number)
  };
  Algorithm algorithm = Algorithm::kAuto;
  int dense_max_tangent_size = 200;
  double min_reciprocal_condition_number = 1e-14;  ///< on eigenvalues of J^T J
  int num_threads = 1;
  /// After a failure the null space of J^T J is found by a dense eigen-decomposition,
  /// only when the free tangent parameters number at most this (O(n^3) time, O(n^2) memory).
  int max_diagnosis_tangent_size = 1000;
};

struct CovarianceResult {
  /// Joint tangent-space covariance of the requested blocks, in their order (each block
  /// contributes its tangent size); empty when the blocks are not all observable.
  std::optional<Eigen::MatrixXd> covariance;
  /// On failure: what failed and which blocks are unobservable; empty on success.
  std::string message;
  /// Indices (into the requested blocks) of the blocks with a component in the null space.
  std::vector<int> unobservable_blocks;
  /// Null-space directions of J^T J (columns, unit length over all free parameters),
  /// restricted to the rows of the requested blocks' tangent coordinates.
  Eigen::MatrixXd null_space;
};

/// Tangent-space covariance of several blocks (joint, with cross terms). A constant block
/// has zero covariance. Fails (no covariance; message, unobservable_blocks, null_space
/// filled) when Ceres finds J rank deficient, or when a requested coordinate's variance
/// inflation H_ii * P_ii (H = J^T J, unit free, >= 1) exceeds 1 / min_reciprocal_condition_number,
/// which catches nearly collinear columns that sparse QR's rank test lets through (not a
/// column that is merely tiny next to the others: dense SVD, kAuto's choice for small
/// problems, catches that one).
/// Throws std::invalid_argument for no block, a block not in the problem, or one requested twice.
CovarianceResult ComputeTangentCovariance(ceres::Problem& problem, const std::vector<const double*>& blocks,
                                          const CovarianceOptions& options = CovarianceOptions());

/// The covariance of one block in its tangent space; std::nullopt when it is not observable.
std::optional<Eigen::MatrixXd> TangentCovariance(ceres::Problem& problem, const double* block);

/// Joint tangent covariance of several blocks; std::nullopt when any is not observable.
std::optional<Eigen::MatrixXd> TangentCovariance(ceres::Problem& problem, const std::vector<const double*>& blocks);

// ---------------------------------------------------------------------------------------
// Per-block (diagonal-block) covariance of large problems

struct BlockCovarianceOptions {
  enum class Algorithm {
    /// Sparse LDL^T of the Jacobi-scaled normal matrix H = J^T J (Eigen, AMD ordering)
    /// followed by selected inversion (Takahashi et al. 1973; Erisman and Tinney 1975):
    /// the entries of H^-1 on the pattern of L + L^T from
    ///   Z_jj = 1/d_j - sum_{k in L_j} l_kj Z_kj,   Z_ij = -sum_{k in L_j} l_kj Z_ik (i in L_j),
    /// backwards over j (L_j = rows below the diagonal of column j of L). Its cost is that of
    /// the factorisation (linear in the number of states for a chain of states).
    kSelectedInversion,
    /// ceres::Covariance with SPARSE_QR and only the pairs (block, block). Ceres solves
    /// R^T R x = e_i for every column, so the time grows with the square of the problem
    /// size (a chain of states of 15 parameters: 6 s for 600 states, 16 s for 1200, where
    /// kSelectedInversion takes 0.17 s and 0.4 s): for small problems and checks.
    kSparseQr,
  };
  Algorithm algorithm = Algorithm::kSelectedInversion;
  /// A tangent coordinate whose variance inflation H_ii * P_ii (unit free, >= 1) exceeds
  /// 1 / min_reciprocal_condition_number is numerically unobservable: its block gets no
  /// covariance. (kSelectedInversion fails as a whole when a pivot of the LDL^T is not
  /// positive; kSparseQr when QR finds J rank deficient.)
  double min_reciprocal_condition_number = 1e-14;
  int num_threads = 1;  ///< Jacobian evaluation and ceres::Covariance
};

struct BlockCovarianceResult {
  /// Per requested block, in order: its covariance with itself in its tangent space
  /// (tangent size square; zero for a constant block), or std::nullopt when not computable.
  std::vector<std::optional<Eigen::MatrixXd>> covariances;
  /// Empty when every block has its covariance; otherwise what failed (rank deficiency,
  /// which blocks).
  std::string message;
  double run_time_s = 0.0;  ///< wall time of the whole computation
};

/// The diagonal blocks of the tangent-space covariance (J^T J)^-1 at the current parameter
/// values: each requested block with itself, never the cross terms (the joint covariance
/// of a long trajectory would not fit in memory). Cheap for problems of tens of thousands
/// of parameters with kSelectedInversion. As for ComputeTangentCovariance, this is the
/// estimator covariance only when every residual is whitened. With loss functions J is the
/// Jacobian of the robustified residuals, as Ceres evaluates it (and ceres::Covariance uses).
/// Throws std::invalid_argument for no block, a block not in the problem, or one requested twice.
BlockCovarianceResult ComputeBlockDiagonalCovariance(ceres::Problem& problem,
                                                     const std::vector<const double*>& blocks,
                                                     const BlockCovarianceOptions& options = BlockCovarianceOptions());

// ---------------------------------------------------------------------------------------
// Leverages of residual rows (redundancy numbers)

struct LeverageResult {
  /// Per requested residual block, in order: the leverage of each of its rows; all empty
  /// when the inverse could not be computed.
  std::vector<Eigen::VectorXd> leverages;
  std::string message;  ///< why it failed; empty on success
  double run_time_s = 0.0;
};

/// The leverage of every row i of the requested residual blocks, h_i = J_i (J^T J)^-1 J_i^T,
/// J the Jacobian of all residual blocks over the free tangent parameters at the current
/// values (robustified where a block has a loss, as Ceres evaluates it), by selected
/// inversion (solvers/selected_inversion.h). For whitened residuals 0 <= h_i <= 1, 1 - h_i
/// is the row's redundancy number (Foerstner 1979), and the leverages of all rows of the
/// problem sum to the number of free tangent parameters. A block with no free parameter
/// has leverages 0. Throws std::invalid_argument for a block not in the problem.
LeverageResult ComputeResidualLeverages(ceres::Problem& problem, const std::vector<ceres::ResidualBlockId>& blocks,
                                        int num_threads = 1);

}  // namespace navtwin
