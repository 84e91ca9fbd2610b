// Tangent-space Jacobian check shared by the measurement-model tests: a model's
// Linearize (solvers/linearize.h) Jacobians against central differences through each
// block's manifold, at the three test points (zero/identity, a tiny perturbation of it,
// a random state with a fixed seed).
#pragma once

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/manifold.h>
#include <gtest/gtest.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"
#include "core/units.h"
#include "solvers/linearize.h"

namespace navtwin::tangent_check {
// A parameter block at its ambient value, its manifold (nullptr: Euclidean) and the
// central-difference step in its tangent space.
struct Block {
  std::vector<double> x;
  const ceres::Manifold* manifold;
  double step;
};

inline Eigen::VectorXd Residual(const ceres::CostFunction& f, const std::vector<Block>& blocks) {
  std::vector<const double*> params;
  for (const Block& b : blocks) params.push_back(b.x.data());
  Eigen::VectorXd r(f.num_residuals());
  EXPECT_TRUE(f.Evaluate(params.data(), r.data(), nullptr));
  return r;
}

/// Block k moved by delta in its tangent space (manifold Plus, or +).
inline std::vector<Block> Moved(std::vector<Block> blocks, int k, const Eigen::VectorXd& delta) {
  Block& b = blocks[k];
  std::vector<double> out(b.x.size());
  if (b.manifold != nullptr) {
    EXPECT_TRUE(b.manifold->Plus(b.x.data(), delta.data(), out.data()));
  } else {
    for (size_t i = 0; i < out.size(); ++i) out[i] = b.x[i] + delta[i];
  }
  b.x = out;
  return blocks;
}

/// Central differences of the residual in block k's tangent space.
inline Eigen::MatrixXd NumericTangentJacobian(const ceres::CostFunction& f, const std::vector<Block>& blocks, int k) {
  const Block& b = blocks[k];
  const int n = b.manifold != nullptr ? b.manifold->TangentSize() : static_cast<int>(b.x.size());
  Eigen::MatrixXd jacobian(f.num_residuals(), n);
  for (int i = 0; i < n; ++i) {
    const Eigen::VectorXd h = b.step * Eigen::VectorXd::Unit(n, i);
    jacobian.col(i) = (Residual(f, Moved(blocks, k, h)) - Residual(f, Moved(blocks, k, -h))) / (2.0 * b.step);
  }
  return jacobian;
}

inline Linearization LinearizeAt(const ceres::CostFunction& f, const std::vector<Block>& blocks) {
  std::vector<const double*> params;
  std::vector<const ceres::Manifold*> manifolds;
  for (const Block& b : blocks) {
    params.push_back(b.x.data());
    manifolds.push_back(b.manifold);
  }
  return Linearize(f, params, manifolds);
}

/// Linearize's tangent Jacobians against central differences: max |J - J_num| <=
/// tol * max(1, max |J|) per block; its residual equals Evaluate's (to rounding).
inline void ExpectTangentJacobiansMatch(const ceres::CostFunction& f, const std::vector<Block>& blocks, double tol) {
  const Linearization lin = LinearizeAt(f, blocks);
  // Evaluate with and without Jacobians runs double vs Jet arithmetic: rounding only.
  const Eigen::VectorXd r = Residual(f, blocks);
  EXPECT_LE((lin.residual - r).norm(), 1e-14 * (1.0 + r.norm()));
  ASSERT_EQ(lin.jacobians.size(), blocks.size());
  for (size_t k = 0; k < blocks.size(); ++k) {
    SCOPED_TRACE("block " + std::to_string(k));
    const Eigen::MatrixXd numeric = NumericTangentJacobian(f, blocks, static_cast<int>(k));
    ASSERT_EQ(lin.jacobians[k].rows(), numeric.rows());
    ASSERT_EQ(lin.jacobians[k].cols(), numeric.cols());
    const double scale = std::max(1.0, lin.jacobians[k].cwiseAbs().maxCoeff());
    EXPECT_LE((lin.jacobians[k] - numeric).cwiseAbs().maxCoeff(), tol * scale)
        << "analytic\n" << lin.jacobians[k] << "\nnumeric\n" << numeric;
  }
}

inline std::vector<double> Std(const Eigen::Vector3d& v) { return {v[0], v[1], v[2]}; }
inline std::vector<double> Std(const Eigen::Quaterniond& q) { return {q.x(), q.y(), q.z(), q.w()}; }

// The three test points: zero / identity, a tiny perturbation of it, a random state.
struct State {
  std::string name;
  Eigen::Vector3d pos;  // lat_rad, lon_rad, h_m
  Eigen::Quaterniond q_n_b;
  Eigen::Vector3d v_n_mps;
};

inline std::vector<State> States() {
  std::mt19937 rng(20240917);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random3 = [&]() -> Eigen::Vector3d { return Eigen::Vector3d(u(rng), u(rng), u(rng)); };
  std::vector<State> states;
  states.push_back({"zero", Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero()});
  states.push_back({"tiny", Eigen::Vector3d(1e-9, -1e-9, 1e-9), QuatFromRotVec<double>(Eigen::Vector3d(1e-9, -2e-9, 3e-9)),
                    Eigen::Vector3d(1e-9, 2e-9, -1e-9)});
  const Eigen::Vector3d pos(80.0 * kDegToRad * u(rng), M_PI * u(rng), 2500.0 + 2500.0 * u(rng));
  const Eigen::Vector3d phi = 3.0 * std::abs(u(rng)) * random3().normalized();
  states.push_back({"random", pos, QuatFromRotVec<double>(phi), 30.0 * random3()});
  return states;
}

}  // namespace navtwin::tangent_check
