#include "core/sim/segments.h"
#include "tests/core/sim/round_trip.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/input_error.h"
#include "core/rotation.h"
#include "core/strapdown.h"
#include "core/units.h"

namespace navtwin::sim {
namespace sim_segments_test {


// Every segment kind, ~10 min (590 s). Speeds: 0 -> 30 -> 48 -> 6 -> 0 m/s; heading
// 90 -> 180 (hover) -> 270 (turn) -> 150 (turn at 6 deg/s) -> -130 deg (hover).
const char* const kEveryKind = R"(trajectory:
  initial: {speed_mps: 0, heading_deg: 90, flight_path_deg: 0, pitch_offset_deg: 2}
  transition_s: 2
  segments:
    - {kind: static, duration_s: 30}
    - {kind: hover, duration_s: 20, yaw_rate_deg_s: 5}
    - {kind: accelerate, duration_s: 20, speed_mps: 30}
    - {kind: turn, duration_s: 30, heading_change_deg: 90}
    - {kind: climb, duration_s: 40, vertical_speed_mps: 5}
    - {kind: cruise, duration_s: 30}
    - {kind: turn, duration_s: 40, heading_change_deg: -120, turn_rate_deg_s: 6}
    - {kind: s_turns, duration_s: 120, heading_amplitude_deg: 20, period_s: 40}
    - {kind: descend, duration_s: 30, flight_path_deg: -3, transition_s: 4}
    - {kind: wing_rock, duration_s: 60, roll_amplitude_deg: 10, roll_frequency_hz: 0.5,
       pitch_amplitude_deg: 3, pitch_frequency_hz: 0.3, yaw_amplitude_deg: 2,
       yaw_frequency_hz: 0.2}
    - {kind: cruise, duration_s: 20, level: false}
    - {kind: cruise, duration_s: 30}
    - {kind: accelerate, duration_s: 20, acceleration_mps2: 1}
    - {kind: decelerate, duration_s: 30, deceleration_mps2: 1.5}
    - {kind: decelerate, duration_s: 20, speed_mps: 0}
    - {kind: hover, duration_s: 30, yaw_rate_deg_s: -10}
    - {kind: static, duration_s: 20}
)";

TrajectoryConfig Parse(const std::string& yaml) {
  return ParseTrajectoryConfig(ParseYaml(yaml, "scenario.yaml").Child("trajectory"));
}

std::vector<double> SegmentStarts(const TrajectoryConfig& config) {
  std::vector<double> starts{0.0};
  for (const SegmentConfig& s : config.segments) starts.push_back(starts.back() + s.duration_s);
  return starts;  // one more than the segments: the last is the end
}

// Where the channels' pieces meet: segment boundaries, ends of the 2 s (4 s in the
// descent) transitions and the midpoints of 2 s steps, and the end of the rate turn
// (segment 6: 20 s at 6 deg/s plus a 2 s ramp).
std::vector<double> Knots(const TrajectoryConfig& config) {
  const std::vector<double> starts = SegmentStarts(config);
  std::vector<double> knots;
  for (std::size_t i = 0; i < config.segments.size(); ++i) {
    for (const double offset : {0.0, 1.0, 2.0, 4.0}) knots.push_back(starts[i] + offset);
    knots.push_back(starts[i + 1] - 2.0);
  }
  knots.push_back(starts[6] + 20.0);
  knots.push_back(starts[6] + 22.0);
  knots.push_back(starts.back());
  return knots;
}

// Test times: a 0.37 s grid over the flight and 10 s beyond it, and every knot and
// knot +- 1e-6 s.
std::vector<double> TestTimes(const TrajectoryConfig& config) {
  std::vector<double> times;
  const double end = SegmentStarts(config).back();
  for (double t = 0.0; t < end + 10.0; t += 0.37) times.push_back(t);
  for (const double k : Knots(config)) {
    for (const double d : {-1e-6, 0.0, 1e-6}) times.push_back(std::max(0.0, k + d));
  }
  return times;
}

TEST(SegmentTrajectory, AnalyticDerivativesMatchCentralDifferences) {
  const TrajectoryConfig config = Parse(kEveryKind);
  const SegmentTrajectory traj(config);
  const double h = 1e-5;
  double max_euler_err = 0.0, max_accel_err = 0.0;
  for (const double t : TestTimes(config)) {
    // The step as represented (t + h rounds to the spacing of doubles near t, ~1e-13 s at
    // t = 500 s, a relative step error of ~1e-8 if 2h were used).
    const double tp = t + h, tm = t - h, step = tp - tm;
    const Eigen::Vector3d de = (traj.Euler_rad(tp) - traj.Euler_rad(tm)) / step;
    const Eigen::Vector3d dv = (traj.Velocity_n_mps(tp) - traj.Velocity_n_mps(tm)) / step;
    max_euler_err = std::max(max_euler_err, (de - traj.EulerRate_radps(t)).norm());
    max_accel_err = std::max(max_accel_err, (dv - traj.Acceleration_n_mps2(t)).norm());
  }
  // Every channel has continuous third derivatives, so the central difference errs by
  // h^2/6 |f'''| (f''' < ~20 rad/s^3 or m/s^3 here: < 4e-10) plus rounding eps |f| / h
  // (angles up to ~5 rad, speeds up to 48 m/s: < 1e-9). Measured: 2.7e-10 rad/s and
  // 1.4e-9 m/s^2. A wrong derivative term (e.g. the bank rate without V psi'') errs by
  // more than 1e-3.
  EXPECT_LT(max_euler_err, 1e-8);
  EXPECT_LT(max_accel_err, 1e-8);
}

TEST(SegmentTrajectory, MotionIsContinuousAtEveryKnot) {
  const TrajectoryConfig config = Parse(kEveryKind);
  const SegmentTrajectory traj(config);
  const double d = 1e-6;  // the two sides of a knot
  const double h = 1e-4;  // one-sided difference step for the second derivatives
  double max_angle_jump = 0.0, max_v_jump = 0.0, max_rate_jump = 0.0, max_accel_jump = 0.0;
  double max_alpha_jump = 0.0, max_jerk_jump = 0.0;
  for (const double k : Knots(config)) {
    const auto jump = [&](auto f) { return (f(k + d) - f(k - d)).norm(); };
    const auto kink = [&](auto f) {  // right minus left one-sided derivative at k
      return ((f(k + h) - f(k)) / h - (f(k) - f(k - h)) / h).norm();
    };
    const auto euler = [&](double t) { return traj.Euler_rad(t); };
    const auto rate = [&](double t) { return traj.EulerRate_radps(t); };
    const auto velocity = [&](double t) { return traj.Velocity_n_mps(t); };
    const auto accel = [&](double t) { return traj.Acceleration_n_mps2(t); };
    max_angle_jump = std::max(max_angle_jump, jump(euler));
    max_v_jump = std::max(max_v_jump, jump(velocity));
    max_rate_jump = std::max(max_rate_jump, jump(rate));
    max_accel_jump = std::max(max_accel_jump, jump(accel));
    max_alpha_jump = std::max(max_alpha_jump, kink(rate));
    max_jerk_jump = std::max(max_jerk_jump, kink(accel));
  }
  // Over 2e-6 s a continuous quantity moves by at most 2e-6 times its derivative's bound:
  // rates < 1 rad/s, accelerations < 5.1 m/s^2, angular accelerations < 2 rad/s^2 and
  // jerks < 5 m/s^3 here, so 2e-5 bounds every change (measured: 1.0e-5, the velocity).
  // The smallest jump a missing smooth ramp would cause is ~0.1 rad/s (the 6 deg/s turn)
  // or 1 m/s^2.
  EXPECT_LT(max_angle_jump, 2e-5);
  EXPECT_LT(max_v_jump, 2e-5);
  EXPECT_LT(max_rate_jump, 2e-5);
  EXPECT_LT(max_accel_jump, 2e-5);
  // One-sided differences of a C2 quantity differ by h times its second derivative's bound
  // (angular jerk and snap < ~20 here): 1e-2 (measured: 8e-4 rad/s^2, 1.1e-3 m/s^3). The
  // quintic smoothstep's jump in the roll acceleration (~2 rad/s^2 at the S-turn fade-in's
  // end) or a jerk step of a missing ramp (> 0.5 m/s^3) would fail.
  EXPECT_LT(max_alpha_jump, 1e-2);
  EXPECT_LT(max_jerk_jump, 1e-2);
}

TEST(SegmentTrajectory, SegmentsReachTheirTargets) {
  const TrajectoryConfig config = Parse(kEveryKind);
  const SegmentTrajectory traj(config);
  const std::vector<double> s = SegmentStarts(config);
  const auto heading_deg = [&](double t) { return traj.Euler_rad(t).z() * kRadToDeg; };
  const auto speed = [&](double t) { return traj.Velocity_n_mps(t).norm(); };
  // Sums of a few double operations on values of order 1e2: 1e-9 leaves ~1e4 ulps.
  const double tol = 1e-9;
  EXPECT_NEAR(traj.duration_s(), 590.0, tol);
  // static: at rest, attitude (0, 2 deg pitch offset, 90 deg) held.
  EXPECT_EQ(traj.Velocity_n_mps(15.0).norm(), 0.0);
  EXPECT_LT((traj.Euler_rad(15.0) - kDegToRad * Eigen::Vector3d(0, 2, 90)).norm(), tol);
  // hover: 5 deg/s after the 2 s ramp, 5 * (20 - 2) = 90 deg turned, still at rest.
  EXPECT_NEAR(traj.EulerRate_radps(s[1] + 10.0).z() * kRadToDeg, 5.0, tol);
  EXPECT_NEAR(heading_deg(s[2]), 180.0, tol);
  EXPECT_EQ(traj.Velocity_n_mps(s[1] + 10.0).norm(), 0.0);
  // accelerate to 30 m/s: constant 30 / (20 - 2) m/s^2 between the ramps.
  EXPECT_NEAR(speed(s[3]), 30.0, tol);
  EXPECT_NEAR(traj.Acceleration_n_mps2(s[2] + 10.0).norm(), 30.0 / 18.0, tol);
  // turn of 90 deg over 30 s: rate 90 / 28 deg/s, bank atan(V psi' / g).
  const double turn_rate = 90.0 / 28.0 * kDegToRad;
  EXPECT_NEAR(traj.EulerRate_radps(s[3] + 15.0).z(), turn_rate, tol);
  EXPECT_NEAR(traj.Euler_rad(s[3] + 15.0).x(), std::atan(30.0 * turn_rate / kStandardGravity_mps2), tol);
  EXPECT_NEAR(heading_deg(s[4]), 270.0, tol);
  EXPECT_NEAR(traj.Euler_rad(s[4]).x(), 0.0, tol);  // wings level after the turn
  // climb at 5 m/s: the flight path asin(5/30) is reached within the 2 s transition.
  EXPECT_NEAR(-traj.Velocity_n_mps(s[4] + 2.0).z(), 5.0, tol);
  EXPECT_NEAR(traj.Euler_rad(s[4] + 20.0).y(), std::asin(5.0 / 30.0) + 2 * kDegToRad, tol);
  // cruise levels off.
  EXPECT_NEAR(traj.Velocity_n_mps(s[5] + 2.0).z(), 0.0, tol);
  // turn at 6 deg/s: the plateau rate, then straight after 20 + 2 s.
  EXPECT_NEAR(traj.EulerRate_radps(s[6] + 10.0).z() * kRadToDeg, -6.0, tol);
  EXPECT_NEAR(heading_deg(s[6] + 22.0), 150.0, tol);
  EXPECT_EQ(traj.EulerRate_radps(s[6] + 30.0).z(), 0.0);
  // S-turns: +20 deg at tau = 50 s (sin(2 pi 50 / 40) = 1), back to 150 deg at the end.
  EXPECT_NEAR(heading_deg(s[7] + 50.0), 170.0, tol);
  EXPECT_NEAR(heading_deg(s[8]), 150.0, tol);
  // descend at -3 deg (4 s transition).
  EXPECT_NEAR(traj.Velocity_n_mps(s[8] + 4.0).z(), 30.0 * std::sin(3.0 * kDegToRad), tol);
  // wing rock: roll overlay 10 sin(2 pi 0.5 tau) deg, peaks at tau = 30.5 s; no bank.
  EXPECT_NEAR(traj.Euler_rad(s[9] + 30.5).x() * kRadToDeg, 10.0, tol);
  EXPECT_NEAR(traj.Euler_rad(s[10]).x(), 0.0, tol);
  // cruise with level: false keeps the descent; the next cruise levels.
  EXPECT_NEAR(traj.Velocity_n_mps(s[11]).z(), 30.0 * std::sin(3.0 * kDegToRad), tol);
  EXPECT_NEAR(traj.Velocity_n_mps(s[12]).z(), 0.0, tol);
  // accelerate at 1 m/s^2: 1 * (20 - 2) m/s gained; decelerate at 1.5: 1.5 * 28 lost.
  EXPECT_NEAR(speed(s[13]), 48.0, tol);
  EXPECT_NEAR(traj.Acceleration_n_mps2(s[12] + 10.0).norm(), 1.0, tol);
  EXPECT_NEAR(speed(s[14]), 6.0, tol);
  EXPECT_NEAR(speed(s[15]), 0.0, tol);
  // hover at -10 deg/s: -280 deg; the end state is held after the last segment.
  EXPECT_NEAR(heading_deg(s[16]), 150.0 - 280.0, tol);
  EXPECT_EQ(traj.Euler_rad(700.0), traj.Euler_rad(590.0));
  EXPECT_EQ(traj.Velocity_n_mps(700.0).norm(), 0.0);
}

// The trajectory is found by binary search over hundreds of segments.
TEST(SegmentTrajectory, ManySegmentsAreEvaluatedInTheirOwnSegment) {
  TrajectoryConfig config;
  config.initial_speed_mps = 10.0;
  for (int i = 0; i < 400; ++i) {
    SegmentConfig turn;
    turn.kind = SegmentKind::kTurn;
    turn.duration_s = 1.0 + (i % 3);  // uneven starts
    turn.heading_change_rad = (i % 2 == 0 ? 3.0 : 1.0) * kDegToRad;
    config.segments.push_back(turn);
  }
  const SegmentTrajectory traj(config);
  const std::vector<double> starts = SegmentStarts(config);
  double heading_deg = 0.0;
  for (int i = 0; i < 400; ++i) {
    // Rounding over 400 additions of values up to 800 deg.
    EXPECT_NEAR(traj.Euler_rad(starts[i]).z() * kRadToDeg, heading_deg, 1e-10);
    heading_deg += i % 2 == 0 ? 3.0 : 1.0;
  }
  EXPECT_NEAR(traj.Euler_rad(starts.back()).z() * kRadToDeg, 800.0, 1e-10);
  EXPECT_NEAR(traj.duration_s(), starts.back(), 1e-9);
}

TEST(SegmentTrajectory, MechanizationReproducesTheTruthOnEveryKind) {
  const SegmentTrajectory traj(Parse(kEveryKind));
  const testing::SynthesisRoundTrip r = testing::MechanizeExactIncrements(
      traj, {45.0 * kDegToRad, 7.0 * kDegToRad, 300.0}, 200.0, traj.duration_s());
  EXPECT_NEAR(r.t_end_s, 590.0, 1e-9);
  // The issue's bounds: 1 cm and 1e-4 deg; measured 38 um and 5e-8 deg. An attitude or
  // velocity inconsistent with its analytic derivative drifts far beyond them.
  EXPECT_LT(r.max_position_m, 0.01);
  EXPECT_LT(r.max_attitude_deg, 1e-4);
}

// A configuration error's field and line.
struct BadCase {
  const char* segment;  // the YAML of the faulty line
  const char* field;
};

TEST(SegmentTrajectory, ParseErrorsNameTheKeyPathAndLine) {
  const BadCase cases[] = {
      {"{kind: static, duration_s: -1}", "trajectory.segments[1].duration_s"},
      {"{kind: cruise, duration_s: 10, speed_mps: 3}", "trajectory.segments[1].speed_mps"},
      {"{kind: loop, duration_s: 10}", "trajectory.segments[1].kind"},
      {"{kind: cruise}", "trajectory.segments[1].duration_s"},
      {"{kind: static, duration_s: 10}", "trajectory.segments[1].kind"},  // moving at 20 m/s
      {"{kind: climb, duration_s: 10, flight_path_deg: 90}",
       "trajectory.segments[1].flight_path_deg"},
      {"{kind: climb, duration_s: 10, flight_path_deg: -5}",
       "trajectory.segments[1].flight_path_deg"},
      {"{kind: descend, duration_s: 10, vertical_speed_mps: -25}",
       "trajectory.segments[1].vertical_speed_mps"},
      {"{kind: accelerate, duration_s: 10, speed_mps: 30, acceleration_mps2: 1}",
       "trajectory.segments[1].acceleration_mps2"},
      {"{kind: accelerate, duration_s: 10, speed_mps: 10}", "trajectory.segments[1].speed_mps"},
      {"{kind: decelerate, duration_s: 10, speed_mps: -1}", "trajectory.segments[1].speed_mps"},
      {"{kind: decelerate, duration_s: 10, deceleration_mps2: 3}",
       "trajectory.segments[1].deceleration_mps2"},
      {"{kind: turn, duration_s: 10, heading_change_deg: 90, turn_rate_deg_s: 10}",
       "trajectory.segments[1].turn_rate_deg_s"},
      {"{kind: s_turns, duration_s: 10, heading_amplitude_deg: 5, period_s: 0}",
       "trajectory.segments[1].period_s"},
      {"{kind: wing_rock, duration_s: 10, roll_amplitude_deg: 5}",
       "trajectory.segments[1].roll_frequency_hz"},
      {"{kind: wing_rock, duration_s: 10, pitch_amplitude_deg: 90, pitch_frequency_hz: 1}",
       "trajectory.segments[1].pitch_amplitude_deg"},
      {"{kind: cruise, duration_s: 10, transition_s: 0}", "trajectory.segments[1].transition_s"},
  };
  for (const BadCase& c : cases) {
    const std::string yaml = std::string("trajectory:\n") +
                             "  initial: {speed_mps: 20, heading_deg: 0}\n" +
                             "  segments:\n" +  //
                             "    - {kind: cruise, duration_s: 5}\n" +
                             "    - " + c.segment + "\n";
    try {
      Parse(yaml);
      ADD_FAILURE() << "accepted: " << c.segment;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), c.field) << e.what();
      EXPECT_EQ(e.line(), 5) << e.what();
      EXPECT_EQ(e.file(), "scenario.yaml");
    }
  }
}

TEST(SegmentTrajectory, ParseErrorsInTheInitialStateAndTopLevel) {
  const char* const kSegments = "  segments: [{kind: cruise, duration_s: 5}]\n";
  const BadCase cases[] = {
      {"  initial: {speed_mps: -1}\n", "trajectory.initial.speed_mps"},
      {"  initial: {flight_path_deg: 95}\n", "trajectory.initial.flight_path_deg"},
      {"  initial: {flight_path_deg: 60, pitch_offset_deg: 40}\n",
       "trajectory.initial.pitch_offset_deg"},
      {"  initial: {speed_kmh: 3}\n", "trajectory.initial.speed_kmh"},
      {"  transition_s: -2\n", "trajectory.transition_s"},
  };
  for (const BadCase& c : cases) {  // the bad line is line 2
    try {
      Parse(std::string("trajectory:\n") + c.segment + kSegments);
      ADD_FAILURE() << "accepted: " << c.segment;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), c.field) << e.what();
      EXPECT_EQ(e.line(), 2) << e.what();
    }
  }
  for (const char* segments : {"  segments: []\n", "  segment: []\n"}) {
    try {
      Parse(std::string("trajectory:\n") + segments);
      ADD_FAILURE() << "accepted: " << segments;
    } catch (const InputError& e) {
      EXPECT_EQ(e.line(), 2) << e.what();
    }
  }
}

TEST(SegmentTrajectory, ConstructorRejectsAnImpossibleConfiguration) {
  TrajectoryConfig config;
  EXPECT_THROW(SegmentTrajectory{config}, std::invalid_argument);  // no segments
  SegmentConfig seg;
  seg.kind = SegmentKind::kCruise;
  seg.duration_s = -1.0;
  config.segments.push_back(seg);
  EXPECT_THROW(SegmentTrajectory{config}, std::invalid_argument);
}

}  // namespace sim_segments_test
}  // namespace navtwin::sim
