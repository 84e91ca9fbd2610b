// The barometer as an aiding source: the height functor (factors/baro_height.h) with an
// offset (altitude - ellipsoidal height) taken once, at the first sample that has a height
// reference (the first GNSS fix the estimator uses; the first sample when there is none).
#pragma once

#include <memory>
#include <vector>

#include "core/types.h"
#include "problems/ins/aiding.h"

namespace navtwin::ins {

struct BaroConfig {
  bool use = false;
  double std_m = 1.0;
  /// The barometer's offset from the ellipsoidal height is taken at the first epoch with
  /// a height reference (a GNSS fix; the first sample without one) and held constant.
};

/// Count key "baro". reference_times_s: the times of the height references (GNSS fixes),
/// increasing. Filter: samples before the first reference it uses are rejected; batch:
/// the offset is taken at the first state placed at a fix of the anchoring source.
std::unique_ptr<AidingSource> MakeBaroSource(const std::vector<BaroSample>& samples, const BaroConfig& config,
                                             std::vector<double> reference_times_s);

}  // namespace navtwin::ins
