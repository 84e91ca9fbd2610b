#include "core/sim/segments.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/rotation.h"
#include "core/units.h"

namespace navtwin::sim {
namespace {

using detail::ChannelProfile;
using detail::SegmentPlan;

// Standard gravity for the coordinated-turn bank atan(V psi' / g0): the bank is a shape
// chosen for the trajectory, so a fixed g keeps it independent of position.
// A static or hover segment needs speed 0 at its start; a deceleration computed to end at
// 0 may leave rounding of this size.
constexpr double kRestSpeedTolerance_mps = 1e-9;
// Slack when checking that a turn at a given rate fits in its segment (s).
constexpr double kFitTolerance_s = 1e-9;
constexpr double kMaxPitch_rad = M_PI / 2.0;

// ---------------------------------------------------------------------------------------
// Channel shapes

// The septic smoothstep s(x) = 35x^4 - 84x^5 + 70x^6 - 20x^7 on [0, 1] (s(0) = 0,
// s(1) = 1, s', s'' and s''' zero at both ends), its derivatives and its integral from 0
// (1/2 at x = 1). The zero s''' keeps the bank's second derivative, which involves the
// heading's third, continuous: angular acceleration is continuous at every ramp end.
struct Smoothstep {
  double integral, value, slope, curvature;
};

Smoothstep Septic(double x) {
  const double x2 = x * x, x3 = x2 * x, x4 = x2 * x2, y = 1.0 - x;
  return {x4 * x * (7.0 + x * (-14.0 + x * (10.0 - 2.5 * x))),
          x4 * (35.0 + x * (-84.0 + x * (70.0 - 20.0 * x))), 140.0 * x3 * y * y * y,
          420.0 * x2 * y * y * (1.0 - 2.0 * x)};
}

// A value and its first and second time derivatives.
struct Jet {
  double value = 0.0, rate = 0.0, accel = 0.0;
};

// The trapezoidal-rate part of a profile at tau (s since the segment start).
Jet TrapezoidAt(const ChannelProfile& p, double tau) {
  if (p.plateau == 0.0 || tau <= 0.0) return {};
  const double r = p.plateau, ramp = p.ramp_s;
  if (tau < ramp) {  // rate rising 0 -> r
    const Smoothstep s = Septic(tau / ramp);
    return {r * ramp * s.integral, r * s.value, r * s.slope / ramp};
  }
  if (tau <= p.active_s - ramp) return {r * (tau - 0.5 * ramp), r, 0.0};
  const double total = r * (p.active_s - ramp);
  if (tau >= p.active_s) return {total, 0.0, 0.0};
  const Smoothstep s = Septic((p.active_s - tau) / ramp);  // rate falling r -> 0
  return {total - r * ramp * s.integral, r * s.value, -r * s.slope / ramp};
}

// The oscillation part of a profile at tau in a segment of duration_s.
Jet OscillationAt(const ChannelProfile& p, double tau, double duration_s) {
  if (p.amplitude == 0.0) return {};
  Jet envelope{1.0, 0.0, 0.0};
  if (tau < p.fade_s) {
    const Smoothstep s = Septic(tau / p.fade_s);
    envelope = {s.value, s.slope / p.fade_s, s.curvature / (p.fade_s * p.fade_s)};
  } else if (tau > duration_s - p.fade_s) {
    const Smoothstep s = Septic((duration_s - tau) / p.fade_s);
    envelope = {s.value, -s.slope / p.fade_s, s.curvature / (p.fade_s * p.fade_s)};
  }
  const double w = p.omega_radps;
  const double sine = p.amplitude * std::sin(w * tau), cosine = p.amplitude * std::cos(w * tau);
  return {envelope.value * sine, envelope.rate * sine + envelope.value * w * cosine,
          envelope.accel * sine + 2.0 * envelope.rate * w * cosine - envelope.value * w * w * sine};
}

// Value change over a whole segment of the trapezoidal part.
double TrapezoidChange(const ChannelProfile& p) {
  return p.plateau == 0.0 ? 0.0 : p.plateau * (p.active_s - p.ramp_s);
}

// A change `delta` spread over a segment of duration_s: ramps of min(transition, D/2),
// constant rate in between.
ChannelProfile Spread(double delta, double duration_s, double transition_s) {
  ChannelProfile p;
  p.ramp_s = std::min(transition_s, 0.5 * duration_s);
  p.active_s = duration_s;
  p.plateau = delta / (duration_s - p.ramp_s);
  return p;
}

// A change `delta` made at the segment start over step_s (rate: a smooth bell).
ChannelProfile Step(double delta, double step_s) {
  ChannelProfile p;
  p.ramp_s = 0.5 * step_s;
  p.active_s = step_s;
  p.plateau = delta / p.ramp_s;
  return p;
}

// ---------------------------------------------------------------------------------------
// Planning: from the configuration to per-segment channel profiles, with every check.

// Where a configuration problem is: a segment index, or one of these.
constexpr long kTrajectoryLevel = -2, kInitialLevel = -1;
using FailFn = std::function<void(long where, const std::string& key, const std::string& reason)>;

std::string Number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

class Planner {
 public:
  // `fail` reports a problem (and must throw); without it, std::invalid_argument is thrown.
  Planner(const TrajectoryConfig& config, FailFn fail) : config_(config), fail_(std::move(fail)) {}

  std::vector<SegmentPlan> Plan() {
    CheckTrajectoryLevel();
    state_ = {config_.initial_speed_mps,       config_.initial_heading_rad,
              config_.initial_flight_path_rad, config_.attitude_offset_rad.x(),
              config_.attitude_offset_rad.y(), config_.attitude_offset_rad.z()};
    std::vector<SegmentPlan> plans;
    double start_s = 0.0;
    for (index_ = 0; index_ < static_cast<long>(config_.segments.size()); ++index_) {
      const SegmentConfig& seg = config_.segments[index_];
      if (!(seg.duration_s > 0.0)) Reject("duration_s", "must be > 0");
      if (seg.transition_s && !(*seg.transition_s > 0.0)) Reject("transition_s", "must be > 0");
      SegmentPlan plan;
      plan.start_s = start_s;
      plan.duration_s = seg.duration_s;
      plan.start_value = state_;
      PlanSegment(seg, seg.transition_s.value_or(config_.transition_s), plan);
      plans.push_back(plan);
      start_s += seg.duration_s;
    }
    return plans;
  }

 private:
  [[noreturn]] void Fail(long where, const std::string& key, const std::string& reason) const {
    if (fail_) fail_(where, key, reason);
    std::string place = "trajectory.";
    if (where == kInitialLevel) place += "initial.";
    if (where >= 0) place += "segments[" + std::to_string(where) + "].";
    throw std::invalid_argument(place + key + ": " + reason);
  }
  [[noreturn]] void Reject(const std::string& key, const std::string& reason) const {
    Fail(index_, key, reason);
  }

  void CheckTrajectoryLevel() const {
    if (!(config_.transition_s > 0.0)) Fail(kTrajectoryLevel, "transition_s", "must be > 0");
    if (config_.segments.empty()) Fail(kTrajectoryLevel, "segments", "needs at least one segment");
    if (!(config_.initial_speed_mps >= 0.0)) Fail(kInitialLevel, "speed_mps", "must be >= 0");
    if (!(std::abs(config_.initial_flight_path_rad) < kMaxPitch_rad)) {
      Fail(kInitialLevel, "flight_path_deg", "must be strictly between -90 and 90");
    }
    if (!(std::abs(config_.initial_flight_path_rad) + std::abs(config_.attitude_offset_rad.y()) <
          kMaxPitch_rad)) {
      Fail(kInitialLevel, "pitch_offset_deg",
           "flight path plus pitch offset must stay strictly between -90 and 90 deg");
    }
  }

  void PlanSegment(const SegmentConfig& seg, double transition_s, SegmentPlan& plan) {
    switch (seg.kind) {
      case SegmentKind::kStatic:
        return RequireRest("static");
      case SegmentKind::kHover:
        return PlanHover(seg, transition_s, plan);
      case SegmentKind::kAccelerate:
      case SegmentKind::kDecelerate:
        return PlanSpeed(seg, transition_s, plan);
      case SegmentKind::kClimb:
      case SegmentKind::kDescend:
        return PlanClimb(seg, transition_s, plan);
      case SegmentKind::kTurn:
        return PlanTurn(seg, transition_s, plan);
      case SegmentKind::kSTurns:
        return PlanSTurns(seg, transition_s, plan);
      case SegmentKind::kWingRock:
        return PlanWingRock(seg, transition_s, plan);
      case SegmentKind::kCruise:
        return PlanCruise(seg, transition_s, plan);
    }
  }

  void RequireRest(const char* kind) const {
    if (std::abs(state_[detail::kSpeed]) > kRestSpeedTolerance_mps) {
      Reject("kind", std::string("a ") + kind + " segment needs speed 0 at its start (it is " +
                         Number(state_[detail::kSpeed]) + " m/s): decelerate to 0 first");
    }
  }

  void PlanHover(const SegmentConfig& seg, double transition_s, SegmentPlan& plan) {
    RequireRest("hover");
    if (seg.yaw_rate_radps == 0.0) return;
    ChannelProfile& p = plan.profile[detail::kHeading];
    p.ramp_s = std::min(transition_s, 0.5 * seg.duration_s);
    p.active_s = seg.duration_s;
    p.plateau = seg.yaw_rate_radps;
    state_[detail::kHeading] += TrapezoidChange(p);
  }

  void PlanSpeed(const SegmentConfig& seg, double transition_s, SegmentPlan& plan) {
    const bool up = seg.kind == SegmentKind::kAccelerate;
    const char* rate_key = up ? "acceleration_mps2" : "deceleration_mps2";
    const double v0 = state_[detail::kSpeed];
    if (seg.speed_mps.has_value() == seg.rate_mps2.has_value()) {
      Reject(seg.speed_mps ? rate_key : "",
             std::string("give exactly one of speed_mps and ") + rate_key);
    }
    double v1;
    if (seg.speed_mps) {
      v1 = *seg.speed_mps;
      if (!(v1 >= 0.0)) Reject("speed_mps", "must be >= 0");
      if (up ? v1 < v0 : v1 > v0) {
        Reject("speed_mps", std::string("must be ") + (up ? "at least" : "at most") +
                                " the speed at the segment start, " + Number(v0) + " m/s");
      }
      plan.profile[detail::kSpeed] = Spread(v1 - v0, seg.duration_s, transition_s);
    } else {
      if (!(*seg.rate_mps2 > 0.0)) Reject(rate_key, "must be > 0 (a magnitude)");
      ChannelProfile& p = plan.profile[detail::kSpeed];
      p = Spread(0.0, seg.duration_s, transition_s);
      p.plateau = up ? *seg.rate_mps2 : -*seg.rate_mps2;
      v1 = v0 + TrapezoidChange(p);
      if (v1 < -kRestSpeedTolerance_mps) {
        Reject(rate_key, "would take the speed from " + Number(v0) + " m/s below 0 (to " +
                             Number(v1) + " m/s)");
      }
      v1 = std::max(v1, 0.0);
    }
    state_[detail::kSpeed] = v1;
  }

  double ClimbTarget(const SegmentConfig& seg) const {
    const bool up = seg.kind == SegmentKind::kClimb;
    if (seg.flight_path_rad.has_value() == seg.vertical_speed_mps.has_value()) {
      Reject(seg.flight_path_rad ? "vertical_speed_mps" : "",
             "give exactly one of flight_path_deg and vertical_speed_mps");
    }
    const char* key = seg.flight_path_rad ? "flight_path_deg" : "vertical_speed_mps";
    const double given = seg.flight_path_rad ? *seg.flight_path_rad : *seg.vertical_speed_mps;
    if (up ? !(given > 0.0) : !(given < 0.0)) {
      Reject(key, std::string("a ") + (up ? "climb" : "descent") + " needs a " +
                      (up ? "positive" : "negative") + " value (up is positive)");
    }
    if (seg.flight_path_rad) return given;
    const double v = state_[detail::kSpeed];
    if (!(std::abs(given) < v)) {
      Reject(key, "must be smaller in magnitude than the speed at the segment start, " + Number(v) +
                      " m/s");
    }
    return std::asin(given / v);
  }

  void PlanClimb(const SegmentConfig& seg, double transition_s, SegmentPlan& plan) {
    const double target = ClimbTarget(seg);
    const char* key = seg.flight_path_rad ? "flight_path_deg" : "vertical_speed_mps";
    if (!(std::abs(target) + std::abs(state_[detail::kPitchOverlay]) < kMaxPitch_rad)) {
      Reject(key, "the flight path (" + Number(target * kRadToDeg) +
                      " deg) plus the pitch offset must stay strictly between -90 and 90 deg");
    }
    plan.profile[detail::kFlightPath] =
        Step(target - state_[detail::kFlightPath], std::min(transition_s, seg.duration_s));
    state_[detail::kFlightPath] = target;
  }

  void PlanTurn(const SegmentConfig& seg, double transition_s, SegmentPlan& plan) {
    const double change = seg.heading_change_rad;
    if (seg.turn_rate_radps && !(*seg.turn_rate_radps > 0.0)) {
      Reject("turn_rate_deg_s", "must be > 0 (a magnitude; the sign of the change turns)");
    }
    if (change == 0.0) return;
    if (!seg.turn_rate_radps) {
      plan.profile[detail::kHeading] = Spread(change, seg.duration_s, transition_s);
    } else {
      const double rate = *seg.turn_rate_radps, at_rate_s = std::abs(change) / rate;
      ChannelProfile& p = plan.profile[detail::kHeading];
      p.ramp_s = std::min(transition_s, at_rate_s);
      p.active_s = at_rate_s + p.ramp_s;
      p.plateau = std::copysign(rate, change);
      if (p.active_s > seg.duration_s + kFitTolerance_s) {
        Reject("turn_rate_deg_s", "the turn needs " + Number(p.active_s) +
                                      " s with its transitions, more than duration_s");
      }
    }
    state_[detail::kHeading] += change;
  }

  void PlanSTurns(const SegmentConfig& seg, double transition_s, SegmentPlan& plan) const {
    if (!(seg.heading_amplitude_rad >= 0.0)) Reject("heading_amplitude_deg", "must be >= 0");
    if (!(seg.period_s > 0.0)) Reject("period_s", "must be > 0");
    ChannelProfile& p = plan.profile[detail::kHeading];
    p.amplitude = seg.heading_amplitude_rad;
    p.omega_radps = 2.0 * M_PI / seg.period_s;
    p.fade_s = std::min(transition_s, 0.5 * seg.duration_s);
  }

  void PlanWingRock(const SegmentConfig& seg, double transition_s, SegmentPlan& plan) const {
    static const char* const kAxes[3] = {"roll", "pitch", "yaw"};
    for (int axis = 0; axis < 3; ++axis) {
      const std::string name = kAxes[axis];
      const double amplitude = seg.amplitude_rad[axis], f = seg.frequency_hz[axis];
      if (!(amplitude >= 0.0)) Reject(name + "_amplitude_deg", "must be >= 0");
      if (amplitude == 0.0) continue;
      if (!(f > 0.0)) Reject(name + "_frequency_hz", "must be > 0 when the amplitude is not 0");
      ChannelProfile& p = plan.profile[detail::kRollOverlay + axis];
      p.amplitude = amplitude;
      p.omega_radps = 2.0 * M_PI * f;
      p.fade_s = std::min(transition_s, 0.5 * seg.duration_s);
    }
    if (!(std::abs(state_[detail::kFlightPath]) + std::abs(state_[detail::kPitchOverlay]) +
              seg.amplitude_rad.y() <
          kMaxPitch_rad)) {
      Reject("pitch_amplitude_deg",
             "flight path, pitch offset and amplitude must stay below 90 deg in magnitude");
    }
  }

  void PlanCruise(const SegmentConfig& seg, double transition_s, SegmentPlan& plan) {
    if (!seg.level || state_[detail::kFlightPath] == 0.0) return;
    plan.profile[detail::kFlightPath] =
        Step(-state_[detail::kFlightPath], std::min(transition_s, seg.duration_s));
    state_[detail::kFlightPath] = 0.0;
  }

  const TrajectoryConfig& config_;
  const FailFn fail_;
  std::array<double, detail::kChannels> state_{};  // channel values at the current time
  long index_ = 0;                                 // the segment being planned
};

// ---------------------------------------------------------------------------------------
// Parsing

std::optional<double> OptionalDouble(const ConfigNode& n, const std::string& key, double scale) {
  if (!n.Has(key)) return std::nullopt;
  return scale * n.Double(key, 0.0);
}

SegmentKind ParseKind(const ConfigNode& n) {
  static const std::pair<const char*, SegmentKind> kKinds[] = {
      {"static", SegmentKind::kStatic},
      {"hover", SegmentKind::kHover},
      {"accelerate", SegmentKind::kAccelerate},
      {"decelerate", SegmentKind::kDecelerate},
      {"climb", SegmentKind::kClimb},
      {"descend", SegmentKind::kDescend},
      {"turn", SegmentKind::kTurn},
      {"s_turns", SegmentKind::kSTurns},
      {"wing_rock", SegmentKind::kWingRock},
      {"cruise", SegmentKind::kCruise}};
  const std::string kind = n.String("kind", "");
  std::string known;
  for (const auto& k : kKinds) {
    if (kind == k.first) return k.second;
    known += (known.empty() ? "" : ", ") + std::string(k.first);
  }
  n.Fail("kind",
         (kind.empty() ? "required" : "unknown kind '" + kind + "'") + " (one of: " + known + ")");
}

// Checks the keys allowed for the segment's kind (the common ones are kind, duration_s
// and transition_s).
void RequireSegmentKeys(const ConfigNode& n, SegmentKind kind) {
  switch (kind) {
    case SegmentKind::kStatic:
      return n.RequireKeys({"kind", "duration_s", "transition_s"});
    case SegmentKind::kHover:
      return n.RequireKeys({"kind", "duration_s", "transition_s", "yaw_rate_deg_s"});
    case SegmentKind::kAccelerate:
      return n.RequireKeys(
          {"kind", "duration_s", "transition_s", "speed_mps", "acceleration_mps2"});
    case SegmentKind::kDecelerate:
      return n.RequireKeys(
          {"kind", "duration_s", "transition_s", "speed_mps", "deceleration_mps2"});
    case SegmentKind::kClimb:
    case SegmentKind::kDescend:
      return n.RequireKeys(
          {"kind", "duration_s", "transition_s", "flight_path_deg", "vertical_speed_mps"});
    case SegmentKind::kTurn:
      return n.RequireKeys(
          {"kind", "duration_s", "transition_s", "heading_change_deg", "turn_rate_deg_s"});
    case SegmentKind::kSTurns:
      return n.RequireKeys(
          {"kind", "duration_s", "transition_s", "heading_amplitude_deg", "period_s"});
    case SegmentKind::kWingRock:
      return n.RequireKeys({"kind", "duration_s", "transition_s", "roll_amplitude_deg",
                            "roll_frequency_hz", "pitch_amplitude_deg", "pitch_frequency_hz",
                            "yaw_amplitude_deg", "yaw_frequency_hz"});
    case SegmentKind::kCruise:
      return n.RequireKeys({"kind", "duration_s", "transition_s", "level"});
  }
}

SegmentConfig ParseSegment(const ConfigNode& n) {
  if (!n.yaml().IsMap()) n.Fail("", "expected a mapping with kind and duration_s");
  SegmentConfig s;
  s.kind = ParseKind(n);
  RequireSegmentKeys(n, s.kind);
  s.duration_s = n.RequiredDouble("duration_s");
  s.transition_s = OptionalDouble(n, "transition_s", 1.0);
  s.speed_mps = OptionalDouble(n, "speed_mps", 1.0);
  s.rate_mps2 = OptionalDouble(
      n, s.kind == SegmentKind::kDecelerate ? "deceleration_mps2" : "acceleration_mps2", 1.0);
  s.flight_path_rad = OptionalDouble(n, "flight_path_deg", kDegToRad);
  s.vertical_speed_mps = OptionalDouble(n, "vertical_speed_mps", 1.0);
  if (s.kind == SegmentKind::kTurn) {
    s.heading_change_rad = kDegToRad * n.RequiredDouble("heading_change_deg");
  }
  s.turn_rate_radps = OptionalDouble(n, "turn_rate_deg_s", kDegToRad);
  if (s.kind == SegmentKind::kSTurns) {
    s.heading_amplitude_rad = kDegToRad * n.RequiredDouble("heading_amplitude_deg");
    s.period_s = n.RequiredDouble("period_s");
  }
  s.amplitude_rad = kDegToRad * Eigen::Vector3d(n.Double("roll_amplitude_deg", 0.0),
                                                n.Double("pitch_amplitude_deg", 0.0),
                                                n.Double("yaw_amplitude_deg", 0.0));
  s.frequency_hz =
      Eigen::Vector3d(n.Double("roll_frequency_hz", 0.0), n.Double("pitch_frequency_hz", 0.0),
                      n.Double("yaw_frequency_hz", 0.0));
  s.yaw_rate_radps = kDegToRad * n.Double("yaw_rate_deg_s", 0.0);
  s.level = n.Bool("level", true);
  return s;
}

}  // namespace

TrajectoryConfig ParseTrajectoryConfig(const ConfigNode& node) {
  node.RequireKeys({"kind", "initial", "transition_s", "segments"});
  if (node.String("kind", "segments") != "segments") node.Fail("kind", "expected segments");
  const ConfigNode initial = node.Child("initial");
  initial.RequireKeys({"speed_mps", "heading_deg", "flight_path_deg", "roll_offset_deg",
                       "pitch_offset_deg", "yaw_offset_deg"});
  TrajectoryConfig c;
  c.initial_speed_mps = initial.Double("speed_mps", 0.0);
  c.initial_heading_rad = kDegToRad * initial.Double("heading_deg", 0.0);
  c.initial_flight_path_rad = kDegToRad * initial.Double("flight_path_deg", 0.0);
  c.attitude_offset_rad = kDegToRad * Eigen::Vector3d(initial.Double("roll_offset_deg", 0.0),
                                                      initial.Double("pitch_offset_deg", 0.0),
                                                      initial.Double("yaw_offset_deg", 0.0));
  c.transition_s = node.Double("transition_s", c.transition_s);
  if (!node.Has("segments")) node.Fail("segments", "required (a list of segments)");
  const std::vector<ConfigNode> elements = node.Elements("segments");
  for (const ConfigNode& e : elements) c.segments.push_back(ParseSegment(e));
  // The checks that need the state before each segment, reported at the segment's line.
  const FailFn fail = [&](long where, const std::string& key, const std::string& reason) {
    if (where == kTrajectoryLevel) node.Fail(key, reason);
    if (where == kInitialLevel) initial.Fail(key, reason);
    elements.at(static_cast<std::size_t>(where)).Fail(key, reason);
  };
  Planner(c, fail).Plan();
  return c;
}

SegmentTrajectory::SegmentTrajectory(const TrajectoryConfig& config)
    : segments_(Planner(config, nullptr).Plan()) {
  for (const SegmentPlan& s : segments_) starts_s_.push_back(s.start_s);
}

double SegmentTrajectory::duration_s() const {
  return segments_.back().start_s + segments_.back().duration_s;
}

SegmentTrajectory::Channels SegmentTrajectory::Evaluate(double t_s) const {
  struct Cache {
    std::uint64_t owner = 0;  // id_ of the trajectory (an address could be reused)
    double t_s = 0.0;
    Channels channels;
  };
  thread_local Cache cache;
  if (cache.owner != id_ || cache.t_s != t_s) {
    cache.channels = EvaluateUncached(t_s);
    cache.owner = id_;
    cache.t_s = t_s;
  }
  return cache.channels;
}

SegmentTrajectory::Channels SegmentTrajectory::EvaluateUncached(double t_s) const {
  // The segment holding t: the last start <= t (the first one for t < 0).
  const auto after = std::upper_bound(starts_s_.begin(), starts_s_.end(), t_s);
  const SegmentPlan& seg =
      segments_[after == starts_s_.begin() ? 0 : (after - starts_s_.begin()) - 1];
  const double tau = std::clamp(t_s - seg.start_s, 0.0, seg.duration_s);
  Channels c;
  for (int i = 0; i < detail::kChannels; ++i) {
    const Jet a = TrapezoidAt(seg.profile[i], tau);
    const Jet b = OscillationAt(seg.profile[i], tau, seg.duration_s);
    c.value[i] = seg.start_value[i] + a.value + b.value;
    c.rate[i] = a.rate + b.rate;
    c.accel[i] = a.accel + b.accel;
  }
  return c;
}

namespace {

using Channels = SegmentTrajectory::Channels;

Eigen::Vector3d EulerOf(const Channels& c) {
  using namespace detail;
  const double bank = std::atan(c.value[kSpeed] * c.rate[kHeading] / kStandardGravity_mps2);
  return {bank + c.value[kRollOverlay], c.value[kFlightPath] + c.value[kPitchOverlay],
          c.value[kHeading] + c.value[kYawOverlay]};
}

Eigen::Vector3d EulerRateOf(const Channels& c) {
  using namespace detail;
  // d/dt atan(q) with q = V psi' / g0.
  const double q = c.value[kSpeed] * c.rate[kHeading] / kStandardGravity_mps2;
  const double dq =
      (c.rate[kSpeed] * c.rate[kHeading] + c.value[kSpeed] * c.accel[kHeading]) / kStandardGravity_mps2;
  return {dq / (1.0 + q * q) + c.rate[kRollOverlay], c.rate[kFlightPath] + c.rate[kPitchOverlay],
          c.rate[kHeading] + c.rate[kYawOverlay]};
}

Eigen::Vector3d VelocityOf(const Channels& c) {
  using namespace detail;
  const double v = c.value[kSpeed], psi = c.value[kHeading], gamma = c.value[kFlightPath];
  return v * Eigen::Vector3d(std::cos(gamma) * std::cos(psi), std::cos(gamma) * std::sin(psi),
                             -std::sin(gamma));
}

Eigen::Vector3d AccelerationOf(const Channels& c) {
  using namespace detail;
  const double v = c.value[kSpeed], dv = c.rate[kSpeed];
  const double cp = std::cos(c.value[kHeading]), sp = std::sin(c.value[kHeading]);
  const double cg = std::cos(c.value[kFlightPath]), sg = std::sin(c.value[kFlightPath]);
  const double dpsi = c.rate[kHeading], dgamma = c.rate[kFlightPath];
  // d/dt of V u(psi, gamma) = V' u + V (du/dpsi psi' + du/dgamma gamma').
  return dv * Eigen::Vector3d(cg * cp, cg * sp, -sg) +
         v * Eigen::Vector3d(-sg * dgamma * cp - cg * sp * dpsi, -sg * dgamma * sp + cg * cp * dpsi,
                             -cg * dgamma);
}

}  // namespace

Eigen::Vector3d SegmentTrajectory::Euler_rad(double t_s) const { return EulerOf(Evaluate(t_s)); }
Eigen::Vector3d SegmentTrajectory::EulerRate_radps(double t_s) const {
  return EulerRateOf(Evaluate(t_s));
}
Eigen::Vector3d SegmentTrajectory::Velocity_n_mps(double t_s) const {
  return VelocityOf(Evaluate(t_s));
}
Eigen::Vector3d SegmentTrajectory::Acceleration_n_mps2(double t_s) const {
  return AccelerationOf(Evaluate(t_s));
}

TrajectoryPoint SegmentTrajectory::PointAt(double t_s) const {
  const Channels c = Evaluate(t_s);
  return {EulerOf(c), EulerRateOf(c), VelocityOf(c), AccelerationOf(c)};
}

}  // namespace navtwin::sim
