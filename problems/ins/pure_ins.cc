#include "problems/ins/pure_ins.h"

#include <chrono>
#include <cmath>
#include <iostream>

#include "core/io/input_error.h"
#include "problems/ins/ins_state.h"

namespace navtwin {
namespace {

/// Walks the truth reader alongside the solution and compares at every truth epoch that
/// falls between two solution epochs.
class TruthComparer {
 public:
  explicit TruthComparer(NavReader* truth) : truth_(truth) { have_ = truth_ && truth_->Next(&next_); }

  void Advance(const NavState& prev, const NavState& cur, NavErrorStats* stats) {
    while (have_ && next_.t_s <= cur.t_s + ins::kSameEpoch_s) {
      if (next_.t_s >= prev.t_s - ins::kSameEpoch_s) {
        const NavState at = std::abs(next_.t_s - cur.t_s) <= ins::kSameEpoch_s
                                ? cur
                                : InterpolateNav(prev, cur, next_.t_s);
        stats->Add(CompareNav(at, next_));
      }
      have_ = truth_->Next(&next_);
    }
  }

 private:
  NavReader* truth_;
  NavState next_;
  bool have_ = false;
};

}  // namespace

NavState InitialStateFromNav(NavReader& nav, std::optional<double> start_s) {
  NavState s;
  while (nav.Next(&s)) {
    if (!start_s || s.t_s >= *start_s - ins::kSameEpoch_s) return s;
  }
  throw InputError(nav.path(), 0, "sow",
                   start_s ? "no record at or after the start time " + std::to_string(*start_s) + " s"
                           : std::string("no navigation record in the file"));
}

PureInsResult RunPureIns(ImuReader& imu, const NavState& initial, const PureInsOptions& options,
                         const std::function<void(const NavState&)>& output, NavReader* truth) {
  const auto wall_start = std::chrono::steady_clock::now();
  PureInsResult result;
  Strapdown ins(initial, options.strapdown);
  TruthComparer comparer(truth);
  NavErrorStats stats;
  if (truth) comparer.Advance(initial, initial, &stats);
  if (output) output(ins.state());
  double next_output_s = initial.t_s + options.output_interval_s;

  ImuSample s;
  // An IMU sample belongs to the run when its interval ends after the start epoch.
  constexpr double kEpochTolerance_s = 1e-9;
  while (imu.Next(&s)) {
    if (s.t_s <= initial.t_s + kEpochTolerance_s) {
      ++result.skipped_before_start;
      continue;
    }
    if (s.t_s > options.end_time_s + kEpochTolerance_s) break;
    const NavState prev = ins.state();
    ins.Update(s);
    ++result.imu_samples;
    if (truth) comparer.Advance(prev, ins.state(), &stats);
    if (output && ins.state().t_s >= next_output_s - kEpochTolerance_s) {
      output(ins.state());
      next_output_s += options.output_interval_s;
      if (next_output_s < ins.state().t_s) next_output_s = ins.state().t_s + options.output_interval_s;
    }
    if (options.progress_every && result.imu_samples % options.progress_every == 0) {
      std::cerr << "ins: t = " << ins.state().t_s << " s, " << result.imu_samples << " samples\r"
                << std::flush;
    }
  }
  if (options.progress_every && result.imu_samples >= options.progress_every) std::cerr << "\n";
  if (result.imu_samples == 0) {
    throw InputError(imu.path(), 0, "t",
                     "no IMU sample after the initial epoch t = " + std::to_string(initial.t_s) + " s");
  }
  result.final_state = ins.state();
  if (truth && stats.count() > 0) result.errors = stats;
  result.run_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace navtwin
