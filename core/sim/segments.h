// Segment-based trajectories: a scenario's flight as a list of manoeuvres (static, hover,
// accelerate, decelerate, climb, descend, turn, S-turns, wing rock, cruise), each lasting
// duration_s. The schema, the motion model and an example per kind are in
// docs/trajectories.md.
//
// Motion model: smooth scalar channels, speed V(t), heading psi(t), flight-path angle
// gamma(t) and roll/pitch/yaw overlays o(t), give
//   v_n   = V [cos(gamma) cos(psi), cos(gamma) sin(psi), -sin(gamma)]      (NED, m/s)
//   roll  = atan(V psi' / g0) + o_roll     (coordinated-turn bank of a level turn)
//   pitch = gamma + o_pitch,   yaw = psi + o_yaw.
// Every segment starts and ends in a steady state (all channel rates zero); inside it the
// channels change through rate profiles built from a smoothstep whose first three
// derivatives vanish at its ends, so every channel has continuous first, second and third
// derivatives: acceleration, jerk, angular rate and angular acceleration are continuous
// everywhere, including at segment boundaries.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/sim/analytic_trajectory.h"
#include "core/config/yaml_config.h"

namespace navtwin::sim {

enum class SegmentKind {
  kStatic,      ///< no motion: speed must be 0 at the start; the state is held
  kHover,       ///< speed 0 (must be 0 at the start), optional yaw rate
  kAccelerate,  ///< speed up to speed_mps, or at rate_mps2
  kDecelerate,  ///< slow down to speed_mps, or at rate_mps2
  kClimb,       ///< flight-path angle to a positive target (angle or vertical speed)
  kDescend,     ///< flight-path angle to a negative target (angle or vertical speed)
  kTurn,        ///< heading change at a turn rate, or spread over the segment
  kSTurns,      ///< heading oscillation psi0 + A sin(2 pi tau / period), faded in and out
  kWingRock,    ///< roll/pitch/yaw sinusoidal overlays, faded in and out
  kCruise,      ///< straight; level (flight path to 0) or holding the current state
};

/// One manoeuvre; SI units and radians. Only the fields of its kind are used.
struct SegmentConfig {
  SegmentKind kind = SegmentKind::kCruise;
  double duration_s = 0.0;
  std::optional<double> transition_s;  ///< overrides TrajectoryConfig::transition_s
  // accelerate / decelerate: a target speed or a rate magnitude (> 0).
  std::optional<double> speed_mps;
  std::optional<double> rate_mps2;
  // climb / descend: a target flight-path angle or vertical speed (up positive).
  std::optional<double> flight_path_rad;
  std::optional<double> vertical_speed_mps;
  // turn: signed heading change (positive clockwise seen from above, i.e. to the right)
  // at turn_rate_radps (magnitude > 0), or spread over the whole segment when absent.
  double heading_change_rad = 0.0;
  std::optional<double> turn_rate_radps;
  // s_turns: heading amplitude and period.
  double heading_amplitude_rad = 0.0;
  double period_s = 0.0;
  // wing_rock: (roll, pitch, yaw) overlay amplitudes and frequencies.
  Eigen::Vector3d amplitude_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d frequency_hz = Eigen::Vector3d::Zero();
  // hover: yaw rate.
  double yaw_rate_radps = 0.0;
  // cruise: true brings the flight-path angle to 0, false holds the current state.
  bool level = true;
};

struct TrajectoryConfig {
  double initial_speed_mps = 0.0;
  double initial_heading_rad = 0.0;
  double initial_flight_path_rad = 0.0;
  /// Constant (roll, pitch, yaw) offsets added to the attitude, e.g. angle of attack.
  Eigen::Vector3d attitude_offset_rad = Eigen::Vector3d::Zero();
  /// Duration of each smooth change (s); a segment uses at most what fits in it.
  double transition_s = 2.0;
  std::vector<SegmentConfig> segments;
};

/// Parses the scenario's `trajectory:` mapping (see docs/trajectories.md). Throws
/// InputError naming the file, line and key path for unknown keys, missing or
/// impossible values, and for segments the state before them cannot perform (e.g. a
/// static segment while moving, a deceleration below zero speed).
TrajectoryConfig ParseTrajectoryConfig(const ConfigNode& node);

namespace detail {
/// A channel's motion inside one segment (tau = time since the segment start).
struct ChannelProfile {
  // Trapezoidal rate: 0 -> plateau over ramp_s, plateau, plateau -> 0 over ramp_s, active
  // from tau = 0 for active_s (ramp_s <= active_s / 2); the value changes by
  // plateau * (active_s - ramp_s).
  double plateau = 0.0, ramp_s = 0.0, active_s = 0.0;
  // Oscillation amplitude * sin(omega * tau) under an envelope faded in over fade_s after
  // the segment start and out over fade_s before its end (it ends where it started).
  double amplitude = 0.0, omega_radps = 0.0, fade_s = 0.0;
};
/// Channels: speed, heading, flight-path angle, roll/pitch/yaw overlays.
enum Channel { kSpeed, kHeading, kFlightPath, kRollOverlay, kPitchOverlay, kYawOverlay };
constexpr int kChannels = 6;
struct SegmentPlan {
  double start_s = 0.0, duration_s = 0.0;
  std::array<double, kChannels> start_value{};  ///< channel values at the segment start
  std::array<ChannelProfile, kChannels> profile{};
};
}  // namespace detail

class SegmentTrajectory : public AnalyticTrajectory {
 public:
  /// Throws std::invalid_argument for a configuration ParseTrajectoryConfig would reject.
  explicit SegmentTrajectory(const TrajectoryConfig& config);

  Eigen::Vector3d Euler_rad(double t_s) const override;
  Eigen::Vector3d EulerRate_radps(double t_s) const override;
  Eigen::Vector3d Velocity_n_mps(double t_s) const override;
  Eigen::Vector3d Acceleration_n_mps2(double t_s) const override;
  TrajectoryPoint PointAt(double t_s) const override;

  /// Sum of the segment durations; before 0 and after it the end states are held.
  double duration_s() const;

  /// Channel values and their first and second time derivatives at t.
  struct Channels {
    std::array<double, detail::kChannels> value{}, rate{}, accel{};
  };

 private:
  /// The channels at t; the last evaluation is remembered per thread (the truth generator
  /// asks for the same instant several times in a row).
  Channels Evaluate(double t_s) const;
  Channels EvaluateUncached(double t_s) const;
  static std::uint64_t NextId() {
    static std::atomic<std::uint64_t> next{1};
    return next++;
  }
  const std::uint64_t id_ = NextId();

  std::vector<detail::SegmentPlan> segments_;
  std::vector<double> starts_s_;  ///< segment start times, for the binary search
};

}  // namespace navtwin::sim
