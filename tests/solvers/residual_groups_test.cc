// ResidualGroups (solvers/residual_groups.h): the weighting of wrapped rows, the
// chi-square and redundancy per group, and the iterated variance-component estimate on a
// linear problem whose true noise is known.
#include <cmath>
#include <random>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include "solvers/batch_driver.h"
#include "solvers/residual_groups.h"

namespace navtwin {
namespace solvers_residual_groups_test {

/// r = (a . x - y) / sigma over one 3-vector x, rows of a given matrix.
class LinearObservations final : public ceres::CostFunction {
 public:
  LinearObservations(Eigen::MatrixXd a, Eigen::VectorXd y, double sigma) : a_(std::move(a)), y_(std::move(y)), sigma_(sigma) {
    set_num_residuals(static_cast<int>(a_.rows()));
    mutable_parameter_block_sizes()->push_back(3);
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Vector3d> x(parameters[0]);
    Eigen::Map<Eigen::VectorXd>(residuals, a_.rows()) = (a_ * x - y_) / sigma_;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(jacobians[0], a_.rows(), 3) = a_ / sigma_;
    }
    return true;
  }

 private:
  Eigen::MatrixXd a_;
  Eigen::VectorXd y_;
  double sigma_;
};

/// count scalar observations of x_true, noise sigma_true, stated sigma_stated, one block each.
void AddObservations(ceres::Problem* problem, ResidualGroups* groups, int group, double* x, int count,
                     double sigma_true, double sigma_stated, std::mt19937* rng) {
  const Eigen::Vector3d x_true(1.0, -2.0, 0.5);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < count; ++i) {
    Eigen::MatrixXd a(1, 3);
    a << normal(*rng), normal(*rng), normal(*rng);
    Eigen::VectorXd y(1);
    y(0) = a.row(0).dot(x_true) + sigma_true * normal(*rng);
    problem->AddResidualBlock(groups->Wrap(new LinearObservations(a, y, sigma_stated), {group}), nullptr, x);
  }
}

void Solve(ceres::Problem* problem) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(options, problem, &summary);
}

// A wrapped row is the inner row over sqrt(factor), Jacobian included, exactly.
TEST(ResidualGroups, WrappedRowsAreScaledBySqrtFactor) {
  ResidualGroups groups;
  const int a = groups.Group("a"), b = groups.Group("b");
  EXPECT_EQ(groups.Group("a"), a);
  groups.set_factor(a, 4.0);
  groups.set_factor(b, 0.25);
  Eigen::MatrixXd m(2, 3);
  m << 1, 2, 3, 4, 5, 6;
  const LinearObservations inner(m, Eigen::Vector2d(1.0, -1.0), 0.5);
  std::unique_ptr<ceres::CostFunction> wrapped(groups.Wrap(new LinearObservations(m, Eigen::Vector2d(1.0, -1.0), 0.5), {a, b}));
  const double x[3] = {0.3, -0.2, 0.7};
  const double* parameters[1] = {x};
  double r_inner[2], r_wrapped[2], j_inner[6], j_wrapped[6];
  double* ji[1] = {j_inner};
  double* jw[1] = {j_wrapped};
  ASSERT_TRUE(inner.Evaluate(parameters, r_inner, ji));
  ASSERT_TRUE(wrapped->Evaluate(parameters, r_wrapped, jw));
  EXPECT_DOUBLE_EQ(r_wrapped[0], r_inner[0] / 2.0);
  EXPECT_DOUBLE_EQ(r_wrapped[1], r_inner[1] * 2.0);
  for (int c = 0; c < 3; ++c) {
    EXPECT_DOUBLE_EQ(j_wrapped[c], j_inner[c] / 2.0);
    EXPECT_DOUBLE_EQ(j_wrapped[3 + c], j_inner[3 + c] * 2.0);
  }
  EXPECT_THROW(groups.Wrap(new LinearObservations(m, Eigen::Vector2d(1.0, -1.0), 0.5), {a, b, a}),
               std::invalid_argument);
  EXPECT_THROW(groups.set_factor(a, 0.0), std::invalid_argument);
}

// Redundancies sum to rows - parameters (3); the chi-square is the sum of squared rows.
TEST(ResidualGroups, RedundancySumsToRowsMinusParameters) {
  std::mt19937 rng(3);
  ceres::Problem problem;
  ResidualGroups groups;
  double x[3] = {0.0, 0.0, 0.0};
  AddObservations(&problem, &groups, groups.Group("a"), x, 40, 1.0, 1.0, &rng);
  AddObservations(&problem, &groups, groups.Group("b"), x, 7, 1.0, 1.0, &rng);
  Solve(&problem);
  std::string message;
  const std::vector<ResidualGroupStats> stats = groups.Evaluate(problem, true, 1, &message);
  ASSERT_TRUE(message.empty()) << message;
  ASSERT_EQ(stats.size(), 2u);
  EXPECT_EQ(stats[0].rows, 40u);
  EXPECT_EQ(stats[1].blocks, 7u);
  EXPECT_NEAR(stats[0].redundancy + stats[1].redundancy, 47.0 - 3.0, 1e-9);
  double cost = 0.0;
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  EXPECT_NEAR(stats[0].chi2 + stats[1].chi2, 2.0 * cost, 1e-9 * cost);
}

// Two groups observe x; group "loose" states sigma 1 with true noise 3 (variance factor 9),
// group "right" is honest. 2000 rows each: the estimate of a factor s has a relative
// standard deviation of about sqrt(2 / 2000) = 3 %, so 12 % (4 sigma) bounds it.
TEST(ResidualGroups, IteratedEstimateRecoversVarianceFactors) {
  std::mt19937 rng(5);
  ceres::Problem problem;
  ResidualGroups groups;
  double x[3] = {0.0, 0.0, 0.0};
  const int loose = groups.Group("loose"), right = groups.Group("right");
  AddObservations(&problem, &groups, loose, x, 2000, 3.0, 1.0, &rng);
  AddObservations(&problem, &groups, right, x, 2000, 1.0, 1.0, &rng);
  double worst = 1.0;
  int iterations = 0;
  while (worst > 1e-3 && iterations < 20) {
    Solve(&problem);
    const std::vector<ResidualGroupStats> stats = groups.Evaluate(problem, true, 1, nullptr);
    worst = groups.UpdateFactors(stats, 10.0);
    ++iterations;
  }
  EXPECT_LT(iterations, 20);
  EXPECT_NEAR(groups.factor(loose), 9.0, 0.12 * 9.0);
  EXPECT_NEAR(groups.factor(right), 1.0, 0.12);
}

// A group below the minimum redundancy, or not estimable, keeps its factor.
TEST(ResidualGroups, SmallOrFixedGroupsAreNotChanged) {
  std::mt19937 rng(8);
  ceres::Problem problem;
  ResidualGroups groups;
  double x[3] = {0.0, 0.0, 0.0};
  const int few = groups.Group("few"), fixed = groups.Group("fixed", false), many = groups.Group("many");
  AddObservations(&problem, &groups, few, x, 5, 5.0, 1.0, &rng);
  AddObservations(&problem, &groups, fixed, x, 100, 5.0, 1.0, &rng);
  AddObservations(&problem, &groups, many, x, 100, 5.0, 1.0, &rng);
  Solve(&problem);
  groups.UpdateFactors(groups.Evaluate(problem, true, 1, nullptr), 10.0);
  EXPECT_EQ(groups.factor(few), 1.0);
  EXPECT_EQ(groups.factor(fixed), 1.0);
  EXPECT_GT(groups.factor(many), 4.0);  // true factor 25; one step from 1 goes most of the way
}

}  // namespace solvers_residual_groups_test
}  // namespace navtwin
