#include "solvers/residual_groups.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <ceres/cost_function.h>
#include <ceres/problem.h>
#include <Eigen/Core>

#include "solvers/batch_driver.h"

namespace navtwin {

struct ResidualGroups::Data {
  std::vector<std::string> names;
  std::vector<bool> estimable;
  std::vector<double> factors;
};

namespace {

/// A cost function whose rows are divided by sqrt of their group's variance factor.
class GroupWeightedCost final : public ceres::CostFunction {
 public:
  GroupWeightedCost(ceres::CostFunction* inner, std::vector<int> row_groups,
                    std::shared_ptr<const ResidualGroups::Data> data)
      : inner_(inner), row_groups_(std::move(row_groups)), data_(std::move(data)) {
    set_num_residuals(inner->num_residuals());
    *mutable_parameter_block_sizes() = inner->parameter_block_sizes();
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    if (!inner_->Evaluate(parameters, residuals, jacobians)) return false;
    const std::vector<int32_t>& sizes = parameter_block_sizes();
    for (int r = 0; r < num_residuals(); ++r) {
      const double w = 1.0 / std::sqrt(data_->factors[static_cast<std::size_t>(row_groups_[r])]);
      if (w == 1.0) continue;
      residuals[r] *= w;
      if (jacobians == nullptr) continue;
      for (std::size_t k = 0; k < sizes.size(); ++k) {
        if (jacobians[k] == nullptr) continue;
        double* row = jacobians[k] + static_cast<std::ptrdiff_t>(r) * sizes[k];
        for (int c = 0; c < sizes[k]; ++c) row[c] *= w;
      }
    }
    return true;
  }

  const std::vector<int>& row_groups() const { return row_groups_; }
  const ResidualGroups::Data* data() const { return data_.get(); }

 private:
  std::unique_ptr<ceres::CostFunction> inner_;
  std::vector<int> row_groups_;
  std::shared_ptr<const ResidualGroups::Data> data_;
};

}  // namespace

ResidualGroups::ResidualGroups() : data_(std::make_shared<Data>()) {}
ResidualGroups::~ResidualGroups() = default;

int ResidualGroups::Group(const std::string& name, bool estimable) {
  for (std::size_t i = 0; i < data_->names.size(); ++i) {
    if (data_->names[i] == name) return static_cast<int>(i);
  }
  data_->names.push_back(name);
  data_->estimable.push_back(estimable);
  data_->factors.push_back(1.0);
  return static_cast<int>(data_->names.size() - 1);
}

ceres::CostFunction* ResidualGroups::Wrap(ceres::CostFunction* cost, const std::vector<int>& row_groups) const {
  const int rows = cost->num_residuals();
  std::vector<int> groups = row_groups.size() == 1 ? std::vector<int>(rows, row_groups.front()) : row_groups;
  if (static_cast<int>(groups.size()) != rows) {
    delete cost;
    throw std::invalid_argument("ResidualGroups::Wrap: one group per residual row, or one for all");
  }
  for (int g : groups) {
    if (g < 0 || static_cast<std::size_t>(g) >= data_->names.size()) {
      delete cost;
      throw std::invalid_argument("ResidualGroups::Wrap: unknown group");
    }
  }
  return new GroupWeightedCost(cost, std::move(groups), data_);
}

double ResidualGroups::factor(int group) const { return data_->factors.at(static_cast<std::size_t>(group)); }

void ResidualGroups::set_factor(int group, double factor) {
  if (!(factor > 0.0) || !std::isfinite(factor)) {
    throw std::invalid_argument("ResidualGroups::set_factor: the factor must be positive and finite");
  }
  data_->factors.at(static_cast<std::size_t>(group)) = factor;
}

std::size_t ResidualGroups::size() const { return data_->names.size(); }

std::vector<ResidualGroupStats> ResidualGroups::Evaluate(ceres::Problem& problem, bool redundancy, int num_threads,
                                                         std::string* message) const {
  std::vector<ResidualGroupStats> stats(data_->names.size());
  for (std::size_t g = 0; g < stats.size(); ++g) {
    stats[g].name = data_->names[g];
    stats[g].estimable = data_->estimable[g];
    stats[g].factor = data_->factors[g];
  }
  std::vector<ceres::ResidualBlockId> all, ours;
  problem.GetResidualBlocks(&all);
  std::vector<const GroupWeightedCost*> costs;
  for (ceres::ResidualBlockId id : all) {
    const auto* cost = dynamic_cast<const GroupWeightedCost*>(problem.GetCostFunctionForResidualBlock(id));
    if (cost == nullptr || cost->data() != data_.get()) continue;
    ours.push_back(id);
    costs.push_back(cost);
  }
  std::vector<double> r;
  for (std::size_t b = 0; b < ours.size(); ++b) {
    r.assign(static_cast<std::size_t>(costs[b]->num_residuals()), 0.0);
    double plain = 0.0;
    problem.EvaluateResidualBlock(ours[b], false, &plain, r.data(), nullptr);
    double share = 1.0;  // a block with a loss: its rows share rho(|r|^2) in proportion to r_i^2
    if (problem.GetLossFunctionForResidualBlock(ours[b]) != nullptr && plain > 0.0) {
      double robust = 0.0;
      problem.EvaluateResidualBlock(ours[b], true, &robust, nullptr, nullptr);
      share = robust / plain;
    }
    const std::vector<int>& groups = costs[b]->row_groups();
    int previous = -1;
    for (std::size_t i = 0; i < r.size(); ++i) {
      ResidualGroupStats& s = stats[static_cast<std::size_t>(groups[i])];
      if (groups[i] != previous) ++s.blocks;
      previous = groups[i];
      ++s.rows;
      s.chi2 += share * r[i] * r[i];
    }
  }
  if (!redundancy) return stats;
  const LeverageResult leverages = ComputeResidualLeverages(problem, ours, num_threads);
  if (!leverages.message.empty()) {
    if (message != nullptr) *message = leverages.message;
    return stats;
  }
  for (ResidualGroupStats& s : stats) s.redundancy = 0.0;
  for (std::size_t b = 0; b < ours.size(); ++b) {
    const std::vector<int>& groups = costs[b]->row_groups();
    for (std::size_t i = 0; i < groups.size(); ++i) {
      stats[static_cast<std::size_t>(groups[i])].redundancy += 1.0 - leverages.leverages[b](static_cast<Eigen::Index>(i));
    }
  }
  return stats;
}

double ResidualGroups::UpdateFactors(const std::vector<ResidualGroupStats>& stats, double min_redundancy,
                                     double tolerance) {
  const auto estimated = [&](std::size_t g) {
    const ResidualGroupStats& s = stats[g];
    return data_->estimable[g] && s.redundancy >= min_redundancy && s.chi2 > 0.0;
  };
  const std::size_t n = std::min(stats.size(), data_->factors.size());
  double worst = 0.0;
  for (std::size_t g = 0; g < n; ++g) {
    if (estimated(g)) worst = std::max(worst, std::abs(stats[g].ChiSquarePerDof() - 1.0));
  }
  if (worst <= tolerance) return worst;
  for (std::size_t g = 0; g < n; ++g) {
    if (estimated(g)) data_->factors[g] *= stats[g].ChiSquarePerDof();
  }
  return worst;
}

}  // namespace navtwin
