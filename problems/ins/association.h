// Association of a sensor's samples to the batch states: each state takes the sample
// nearest in time among those whose nearest state it is (each sample used at most once),
// within kMaxSensorAssociation_s.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace navtwin::ins {

/// Samples farther than this from every batch state are not used.
constexpr double kMaxSensorAssociation_s = 0.5;

/// For every state time (increasing), the index of its sample, or -1. Sample: has t_s.
template <typename Sample>
std::vector<long> AssociateNearest(const std::vector<Sample>& samples, const std::vector<double>& state_times_s) {
  const std::vector<double>& times = state_times_s;
  std::vector<long> best(times.size(), -1);
  std::vector<double> best_dt(times.size(), std::numeric_limits<double>::infinity());
  if (times.empty()) return best;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const double t = samples[k].t_s;
    const auto it = std::lower_bound(times.begin(), times.end(), t);
    std::size_t j = static_cast<std::size_t>(it - times.begin());
    if (j == times.size() || (j > 0 && t - times[j - 1] < times[j] - t)) --j;
    const double dt = std::abs(t - times[j]);
    if (dt <= kMaxSensorAssociation_s && dt < best_dt[j]) {
      best_dt[j] = dt;
      best[j] = static_cast<long>(k);
    }
  }
  return best;
}

}  // namespace navtwin::ins
