#include "solvers/batch_driver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/covariance.h>
#include <ceres/crs_matrix.h>
#include <ceres/iteration_callback.h>
#include <ceres/solver.h>

#include "core/linalg.h"
#include "solvers/selected_inversion.h"

namespace navtwin {
namespace {

/// Writes one line per minimizer iteration (iteration 0 = the initial point).
class ProgressPrinter final : public ceres::IterationCallback {
 public:
  explicit ProgressPrinter(std::ostream& out) : out_(out) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    std::ostringstream line;  // formatted apart so that the caller's stream flags are untouched
    line.precision(6);
    line << "batch iter " << s.iteration << " cost " << std::scientific << s.cost << " cost_change "
         << s.cost_change << " |gradient| " << s.gradient_norm << std::fixed << " elapsed_s "
         << s.cumulative_time_in_seconds << '\n';
    out_ << line.str() << std::flush;
    return ceres::SOLVER_CONTINUE;
  }

 private:
  std::ostream& out_;
};

int TotalTangentSize(const ceres::Problem& problem) {
  std::vector<double*> blocks;
  problem.GetParameterBlocks(&blocks);
  int size = 0;
  for (const double* block : blocks) size += problem.ParameterBlockTangentSize(block);
  return size;
}

ceres::Solver::Options MakeSolverOptions(const ceres::Problem& problem, const BatchOptions& options) {
  ceres::Solver::Options solver;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = options.num_threads;
  solver.function_tolerance = options.function_tolerance;
  solver.gradient_tolerance = options.gradient_tolerance;
  solver.parameter_tolerance = options.parameter_tolerance;
  solver.minimizer_progress_to_stdout = false;
  solver.logging_type = ceres::SILENT;

  BatchOptions::LinearSolver choice = options.linear_solver;
  if (choice == BatchOptions::LinearSolver::kAuto) {
    choice = TotalTangentSize(problem) <= options.dense_max_tangent_size
                 ? BatchOptions::LinearSolver::kDenseQr
                 : BatchOptions::LinearSolver::kSparseNormalCholesky;
  }
  if (choice == BatchOptions::LinearSolver::kDenseQr) {
    solver.linear_solver_type = ceres::DENSE_QR;
  } else {
    solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    solver.sparse_linear_algebra_library_type =
        ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ? ceres::SUITE_SPARSE
                                                                                : ceres::EIGEN_SPARSE;
  }
  return solver;
}

void CheckBlocks(const ceres::Problem& problem, const std::vector<const double*>& blocks) {
  if (blocks.empty()) throw std::invalid_argument("TangentCovariance: no parameter block requested");
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    if (!problem.HasParameterBlock(blocks[i])) {
      throw std::invalid_argument("TangentCovariance: block " + std::to_string(i) + " is not in the problem");
    }
    if (std::find(blocks.begin(), blocks.begin() + i, blocks[i]) != blocks.begin() + i) {
      throw std::invalid_argument("TangentCovariance: block " + std::to_string(i) + " requested twice");
    }
  }
}

/// The tangent-space Jacobian of the free (non-constant) parameter blocks at the current
/// parameter values.
struct TangentJacobian {
  std::vector<double*> blocks;  ///< free blocks, in column order
  std::vector<int> offsets;     ///< first column of each free block
  ceres::CRSMatrix crs;

  /// First column of a block, or -1 for a constant block.
  int Column(const double* block) const {
    const auto it = std::find(blocks.begin(), blocks.end(), block);
    return it == blocks.end() ? -1 : offsets[it - blocks.begin()];
  }
};

bool EvaluateTangentJacobian(ceres::Problem& problem, int num_threads, TangentJacobian* jacobian) {
  std::vector<double*> all;
  problem.GetParameterBlocks(&all);
  int columns = 0;
  for (double* block : all) {
    if (problem.IsParameterBlockConstant(block)) continue;
    jacobian->blocks.push_back(block);
    jacobian->offsets.push_back(columns);
    columns += problem.ParameterBlockTangentSize(block);
  }
  if (jacobian->blocks.empty()) return true;  // (an empty list would mean "all blocks" to Ceres)
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = jacobian->blocks;
  evaluate.num_threads = num_threads;
  return problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &jacobian->crs);
}

/// Checks what sparse QR's rank test can miss: nearly collinear columns (J = [1 1; 1+d 1-d]
/// with d = 1e-9 passes it). Uses the variance inflation H_ii * P_ii of every requested free
/// coordinate, H = J^T J: unit free, >= 1, and 1 / (1 - R_i^2) for the collinearity R_i of
/// column i with the others; above 1 / min_reciprocal_condition_number the coordinate is
/// numerically unobservable. Returns a description of the first offending coordinate, or
/// an empty string.
std::string CheckVarianceInflation(const ceres::Problem& problem, const std::vector<const double*>& blocks,
                                   const TangentJacobian& jacobian, const Eigen::MatrixXd& covariance,
                                   double min_reciprocal_condition_number) {
  Eigen::VectorXd h = Eigen::VectorXd::Zero(jacobian.crs.num_cols);  // diagonal of J^T J
  for (std::size_t k = 0; k < jacobian.crs.values.size(); ++k) {
    h(jacobian.crs.cols[k]) += jacobian.crs.values[k] * jacobian.crs.values[k];
  }
  int row = 0;
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const int size = problem.ParameterBlockTangentSize(blocks[i]);
    const int column = jacobian.Column(blocks[i]);
    for (int j = 0; column >= 0 && j < size; ++j) {
      const double inflation = h(column + j) * covariance(row + j, row + j);
      if (!(inflation <= 1.0 / min_reciprocal_condition_number)) {
        std::ostringstream text;
        text << "variance inflation of block " << i << " tangent coordinate " << j << " is " << inflation;
        return text.str();
      }
    }
    row += size;
  }
  return std::string();
}

/// Appends to the failure message the null space of J^T J (eigenvalues at most
/// min_reciprocal_condition_number times the largest) and the requested blocks it touches.
void DiagnoseNullSpace(const ceres::Problem& problem, const std::vector<const double*>& blocks,
                       const TangentJacobian& jacobian, const CovarianceOptions& options,
                       CovarianceResult* result) {
  const ceres::CRSMatrix& crs = jacobian.crs;
  if (crs.num_cols > options.max_diagnosis_tangent_size) {
    result->message += "; null-space diagnosis skipped (" + std::to_string(crs.num_cols) +
                       " free tangent parameters > max_diagnosis_tangent_size)";
    return;
  }
  // J^T J accumulated row by row from the sparse J (memory n^2, not rows * n).
  Eigen::MatrixXd jtj = Eigen::MatrixXd::Zero(crs.num_cols, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int k1 = crs.rows[r]; k1 < crs.rows[r + 1]; ++k1) {
      for (int k2 = crs.rows[r]; k2 < crs.rows[r + 1]; ++k2) {
        jtj(crs.cols[k1], crs.cols[k2]) += crs.values[k1] * crs.values[k2];
      }
    }
  }
  const SymmetricEigen eigen = SymmetricEigenDecomposition(jtj);  // ascending eigenvalues
  const Eigen::VectorXd& lambda = eigen.values;
  const double lambda_max = lambda.size() > 0 ? lambda.maxCoeff() : 0.0;
  int null_rank = 0;
  while (null_rank < lambda.size() && lambda(null_rank) <= options.min_reciprocal_condition_number * lambda_max) {
    ++null_rank;
  }

  int rows = 0;
  for (const double* block : blocks) rows += problem.ParameterBlockTangentSize(block);
  result->null_space = Eigen::MatrixXd::Zero(rows, null_rank);
  // A block is reported when its share of the unit null vectors exceeds this: well above
  // the ~1e-16 leakage of rounding, well below any real participation.
  constexpr double kParticipation = 1e-6;
  int row = 0;
  std::ostringstream names;
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const int size = problem.ParameterBlockTangentSize(blocks[i]);
    const int column = jacobian.Column(blocks[i]);
    if (column >= 0) {  // a constant block has no null-space component
      result->null_space.middleRows(row, size) = eigen.vectors.block(column, 0, size, null_rank);
      if (null_rank > 0 && result->null_space.middleRows(row, size).norm() > kParticipation) {
        result->unobservable_blocks.push_back(static_cast<int>(i));
        names << (result->unobservable_blocks.size() > 1 ? ", " : "") << i;
      }
    }
    row += size;
  }
  std::ostringstream text;
  // Rounding in J^T J leaves eigenvalues of +-1e-16 * lambda_max where the true one is 0.
  text << "; null space of dimension " << null_rank << " (smallest/largest eigenvalue of J^T J "
       << (lambda_max > 0.0 ? std::max(0.0, lambda(0) / lambda_max) : 0.0) << ")";
  if (!result->unobservable_blocks.empty()) {
    text << "; unobservable requested blocks: " << names.str();
  } else if (null_rank > 0) {
    text << " lying in blocks that were not requested";
  }
  result->message += text.str();
}

}  // namespace

BatchReport SolveBatch(ceres::Problem& problem, const BatchOptions& options, std::ostream* progress) {
  ceres::Solver::Options solver = MakeSolverOptions(problem, options);
  std::unique_ptr<ProgressPrinter> printer;
  if (options.progress && progress != nullptr) {
    printer = std::make_unique<ProgressPrinter>(*progress);
    solver.callbacks.push_back(printer.get());
  }
  std::string error;
  if (!solver.IsValid(&error)) throw std::invalid_argument("SolveBatch: invalid options: " + error);

  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);

  BatchReport report;
  report.converged = summary.termination_type == ceres::CONVERGENCE;
  // Iteration 0 is the start. (BriefReport's count can be one more: a last step that a
  // convergence test rejects is counted there but has no IterationSummary.)
  report.iterations = std::max(0, static_cast<int>(summary.iterations.size()) - 1);
  report.initial_cost = summary.initial_cost;
  report.final_cost = summary.final_cost;
  report.run_time_s = summary.total_time_in_seconds;
  report.brief_report = summary.BriefReport();
  return report;
}

CovarianceResult ComputeTangentCovariance(ceres::Problem& problem, const std::vector<const double*>& blocks,
                                          const CovarianceOptions& options) {
  CheckBlocks(problem, blocks);
  CovarianceResult result;
  TangentJacobian jacobian;
  if (!EvaluateTangentJacobian(problem, options.num_threads, &jacobian)) {
    result.message = "covariance not computable: the problem could not be evaluated";
    return result;
  }

  ceres::Covariance::Options ceres_options;
  const bool sparse = options.algorithm == CovarianceOptions::Algorithm::kSparseQr ||
                      (options.algorithm == CovarianceOptions::Algorithm::kAuto &&
                       jacobian.crs.num_cols > options.dense_max_tangent_size);
  ceres_options.algorithm_type = sparse ? ceres::SPARSE_QR : ceres::DENSE_SVD;
  ceres_options.min_reciprocal_condition_number = options.min_reciprocal_condition_number;
  ceres_options.null_space_rank = 0;  // never a pseudo-inverse: rank deficiency is a failure
  ceres_options.num_threads = options.num_threads;
  ceres::Covariance covariance(ceres_options);
  const std::string method = sparse ? "sparse QR" : "dense SVD";
  if (!covariance.Compute(blocks, &problem)) {
    result.message = "covariance not computable (" + method + "): the Jacobian is rank deficient";
    DiagnoseNullSpace(problem, blocks, jacobian, options, &result);
    return result;
  }
  int size = 0;
  for (const double* block : blocks) size += problem.ParameterBlockTangentSize(block);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> matrix(size, size);
  if (!covariance.GetCovarianceMatrixInTangentSpace(blocks, matrix.data())) {
    result.message = "ceres::Covariance::GetCovarianceMatrixInTangentSpace failed";
    return result;
  }
  const Eigen::MatrixXd tangent_covariance = matrix;
  const std::string inflated = CheckVarianceInflation(problem, blocks, jacobian, tangent_covariance,
                                                      options.min_reciprocal_condition_number);
  if (!inflated.empty()) {
    result.message = "covariance rejected (" + method + "): " + inflated;
    DiagnoseNullSpace(problem, blocks, jacobian, options, &result);
    return result;
  }
  result.covariance = tangent_covariance;
  return result;
}

std::optional<Eigen::MatrixXd> TangentCovariance(ceres::Problem& problem, const double* block) {
  return TangentCovariance(problem, std::vector<const double*>{block});
}

std::optional<Eigen::MatrixXd> TangentCovariance(ceres::Problem& problem, const std::vector<const double*>& blocks) {
  return ComputeTangentCovariance(problem, blocks).covariance;
}

// ---------------------------------------------------------------------------------------
// ComputeBlockDiagonalCovariance

namespace {

using RowMajorBlock = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Diagonal of J^T J from the sparse tangent Jacobian.
Eigen::VectorXd NormalDiagonal(const ceres::CRSMatrix& crs) {
  Eigen::VectorXd h = Eigen::VectorXd::Zero(crs.num_cols);
  for (std::size_t k = 0; k < crs.values.size(); ++k) h(crs.cols[k]) += crs.values[k] * crs.values[k];
  return h;
}

/// First tangent column of every free block (constant blocks are absent).
std::unordered_map<const double*, int> ColumnMap(const TangentJacobian& jacobian) {
  std::unordered_map<const double*, int> map;
  for (std::size_t i = 0; i < jacobian.blocks.size(); ++i) map.emplace(jacobian.blocks[i], jacobian.offsets[i]);
  return map;
}

/// Drops the covariance of every block with a coordinate whose variance inflation
/// H_ii * P_ii exceeds 1 / min_reciprocal_condition_number (or is not finite) and names
/// them in the message.
void RejectInflated(const std::vector<Eigen::VectorXd>& inflation, double min_reciprocal_condition_number,
                    BlockCovarianceResult* result) {
  std::ostringstream names;
  int rejected = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < inflation.size(); ++i) {
    if (!result->covariances[i] || inflation[i].size() == 0) continue;
    const double max_inflation = inflation[i].maxCoeff();
    if (inflation[i].allFinite() && max_inflation <= 1.0 / min_reciprocal_condition_number) continue;
    result->covariances[i].reset();
    if (rejected < 10) names << (rejected > 0 ? ", " : "") << i;
    ++rejected;
    worst = std::isfinite(max_inflation) ? std::max(worst, max_inflation) : max_inflation;
  }
  if (rejected > 0) {
    std::ostringstream text;
    text << rejected << " block(s) numerically unobservable (variance inflation H_ii P_ii up to " << worst
         << " > 1 / min_reciprocal_condition_number): " << names.str() << (rejected > 10 ? ", ..." : "");
    result->message = text.str();
  }
}

void BlockCovarianceBySparseQr(ceres::Problem& problem, const std::vector<const double*>& blocks,
                               const TangentJacobian& jacobian, const BlockCovarianceOptions& options,
                               BlockCovarianceResult* result) {
  ceres::Covariance::Options ceres_options;
  ceres_options.algorithm_type = ceres::SPARSE_QR;
  ceres_options.min_reciprocal_condition_number = options.min_reciprocal_condition_number;
  ceres_options.null_space_rank = 0;
  ceres_options.num_threads = options.num_threads;
  ceres::Covariance covariance(ceres_options);
  std::vector<std::pair<const double*, const double*>> pairs;
  pairs.reserve(blocks.size());
  for (const double* block : blocks) pairs.emplace_back(block, block);
  if (!covariance.Compute(pairs, &problem)) {
    result->message = "covariance not computable (sparse QR): the Jacobian is rank deficient";
    return;
  }
  const Eigen::VectorXd h = NormalDiagonal(jacobian.crs);
  const std::unordered_map<const double*, int> columns = ColumnMap(jacobian);
  std::vector<Eigen::VectorXd> inflation(blocks.size());
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const int size = problem.ParameterBlockTangentSize(blocks[i]);
    RowMajorBlock block(size, size);
    if (!covariance.GetCovarianceBlockInTangentSpace(blocks[i], blocks[i], block.data())) {
      result->message = "ceres::Covariance::GetCovarianceBlockInTangentSpace failed";
      result->covariances.assign(blocks.size(), std::nullopt);
      return;
    }
    result->covariances[i] = Eigen::MatrixXd(block);
    const auto column = columns.find(blocks[i]);
    if (column != columns.end()) {
      inflation[i] = h.segment(column->second, size).cwiseProduct(block.diagonal());
    }
  }
  RejectInflated(inflation, options.min_reciprocal_condition_number, result);
}

void BlockCovarianceBySelectedInversion(ceres::Problem& problem, const std::vector<const double*>& blocks,
                                        const TangentJacobian& jacobian, const BlockCovarianceOptions& options,
                                        BlockCovarianceResult* result) {
  const std::unordered_map<const double*, int> columns = ColumnMap(jacobian);
  std::vector<std::pair<int, int>> dense;
  for (std::size_t b = 0; b < jacobian.blocks.size(); ++b) {
    dense.emplace_back(jacobian.offsets[b], problem.ParameterBlockTangentSize(jacobian.blocks[b]));
  }
  SelectedInverse inverse;
  const std::string failure = inverse.Compute(jacobian.crs, dense);
  if (!failure.empty()) {
    result->covariances.assign(blocks.size(), std::nullopt);
    result->message = "covariance not computable (selected inversion): " + failure;
    return;
  }
  std::vector<Eigen::VectorXd> inflation(blocks.size());
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const int size = problem.ParameterBlockTangentSize(blocks[i]);
    const auto column = columns.find(blocks[i]);
    if (column == columns.end()) {  // constant block
      result->covariances[i] = Eigen::MatrixXd::Zero(size, size);
      continue;
    }
    Eigen::MatrixXd block(size, size);
    inflation[i].resize(size);
    for (int r = 0; r < size; ++r) {
      for (int c = 0; c <= r; ++c) {
        block(r, c) = block(c, r) = inverse.Inverse(column->second + r, column->second + c);
      }
      inflation[i](r) = inverse.Inflation(column->second + r);
    }
    if (!block.allFinite()) {
      result->covariances.assign(blocks.size(), std::nullopt);
      result->message = "covariance not computable (selected inversion): internal error, a block entry is off "
                        "the factor's pattern";
      return;
    }
    result->covariances[i] = block;
  }
  RejectInflated(inflation, options.min_reciprocal_condition_number, result);
}

}  // namespace

BlockCovarianceResult ComputeBlockDiagonalCovariance(ceres::Problem& problem, const std::vector<const double*>& blocks,
                                                     const BlockCovarianceOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  CheckBlocks(problem, blocks);
  BlockCovarianceResult result;
  result.covariances.assign(blocks.size(), std::nullopt);
  TangentJacobian jacobian;
  if (!EvaluateTangentJacobian(problem, options.num_threads, &jacobian)) {
    result.message = "covariance not computable: the problem could not be evaluated";
  } else if (jacobian.blocks.empty()) {  // every block constant
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      const int size = problem.ParameterBlockTangentSize(blocks[i]);
      result.covariances[i] = Eigen::MatrixXd::Zero(size, size);
    }
  } else if (options.algorithm == BlockCovarianceOptions::Algorithm::kSparseQr) {
    BlockCovarianceBySparseQr(problem, blocks, jacobian, options, &result);
  } else {
    BlockCovarianceBySelectedInversion(problem, blocks, jacobian, options, &result);
  }
  result.run_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}


LeverageResult ComputeResidualLeverages(ceres::Problem& problem, const std::vector<ceres::ResidualBlockId>& blocks,
                                        int num_threads) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<ceres::ResidualBlockId> all;
  problem.GetResidualBlocks(&all);
  std::unordered_map<ceres::ResidualBlockId, int> first_row;
  int rows = 0;
  for (ceres::ResidualBlockId id : all) {
    first_row.emplace(id, rows);
    rows += problem.GetCostFunctionForResidualBlock(id)->num_residuals();
  }
  for (ceres::ResidualBlockId id : blocks) {
    if (first_row.count(id) == 0) throw std::invalid_argument("ComputeResidualLeverages: a block not in the problem");
  }
  LeverageResult result;
  TangentJacobian jacobian;
  std::vector<double*> parameters;
  problem.GetParameterBlocks(&parameters);
  for (double* block : parameters) {
    if (problem.IsParameterBlockConstant(block)) continue;
    jacobian.offsets.push_back(jacobian.blocks.empty() ? 0
                                                       : jacobian.offsets.back() +
                                                             problem.ParameterBlockTangentSize(jacobian.blocks.back()));
    jacobian.blocks.push_back(block);
  }
  SelectedInverse inverse;
  if (!jacobian.blocks.empty()) {
    ceres::Problem::EvaluateOptions evaluate;
    evaluate.parameter_blocks = jacobian.blocks;
    evaluate.residual_blocks = all;
    evaluate.num_threads = num_threads;
    if (!problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &jacobian.crs)) {
      result.message = "leverages not computable: the problem could not be evaluated";
      return result;
    }
    std::vector<std::pair<int, int>> dense;
    for (std::size_t b = 0; b < jacobian.blocks.size(); ++b) {
      dense.emplace_back(jacobian.offsets[b], problem.ParameterBlockTangentSize(jacobian.blocks[b]));
    }
    const std::string failure = inverse.Compute(jacobian.crs, dense);
    if (!failure.empty()) {
      result.message = "leverages not computable (selected inversion): " + failure;
      return result;
    }
  }
  const ceres::CRSMatrix& J = jacobian.crs;
  for (ceres::ResidualBlockId id : blocks) {
    const int size = problem.GetCostFunctionForResidualBlock(id)->num_residuals();
    Eigen::VectorXd h = Eigen::VectorXd::Zero(size);
    for (int r = 0; r < size && !jacobian.blocks.empty(); ++r) {
      const int row = first_row[id] + r;
      double sum = 0.0;
      for (int a = J.rows[row]; a < J.rows[row + 1]; ++a) {
        for (int b = J.rows[row]; b < J.rows[row + 1]; ++b) {
          sum += J.values[a] * J.values[b] * inverse.Inverse(J.cols[a], J.cols[b]);
        }
      }
      h(r) = sum;
    }
    result.leverages.push_back(h);
  }
  result.run_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace navtwin
