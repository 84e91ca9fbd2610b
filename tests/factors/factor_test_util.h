// Helpers shared by the tests of cost functions with 3 residuals and one 4-double attitude
// parameter block (q_n_b as x, y, z, w): evaluation and central-difference Jacobians.
#pragma once

#include <ceres/cost_function.h>
#include <Eigen/Core>
#include <gtest/gtest.h>

namespace navtwin::testing {

/// d(residual)/d(q): 3 x 4, row-major as Ceres fills it.
using Jacobian34 = Eigen::Matrix<double, 3, 4, Eigen::RowMajor>;
/// d(q)/d(delta) of a manifold's PlusJacobian: 4 x 3, row-major as Ceres fills it.
using Jacobian43 = Eigen::Matrix<double, 4, 3, Eigen::RowMajor>;

/// The residual of f at q; also its Jacobian when `jacobian` is given. Expects Evaluate to
/// succeed.
inline Eigen::Vector3d Residual(const ceres::CostFunction& f, const Eigen::Vector4d& q,
                                Jacobian34* jacobian = nullptr) {
  Eigen::Vector3d r;
  const double* parameters[] = {q.data()};
  double* jacobians[] = {jacobian != nullptr ? jacobian->data() : nullptr};
  EXPECT_TRUE(f.Evaluate(parameters, r.data(), jacobian != nullptr ? jacobians : nullptr));
  return r;
}

/// Central differences of Residual in each of the 4 ambient coordinates of q, step
/// h = 1e-6 (each test states its tolerance from this step).
inline Jacobian34 NumericJacobian(const ceres::CostFunction& f, const Eigen::Vector4d& q) {
  constexpr double kStep = 1e-6;
  Jacobian34 jacobian;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector4d h = kStep * Eigen::Vector4d::Unit(i);
    jacobian.col(i) = (Residual(f, q + h) - Residual(f, q - h)) / (2.0 * kStep);
  }
  return jacobian;
}

}  // namespace navtwin::testing
