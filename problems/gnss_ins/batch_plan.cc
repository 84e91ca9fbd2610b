#include "problems/gnss_ins/batch_plan.h"

#include <cmath>
#include <stdexcept>

#include "problems/gnss_ins/batch.h"
#include "problems/gnss_ins/sources.h"
#include "problems/ins/ins_state.h"

namespace navtwin::gnss_ins {

/// The sample times of the source that anchors the states (at most one; none: empty).
std::vector<double> AnchorTimes(const ins::AidingSources& sources) {
  const ins::AidingSource* anchoring = nullptr;
  for (const auto& source : sources) {
    if (!source->anchors_batch_states()) continue;
    if (anchoring != nullptr) throw std::invalid_argument("RunBatch: two aiding sources anchor the states");
    anchoring = source.get();
  }
  return anchoring != nullptr ? anchoring->times() : std::vector<double>();
}

Plan PlanStates(const std::vector<double>& anchor_times, const GnssInsConfig& config, double t0_s, double t_end_s) {
  const double max_gap = config.batch.max_state_interval_s;
  if (!(max_gap > 0.0) || !std::isfinite(max_gap)) {
    throw std::invalid_argument("RunBatch: batch.max_state_interval_s must be positive and finite");
  }
  const double thin = config.batch.state_interval_s;
  Plan plan;
  std::vector<PlannedState> anchors{{t0_s, -1}};
  for (std::size_t i = 0; i < anchor_times.size(); ++i) {
    const double t = anchor_times[i];
    if (t < t0_s - ins::kSameEpoch_s) continue;
    if (t > t_end_s + ins::kSameEpoch_s) break;
    if (t <= t0_s + ins::kSameEpoch_s) {  // at the first state
      anchors.front().anchor = static_cast<long>(i);
      continue;
    }
    if (thin > 0.0 && t - anchors.back().t_s < thin - ins::kSameEpoch_s) {
      plan.thinned.push_back(i);
      continue;
    }
    anchors.push_back({t, static_cast<long>(i)});
  }
  if (t_end_s - anchors.back().t_s > max_gap + ins::kSameEpoch_s) anchors.push_back({t_end_s, -1});
  for (std::size_t i = 0; i < anchors.size(); ++i) {
    plan.states.push_back(anchors[i]);
    if (i + 1 == anchors.size()) break;
    const double gap = anchors[i + 1].t_s - anchors[i].t_s;
    const int pieces = static_cast<int>(std::ceil(gap / max_gap - 1e-9));
    for (int k = 1; k < pieces; ++k) plan.states.push_back({anchors[i].t_s + k * gap / pieces, -1});
  }
  return plan;
}

std::vector<double> BatchStateTimes(const Inputs& inputs, const GnssInsConfig& config, double t0_s, double t_end_s) {
  const Plan plan = PlanStates(AnchorTimes(MakeSources(inputs, config)), config, t0_s, t_end_s);
  std::vector<double> times;
  times.reserve(plan.states.size());
  for (const PlannedState& s : plan.states) times.push_back(s.t_s);
  return times;
}

}  // namespace navtwin::gnss_ins
