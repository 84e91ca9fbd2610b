// Statistics of Monte Carlo run records (mc_record.h), accumulated in run order so the sums,
// and therefore the result files, are the same bits for any number of threads or ranks.
//
// Per method, quantity and axis point, over the runs with a finite error there:
//   RMS error per component, the mean reported sigma (sqrt of the covariance diagonal) and
//   their ratio (1 for honest sigma, above 1 when the method claims too much);
//   ANEES = sum_k e_k^T P_k^-1 e_k / (n d) over the n runs with a positive-definite P, whose
//   two-sided 95 % bounds are chi2_{n d}(0.025) / (n d) and chi2_{n d}(0.975) / (n d)
//   (Bar-Shalom, Li & Kirubarajan, "Estimation with Applications to Tracking and
//   Navigation", 2001, sec. 5.4.2);
//   the fraction of runs whose |error| is within 3 sigma, per component.
// At the last point (the final value) every run's error and sigma are kept for histograms
// and the per-run table.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "solvers/mc_record.h"

namespace navtwin::mc {

struct PointStatistics {
  int runs = 0;                       ///< runs with a finite error at the point
  std::vector<double> rms;            ///< per component, SI
  std::vector<double> sigma_mean;     ///< mean reported sigma, SI; NaN when no run reports one
  std::vector<double> within_3sigma;  ///< fraction of the runs with a sigma; NaN without one
  int nees_runs = 0;                  ///< runs whose covariance is positive definite
  double anees = 0.0;                 ///< NaN when nees_runs = 0
  double anees_lo = 0.0, anees_hi = 0.0;  ///< 95 % bounds for nees_runs x dim degrees of freedom
  std::vector<double> bound_sigma;    ///< the Cramér-Rao bound per component, SI; NaN without
};

struct QuantityStatistics {
  Quantity layout;  ///< name, unit, scale, axis and components (error / covariance empty)
  std::vector<PointStatistics> points;
  /// The final point of every run added (run order): runs x dim, SI, NaN when missing.
  std::vector<double> final_error;
  std::vector<double> final_sigma;
};

struct MethodStatistics {
  std::string method;
  int runs = 0;      ///< records added
  int failures = 0;  ///< runs on which the method threw
  std::string first_failure;
  double run_time_s = 0.0;  ///< summed over the runs (for the progress line, not for files)
  std::vector<QuantityStatistics> quantities;
};

class Accumulator {
 public:
  /// Adds the next run's record. The first record that has a method's quantity fixes its
  /// axis; a later record with another axis for it throws std::logic_error.
  void Add(const RunRecord& record);
  /// The statistics so far, with the bound's sigma (a method record whose covariances
  /// are the bound, matched by quantity name and axis point) when given.
  std::vector<MethodStatistics> Finish(const MethodRecord* bound = nullptr) const;
  int runs() const { return runs_; }
  /// The seed of every run added, in run order.
  const std::vector<std::uint64_t>& seeds() const { return seeds_; }

 private:
  struct PointSums {
    std::vector<double> sum_sq, sum_sigma, within;
    std::vector<int> n_sigma;
    int n = 0, nees_n = 0;
    double nees_sum = 0.0;
  };
  struct QuantitySums {
    Quantity layout;
    std::vector<PointSums> points;
    std::vector<double> final_error, final_sigma;
  };
  struct MethodSums {
    MethodStatistics head;  ///< method, runs, failures, run time
    std::vector<QuantitySums> quantities;
  };
  void AddQuantity(const Quantity& q, int runs_before, MethodSums* m);

  int runs_ = 0;
  std::vector<std::uint64_t> seeds_;
  std::vector<MethodSums> methods_;  ///< in the order first seen
};

/// The index of `name` in stats, or -1.
int FindMethod(const std::vector<MethodStatistics>& stats, const std::string& name);

}  // namespace navtwin::mc
