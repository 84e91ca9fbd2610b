// The result type every GNSS/INS estimator returns (filter, RTS smoother, batch), so the
// command and the tests compare them directly.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "problems/gnss_ins/ins_vocabulary.h"

namespace navtwin::gnss_ins {

struct MeasurementCount {
  std::size_t used = 0;
  std::size_t rejected = 0;  ///< by the chi-square gate (filter) or not used for another reason
};

struct Solution {
  std::string method;  ///< "filter", "rts", "batch"
  /// The estimator's state epochs ("knots"), increasing in time, with error-state standard
  /// deviations: for the filter the epochs after each update and at least every
  /// FilterConfig::store_interval_s; for the batch its parameter epochs.
  std::vector<NavEpoch> epochs;
  /// Keys: "gnss_position", "gnss_velocity", "mag", "baro", "zupt".
  std::map<std::string, MeasurementCount> counts;
  /// Names of the epochs' auxiliary states (NavEpoch::aux; the aiding sources' parameters,
  /// e.g. "odometer_scale"), in order.
  std::vector<std::string> aux_names;
  double run_time_s = 0.0;
  std::string solver_report;  ///< batch: Ceres' brief report; filter: empty
};

}  // namespace navtwin::gnss_ins
