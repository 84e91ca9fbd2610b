// Calibration rigs as analytic trajectories (valid for every t >= 0, continuous angular
// rate and acceleration), for the calibration work of seed 001 (spec gnss-ins-mag.md
// section 3). docs/aiding-models.md gives the YAML schema and the choices below.
//
// Multi-position table: the IMU at the table centre (no linear motion) is held at a list
// of attitudes; between two attitudes (roll, pitch, yaw) move along the straight line in
// Euler angles with a quintic smoothstep (zero rate and angular acceleration at both
// ends), so a yaw from 0 to 270 deg turns 270 deg. Rate-table rotations turn one Euler
// angle at a constant rate, i.e. the inner (roll), middle (pitch) or outer (yaw) gimbal of
// a ZYX three-axis table, with smooth spin-up and spin-down ramps.
//
// Pendulum (seed 001): theta'' + c1 theta' + c2 sin(theta) = 0. The pivot axis is east:
// the bob frame p is NED at theta = 0 and R_n_p = Ry(theta), so the bob, at radius
// length_m below the pivot, is at L (sin theta, 0, cos theta) from the pivot (theta > 0:
// north and up). The IMU sits on the bob with R_n_b = R_n_p R_p_b (mounting R_p_b). theta is
// integrated by RK4 (10 steps per node, nodes every min(10 ms, period / 100)); between nodes
// a quintic Hermite in (theta, theta', theta'') gives a C2 angle whose derivatives are
// exactly the rates and accelerations reported, so the synthesized increments and the
// attitude agree to rounding; the angle itself follows the ODE to ~1e-12 rad.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include "core/sim/analytic_trajectory.h"
#include "core/config/yaml_config.h"

namespace navtwin::sim {

/// One step of a multi-position schedule, followed by a static hold of dwell_s.
struct TableStep {
  enum class Kind { kPosition, kRotation };
  Kind kind = Kind::kPosition;
  Eigen::Vector3d euler_rad = Eigen::Vector3d::Zero();  ///< position: (roll, pitch, yaw)
  int axis = 2;             ///< rotation: Euler angle turned, 0 roll, 1 pitch, 2 yaw
  double rate_radps = 0.0;  ///< rotation: the constant rate (signed)
  double duration_s = 0.0;  ///< rotation: time at the constant rate
  double ramp_s = 1.0;      ///< rotation: spin-up time and spin-down time (> 0)
  double dwell_s = 0.0;     ///< hold after the step
  double move_s = 0.0;      ///< position: time of the move to it (0: the schedule's rotation_s)
};

struct MultiPositionConfig {
  double rotation_s = 5.0;  ///< time of each move between two positions (> 0)
  /// The first position step (or level, north, if the list starts with a rotation) is the
  /// attitude at t = 0.
  std::vector<TableStep> steps;
};

struct PendulumConfig {
  double length_m = 1.0;                          ///< pivot to IMU
  double damping_per_s = 0.0;                     ///< c1 >= 0
  std::optional<double> c2_per_s2;                ///< default g0 / length_m (simple pendulum)
  double initial_angle_rad = 0.5235987755982988;  ///< 30 deg
  double initial_rate_radps = 0.0;
  Eigen::Matrix3d mounting_p_b = Eigen::Matrix3d::Identity();  ///< R_p_b: IMU axes in the bob frame
  /// The pivot encoder (angle.csv of `navtwin simulate`): white noise (1 sigma) and the
  /// quantum of its absolute reading; 0: none.
  double angle_noise_rad = 0.0;
  double angle_quantum_rad = 0.0;
};

/// A sensor put down by hand in random orientations (no rig, no known attitudes): held
/// still for initial_still_s, then `positions` times turned by hand (a smooth turn of
/// random length in [turn_min_s, turn_max_s] along the straight line in Euler angles, the
/// short way round) to a random attitude and held still for a random time in
/// [still_min_s, still_max_s]. The attitudes put gravity uniformly over the sphere of body
/// directions within |pitch| <= max_pitch (roll and yaw uniform, sin(pitch) uniform). The
/// placements are drawn from placement_seed (part of the scenario, like a table's
/// schedule: `simulate --seed` draws the sensor errors and noise, not the placements). No
/// translation: a hand's lifts do not matter to the gyro integration between still
/// intervals, and the accelerometer is used only when still.
struct HandheldConfig {
  int positions = 15;
  double initial_still_s = 30.0;
  double still_min_s = 2.0, still_max_s = 5.0;
  double turn_min_s = 1.0, turn_max_s = 3.0;
  double max_pitch_rad = 80.0 * 0.017453292519943295;
  std::uint64_t placement_seed = 1;
};

/// The table schedule of a hand-placed sequence (HandheldConfig above).
MultiPositionConfig HandheldSchedule(const HandheldConfig& config);

struct CalibrationRigConfig {
  enum class Kind { kMultiPosition, kPendulum, kHandheld };
  Kind kind = Kind::kMultiPosition;
  MultiPositionConfig table;  ///< kMultiPosition; kHandheld: HandheldSchedule(handheld)
  PendulumConfig pendulum;
  HandheldConfig handheld;
};

/// Parses `trajectory: {kind: multiposition, ...}`, `{kind: pendulum, ...}` or
/// `{kind: handheld, ...}` (schema in docs/aiding-models.md). Throws InputError naming the file, line and key.
CalibrationRigConfig ParseCalibrationRigConfig(const ConfigNode& node);

/// The IMU mounting on a pendulum's bob, R_p_b, from the keys of `node`: `mounting`
/// (letters: the bob-frame directions N, E, D, S, W, U of the IMU x, y, z axes, e.g. NED,
/// DNE, EDN) or `mounting_deg` ([roll, pitch, yaw] of R_p_b); identity when neither is
/// given. Shared by the rig and the pendulum calibration record. Throws InputError naming
/// the key (both given, letters that are not a right-handed frame).
Eigen::Matrix3d ParsePendulumMounting(const ConfigNode& node);

/// A rig trajectory that can also describe itself for errors.yaml (rigs draw nothing; they
/// write the truth a calibration needs: static intervals, c1, c2, the mounting).
class CalibrationRig : public AnalyticTrajectory {
 public:
  virtual void EmitDrawn(YAML::Emitter& out) const = 0;
};

/// Throws std::invalid_argument for a configuration ParseCalibrationRigConfig would reject.
std::unique_ptr<CalibrationRig> MakeCalibrationRig(const CalibrationRigConfig& config);

/// A static interval of the table: [start_s, end_s] at attitude euler_rad.
struct StaticInterval {
  double start_s = 0.0;
  double end_s = 0.0;
  Eigen::Vector3d euler_rad = Eigen::Vector3d::Zero();
};

class MultiPositionRig : public CalibrationRig {
 public:
  explicit MultiPositionRig(const MultiPositionConfig& config);
  TrajectoryPoint PointAt(double t_s) const override;
  Eigen::Vector3d Euler_rad(double t_s) const override;
  Eigen::Vector3d EulerRate_radps(double t_s) const override;
  Eigen::Vector3d Velocity_n_mps(double) const override { return Eigen::Vector3d::Zero(); }
  Eigen::Vector3d Acceleration_n_mps2(double) const override { return Eigen::Vector3d::Zero(); }
  void EmitDrawn(YAML::Emitter& out) const override;

  /// End of the schedule; after it the last attitude is held.
  double duration_s() const;
  const std::vector<StaticInterval>& static_intervals() const { return static_intervals_; }

 private:
  struct Segment {
    enum class Kind { kHold, kMove, kSpin } kind = Kind::kHold;
    double t0_s = 0.0, t1_s = 0.0;
    Eigen::Vector3d e0 = Eigen::Vector3d::Zero(), e1 = Eigen::Vector3d::Zero();
    int axis = 2;
    double rate_radps = 0.0, ramp_s = 0.0;
  };
  /// (Euler angles, Euler rates) at t.
  std::pair<Eigen::Vector3d, Eigen::Vector3d> Evaluate(double t_s) const;

  std::vector<Segment> segments_;
  std::vector<StaticInterval> static_intervals_;
  Eigen::Vector3d final_euler_rad_ = Eigen::Vector3d::Zero();
};

class PendulumRig : public CalibrationRig {
 public:
  explicit PendulumRig(const PendulumConfig& config);
  TrajectoryPoint PointAt(double t_s) const override;
  Eigen::Vector3d Euler_rad(double t_s) const override;
  Eigen::Vector3d EulerRate_radps(double t_s) const override;
  Eigen::Vector3d Velocity_n_mps(double t_s) const override;
  Eigen::Vector3d Acceleration_n_mps2(double t_s) const override;
  void EmitDrawn(YAML::Emitter& out) const override;

  /// The pendulum angle theta (rad) and its first and second derivatives.
  double Angle_rad(double t_s) const { return Swing(t_s).theta; }
  double AngleRate_radps(double t_s) const { return Swing(t_s).rate; }
  double AngleAcceleration_rad_s2(double t_s) const { return Swing(t_s).accel; }
  double c1_per_s() const { return c1_; }
  double c2_per_s2() const { return c2_; }
  const PendulumConfig& config() const { return config_; }
  /// The pivot axis (east) in IMU axes: omega_nb_b = theta' * pivot_axis_b().
  const Eigen::Vector3d& pivot_axis_b() const { return pivot_axis_b_; }

 private:
  struct Node {
    double theta = 0.0, rate = 0.0, accel = 0.0;
  };
  /// theta and its derivatives at t (quintic Hermite between the nodes).
  Node Swing(double t_s) const;
  Node Derivatives(double theta, double rate) const;
  Eigen::Vector3d EulerOf(const Node& n) const;
  Eigen::Vector3d EulerRateOf(const Node& n, const Eigen::Vector3d& euler_rad) const;
  Eigen::Vector3d VelocityOf(const Node& n) const;
  Eigen::Vector3d AccelerationOf(const Node& n) const;
  void ExtendTo(std::size_t count) const;  ///< with mutex_ held

  PendulumConfig config_;
  double c1_, c2_;
  double node_step_s_;
  Eigen::Vector3d pivot_axis_b_;
  // The mounting as Ry(p0) Rx(r0) when the IMU x axis is perpendicular to the pivot axis
  // (then the Euler angles (r0, p0 + theta, 0) stay smooth even through pitch +-90 deg).
  bool planar_ = false;
  double mount_roll_rad_ = 0.0, mount_pitch_rad_ = 0.0;
  double rest_roll_rad_ = 0.0;  ///< roll at theta = 0 (branch for unwrapping)
  // theta at nodes k * node_step_s_, extended on demand (const queries, hence mutable).
  mutable std::mutex mutex_;
  mutable std::vector<Node> nodes_;
};

}  // namespace navtwin::sim
