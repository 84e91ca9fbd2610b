// Linearization of a Ceres cost function in the tangent (error-state) space of its
// parameter blocks, so that a Kalman filter uses the same residual functor as the batch
// problem (DESIGN.md "one model, two estimators").
//
// For blocks x_k with manifolds M_k, Linearize evaluates r(x) and the ambient Jacobians
// A_k = d r / d x_k (Ceres fills them row-major, residuals x ambient size) and returns
//   J_k = A_k * P_k,   P_k = M_k.PlusJacobian(x_k)  (ambient x tangent, row-major)
// i.e. d r(x_k (+) delta) / d delta at delta = 0, or J_k = A_k when M_k is nullptr.
// With the project's whitened residuals r = (h(x) - z) / sigma and errors "true minus
// estimate" (x_true = x_est (+) dx): 0 ~ r + sum_k J_k dx_k + noise, so a filter uses the
// innovation y = -r, H = [J_0 ... J_n] and R = I.
// Header-only (inline) so that the factor tests, which link navtwin::factors only, can
// use it too.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/manifold.h>
#include <Eigen/Core>

namespace navtwin {

struct Linearization {
  Eigen::VectorXd residual;                ///< r(x), num_residuals
  std::vector<Eigen::MatrixXd> jacobians;  ///< per block: num_residuals x tangent size
};

namespace linearize_detail {

/// Per-thread scratch reused across calls: std::vector keeps its capacity, so after the
/// first calls no allocation happens (an Eigen matrix would reallocate on any size change).
struct Scratch {
  std::vector<double> ambient;        ///< all ambient Jacobians, row-major, back to back
  std::vector<double*> ambient_ptrs;  ///< one pointer per block into `ambient`
  std::vector<double> plus_jacobian;  ///< one block's PlusJacobian, row-major
};

}  // namespace linearize_detail

/// Same as the overload below, into *out, reusing its storage (no allocation once out has
/// the right shapes; for filters running this at every measurement). Throws
/// std::invalid_argument if the block or manifold counts do not match the cost function,
/// or a manifold's ambient size differs from the block size; std::runtime_error if the
/// cost function or a PlusJacobian fails.
inline void Linearize(const ceres::CostFunction& cost, const std::vector<const double*>& blocks,
                      const std::vector<const ceres::Manifold*>& manifolds, Linearization* out) {
  using RowMajorMap = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>;
  const std::vector<int32_t>& sizes = cost.parameter_block_sizes();
  const int n_blocks = static_cast<int>(sizes.size());
  if (static_cast<int>(blocks.size()) != n_blocks || static_cast<int>(manifolds.size()) != n_blocks) {
    throw std::invalid_argument("Linearize: the cost function has " + std::to_string(n_blocks) +
                                " parameter blocks, got " + std::to_string(blocks.size()) + " blocks and " +
                                std::to_string(manifolds.size()) + " manifolds");
  }
  const int m = cost.num_residuals();
  int total_ambient = 0;
  for (int k = 0; k < n_blocks; ++k) {
    if (manifolds[k] != nullptr && manifolds[k]->AmbientSize() != sizes[k]) {
      throw std::invalid_argument("Linearize: block " + std::to_string(k) + " has size " +
                                  std::to_string(sizes[k]) + " but its manifold's ambient size is " +
                                  std::to_string(manifolds[k]->AmbientSize()));
    }
    total_ambient += sizes[k];
  }

  thread_local linearize_detail::Scratch scratch;
  scratch.ambient.resize(static_cast<std::size_t>(m) * total_ambient);
  scratch.ambient_ptrs.resize(n_blocks);
  for (int k = 0, offset = 0; k < n_blocks; offset += m * sizes[k], ++k) {
    scratch.ambient_ptrs[k] = scratch.ambient.data() + offset;
  }
  out->residual.resize(m);
  if (!cost.Evaluate(blocks.data(), out->residual.data(), scratch.ambient_ptrs.data())) {
    throw std::runtime_error("Linearize: the cost function failed to evaluate");
  }

  out->jacobians.resize(n_blocks);
  for (int k = 0; k < n_blocks; ++k) {
    const RowMajorMap ambient(scratch.ambient_ptrs[k], m, sizes[k]);
    if (manifolds[k] == nullptr) {
      out->jacobians[k] = ambient;
      continue;
    }
    const int tangent_size = manifolds[k]->TangentSize();
    scratch.plus_jacobian.resize(static_cast<std::size_t>(sizes[k]) * tangent_size);
    if (!manifolds[k]->PlusJacobian(blocks[k], scratch.plus_jacobian.data())) {
      throw std::runtime_error("Linearize: PlusJacobian failed for block " + std::to_string(k));
    }
    out->jacobians[k].resize(m, tangent_size);
    out->jacobians[k].noalias() = ambient * RowMajorMap(scratch.plus_jacobian.data(), sizes[k], tangent_size);
  }
}

/// The linearization of cost at blocks (errors as for the overload above).
inline Linearization Linearize(const ceres::CostFunction& cost, const std::vector<const double*>& blocks,
                                const std::vector<const ceres::Manifold*>& manifolds) {
  Linearization out;
  Linearize(cost, blocks, manifolds, &out);
  return out;
}

}  // namespace navtwin
