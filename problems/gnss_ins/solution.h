// The result type every GNSS/INS estimator returns (filter, RTS smoother, batch), so the
// command and the tests compare them directly.
#pragma once

#include <cstddef>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "problems/gnss_ins/ins_vocabulary.h"

namespace navtwin::gnss_ins {

struct MeasurementCount {
  std::size_t used = 0;
  std::size_t rejected = 0;  ///< by the chi-square gate (filter) or not used for another reason
};

/// Residuals of one group of measurement rows (a sensor, or one axis group of a sensor):
/// how well the configured noise fits them. A consistent estimator has chi2 / dof near 1.
struct ResidualStats {
  std::size_t rows = 0;  ///< scalar residuals (filter: summed dimensions of the accepted updates)
  double chi2 = 0.0;     ///< sum of squared whitened residuals (filter: NIS of the accepted updates)
  /// Degrees of freedom: batch, the redundancy sum (1 - h_i) (solvers/residual_groups.h);
  /// filter, the rows (E[NIS] = dimension).
  double dof = 0.0;
  /// Batch: the factor the group's standard deviations were multiplied by (variance-component
  /// estimation; 1 without), and chi2 / dof with the configured standard deviations.
  double sigma_scale = 1.0;
  double configured_chi2_per_dof = std::numeric_limits<double>::quiet_NaN();
  bool adapted = false;  ///< the estimation changed the factor (enough redundancy)
  double ChiSquarePerDof() const { return chi2 / dof; }
};

/// One measurement of an estimator (a row of <method>/residuals.csv, docs/run-folder.md).
struct MeasurementResidual {
  double t_s = 0.0;    ///< filter: the update epoch; batch: the time of the state it constrains
  std::string sensor;  ///< the count key (Solution::counts)
  int dof = 0;         ///< the measurement's dimension; 0 for a sample counted without an update
  /// Filter: the NIS y^T S^-1 y of the update (rejected ones too); batch: the squared norm
  /// of the whitened residual at the solution (with the variance components' noise, without
  /// the robust loss); NaN for a sample counted without an update.
  double chi2 = 0.0;
  bool rejected = false;  ///< by the gate or a rule (counted as rejected)
};

struct Solution {
  std::string method;  ///< "filter", "rts", "batch"
  /// The estimator's state epochs ("knots"), increasing in time, with error-state standard
  /// deviations: for the filter the epochs after each update and at least every
  /// FilterConfig::store_interval_s; for the batch its parameter epochs.
  std::vector<NavEpoch> epochs;
  /// Knots the estimator computed but did not keep (the filter with FilterKnots::kLast);
  /// the knots computed are epochs.size() + knots_not_kept.
  std::size_t knots_not_kept = 0;
  /// Keys: "gnss_position", "gnss_velocity", "mag", "baro", "zupt".
  std::map<std::string, MeasurementCount> counts;
  /// Per residual group: the sources' count keys or their axis groups ("gnss_position_h",
  /// "gnss_position_v", ...; AidingSource::row_groups), and for the batch "imu" (the
  /// preintegrated increments), "gyro_bias_process", "accel_bias_process", "prior".
  std::map<std::string, ResidualStats> residuals;
  /// Filter: one entry per counted sample (an update, accepted or rejected, a sample a rule
  /// rejected, a reset), in time order. Batch: one per measurement residual block, in time
  /// order. RTS: empty (it has no innovations of its own).
  std::vector<MeasurementResidual> measurement_residuals;
  /// The epochs' auxiliary states (NavEpoch::aux; the aiding sources' parameters, e.g.
  /// "odometer_scale"), in order: names, priors and what observes them.
  std::vector<ins::AuxState> aux_states;
  double run_time_s = 0.0;
  std::string solver_report;  ///< batch: Ceres' brief report; filter: empty
};

}  // namespace navtwin::gnss_ins
