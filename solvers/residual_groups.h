// Residual statistics per group of rows, and variance-component estimation (VCE), for a
// batch problem whose residuals are whitened (docs/variance-components.md).
//
// Every residual row belongs to a named group: a sensor and an axis group ("gnss_position_h",
// "imu", ...). Group k has a variance factor s_k: its rows' whitened residuals (and Jacobian
// rows) are divided by sqrt(s_k), i.e. the group's standard deviations are multiplied by
// sqrt(s_k). After a solve, per group:
//   chi2_k = sum_{i in k} r_i^2        (r whitened with the current factors; a row of a block
//                                       with a loss counts its share of the block's rho)
//   red_k  = sum_{i in k} (1 - h_i)    (redundancy; h_i = J_i (J^T J)^-1 J_i^T the leverage)
// and chi2_k / red_k is the group's chi-square per degree of freedom (1 when its sigmas fit
// its residuals; sum_k red_k = rows - free parameters). The iterated estimator of the
// variance components (Foerstner 1979; Koch 1999, "Parameter Estimation and Hypothesis
// Testing in Linear Models", ch. 3.6) replaces s_k by s_k chi2_k / red_k and solves again,
// until every ratio is 1 within a tolerance.
#pragma once

#include <cstddef>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace ceres {
class CostFunction;
class Problem;
}  // namespace ceres

namespace navtwin {

struct ResidualGroupStats {
  std::string name;
  bool estimable = true;      ///< VCE may change the factor (false: priors, fixed groups)
  std::size_t blocks = 0;     ///< residual blocks with a row in the group
  std::size_t rows = 0;
  double chi2 = 0.0;
  double redundancy = std::numeric_limits<double>::quiet_NaN();  ///< NaN: leverages not computed
  double factor = 1.0;        ///< the variance factor s_k the residuals were whitened with
  /// chi2 / redundancy (NaN without redundancy).
  double ChiSquarePerDof() const { return chi2 / redundancy; }
};

class ResidualGroups {
 public:
  ResidualGroups();
  ~ResidualGroups();
  ResidualGroups(const ResidualGroups&) = delete;
  ResidualGroups& operator=(const ResidualGroups&) = delete;

  /// The index of group `name`, created (factor 1) at the first call; `estimable` is the
  /// creating call's.
  int Group(const std::string& name, bool estimable = true);
  /// `cost` with row r in group row_groups[r] (one entry per residual, or one entry for
  /// every row): residuals and Jacobian rows divided by sqrt(factor) at each evaluation, so
  /// a changed factor takes effect at the next solve. The returned cost function owns `cost`.
  ceres::CostFunction* Wrap(ceres::CostFunction* cost, const std::vector<int>& row_groups) const;

  double factor(int group) const;
  void set_factor(int group, double factor);
  std::size_t size() const;

  /// The statistics of every group at the problem's current values, over the residual
  /// blocks made by Wrap (others are not counted); with leverages (num_threads for the
  /// Jacobian) unless `redundancy` is false. On a failure of the leverages the redundancy
  /// stays NaN and `message` (when not null) says why.
  std::vector<ResidualGroupStats> Evaluate(ceres::Problem& problem, bool redundancy, int num_threads,
                                           std::string* message) const;

  /// One step of the iterated estimator: the largest |chi2_k / red_k - 1| over the estimable
  /// groups with red_k >= min_redundancy (0 when none); when it exceeds `tolerance`,
  /// s_k *= chi2_k / red_k for each of them. Returns that largest deviation.
  double UpdateFactors(const std::vector<ResidualGroupStats>& stats, double min_redundancy, double tolerance = 0.0);

  struct Data;  ///< names, estimable flags and factors (defined in the .cc)

 private:
  std::shared_ptr<Data> data_;  ///< shared with the wrapped cost functions
};

}  // namespace navtwin
