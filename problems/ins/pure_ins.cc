#include "problems/ins/pure_ins.h"

#include <chrono>
#include <cmath>
#include <iostream>
#include <sstream>
#include <string>

#include "core/io/input_error.h"
#include "core/io/plausibility.h"
#include "core/units.h"
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

void RequireMechanizable(const NavState& s, const std::string& source, const std::string& what) {
  const auto refuse = [&](const std::string& field, const auto&... why) {
    std::ostringstream os;
    os.precision(12);
    os << what << " at t = " << s.t_s << " s: ";
    (os << ... << why);
    throw InputError(source, 0, field, os.str());
  };
  if (!std::isfinite(s.lat_rad) || !std::isfinite(s.lon_rad) || !std::isfinite(s.h_m) || !s.v_n_mps.allFinite() ||
      !s.q_n_b.coeffs().allFinite()) {
    refuse("state", "not a finite number");
  }
  const double lat_deg = s.lat_rad * kRadToDeg;
  if (std::abs(lat_deg) >= 90.0 - kPolarMargin_deg) {
    refuse("lat", "latitude ", lat_deg, " deg is within ", kPolarMargin_deg,
           " deg of a pole, where the NED mechanization is singular");
  }
  if (s.h_m < plausible::kMinHeight_m || s.h_m > plausible::kMaxHeight_m) {
    refuse("h", "height ", s.h_m, " m outside the plausible band [", plausible::kMinHeight_m, ", ",
           plausible::kMaxHeight_m, "] m");
  }
  const double v_max = s.v_n_mps.cwiseAbs().maxCoeff();
  if (v_max > plausible::kMaxSpeed_mps) {
    refuse("v_n", "a velocity component of ", v_max, " m/s, above the plausible ", plausible::kMaxSpeed_mps, " m/s");
  }
}

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
    RequireMechanizable(ins.state(), imu.path(), "the solution (pure inertial navigation)");
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
