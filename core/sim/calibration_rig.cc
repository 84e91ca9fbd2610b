#include "core/sim/calibration_rig.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "core/rotation.h"
#include "core/sim/random.h"
#include "core/units.h"

namespace navtwin::sim {
namespace {

/// Largest table rate accepted (deg/s); beyond any rate table.
constexpr double kMaxTableRate_deg_s = 1000.0;
/// Pendulum integration: RK4 steps per interpolation node, and node spacing.
constexpr int kRk4StepsPerNode = 10;
constexpr double kMaxNodeStep_s = 0.01;
constexpr double kNodesPerPeriod = 100.0;
/// Nodes added at a time when a query goes beyond the table.
constexpr std::size_t kNodeChunk = 4096;
/// Below this |x_p . e_y| the IMU x axis is in the swing plane (exact mountings such as
/// the seed's, where sin/cos of multiples of 90 deg leave ~1e-16).
constexpr double kInSwingPlane = 1e-12;
/// Angle step of the check that the roll stays on one branch over the swing.
constexpr double kRollCheckStep_rad = 1e-3;
/// Standard gravity (m/s^2) for the default c2 = g0 / length.

// ------------------------------------------------------------- smooth profiles

/// Quintic smoothstep s(u) = u^3 (10 - 15 u + 6 u^2) on [0, 1], its derivative, and its
/// integral S(u) = u^4 (2.5 - 3 u + u^2) (S(1) = 1/2).
double Smooth(double u) { return u * u * u * (10.0 - 15.0 * u + 6.0 * u * u); }
double SmoothRate(double u) { return 30.0 * u * u * (1.0 - u) * (1.0 - u); }
double SmoothIntegral(double u) { return u * u * u * u * (2.5 - 3.0 * u + u * u); }

/// (angle, rate) at tau into a spin of total length T at rate R with ramps of Tr: the rate is
/// R s(tau / Tr) over the spin-up, R, then R (1 - s(u)) over the spin-down.
std::pair<double, double> SpinProfile(double R, double Tr, double T, double tau) {
  const double constant_s = T - 2.0 * Tr;
  if (tau < Tr) return {R * Tr * SmoothIntegral(tau / Tr), R * Smooth(tau / Tr)};
  if (tau < Tr + constant_s) return {R * (0.5 * Tr + (tau - Tr)), R};
  const double u = (tau - Tr - constant_s) / Tr;
  return {R * (0.5 * Tr + constant_s + Tr * (u - SmoothIntegral(u))), R * (1.0 - Smooth(u))};
}

/// The pendulum's roll is unwrapped around its rest value; it must not turn half a turn away
/// within the swing |theta| <= max_angle (only when x passes within a hair of the vertical).
void RequireOneRollBranch(const Eigen::Matrix3d& R_p_b, double rest_roll_rad, double max_angle) {
  for (double a = 0.0; a <= max_angle; a += kRollCheckStep_rad) {
    for (const double theta : {a, -a}) {
      const Eigen::Matrix3d R_n_b = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY()) * R_p_b;
      if (std::fabs(WrapPi(EulerFromDcm(R_n_b).x() - rest_roll_rad)) > 0.9 * M_PI) {
        throw std::invalid_argument(
            "pendulum: the mounting brings the IMU x axis too close to the vertical; put x in "
            "the swing plane (perpendicular to the east pivot axis) or away from it");
      }
    }
  }
}

// ------------------------------------------------------------------ parsing

Eigen::Vector3d DegVector(const ConfigNode& node, const std::string& key) {
  return node.Vector(key, Eigen::Vector3d::Zero()) * kDegToRad;
}

TableStep ParseTableStep(const ConfigNode& node, double default_dwell_s) {
  node.RequireKeys({"euler_deg", "rotate", "rate_deg_s", "duration_s", "ramp_s", "dwell_s"});
  TableStep s;
  s.dwell_s = node.NonNegative("dwell_s", default_dwell_s);
  if (node.Has("euler_deg") == node.Has("rotate")) {
    node.Fail("", "give either euler_deg (a position) or rotate (a rate-table rotation)");
  }
  if (node.Has("euler_deg")) {
    for (const char* key : {"rate_deg_s", "duration_s", "ramp_s"}) {
      if (node.Has(key)) node.Fail(key, "only for a rotation step (rotate: ...)");
    }
    s.euler_rad = DegVector(node, "euler_deg");
    return s;
  }
  s.kind = TableStep::Kind::kRotation;
  const std::string axis = node.String("rotate", "");
  const char* names[3] = {"roll", "pitch", "yaw"};
  s.axis = -1;
  for (int k = 0; k < 3; ++k) {
    if (axis == names[k]) s.axis = k;
  }
  if (s.axis < 0) node.Fail("rotate", "expected roll, pitch or yaw, got '" + axis + "'");
  if (!node.Has("rate_deg_s")) node.Fail("rate_deg_s", "required for a rotation");
  s.rate_radps =
      node.Double("rate_deg_s", 0.0, -kMaxTableRate_deg_s, kMaxTableRate_deg_s) * kDegToRad;
  s.duration_s = node.NonNegative("duration_s", 0.0);
  s.ramp_s = node.NonNegative("ramp_s", s.ramp_s);
  if (!(s.ramp_s > 0.0)) node.Fail("ramp_s", "must be > 0 (the angular rate must be continuous)");
  return s;
}

MultiPositionConfig ParseMultiPosition(const ConfigNode& node) {
  node.RequireKeys({"kind", "rotation_s", "dwell_s", "steps"});
  MultiPositionConfig c;
  c.rotation_s = node.NonNegative("rotation_s", c.rotation_s);
  if (!(c.rotation_s > 0.0)) node.Fail("rotation_s", "must be > 0");
  const double dwell_s = node.NonNegative("dwell_s", 10.0);
  for (const ConfigNode& step : node.Elements("steps")) {
    c.steps.push_back(ParseTableStep(step, dwell_s));
  }
  if (c.steps.empty()) node.Fail("steps", "required: a list of positions and rotations");
  return c;
}

/// A [min, max] pair of seconds (0 < min <= max) from `key`, or the default.
std::pair<double, double> SecondsRange(const ConfigNode& node, const std::string& key, std::pair<double, double> range) {
  const Eigen::Vector2d v = node.Range(key, Eigen::Vector2d(range.first, range.second));
  if (!(v[0] > 0.0)) node.Fail(key, "expected [min, max] seconds with 0 < min <= max");
  return {v[0], v[1]};
}

HandheldConfig ParseHandheld(const ConfigNode& node) {
  node.RequireKeys({"kind", "positions", "initial_still_s", "still_s", "turn_s", "max_pitch_deg", "placement_seed"});
  HandheldConfig c;
  c.positions = node.Int("positions", c.positions, 1, 1000);
  c.initial_still_s = node.NonNegative("initial_still_s", c.initial_still_s);
  std::tie(c.still_min_s, c.still_max_s) = SecondsRange(node, "still_s", {c.still_min_s, c.still_max_s});
  std::tie(c.turn_min_s, c.turn_max_s) = SecondsRange(node, "turn_s", {c.turn_min_s, c.turn_max_s});
  c.max_pitch_rad = node.Double("max_pitch_deg", c.max_pitch_rad * kRadToDeg, 0.0, 89.0) * kDegToRad;
  c.placement_seed = static_cast<std::uint64_t>(node.Double("placement_seed", 1.0, 0.0, 1e15));
  return c;
}

PendulumConfig ParsePendulum(const ConfigNode& node) {
  node.RequireKeys({"kind", "length_m", "damping_per_s", "c2_per_s2", "initial_angle_deg",
                    "initial_rate_deg_s", "mounting", "mounting_deg", "angle_noise_deg",
                    "angle_quantum_deg"});
  PendulumConfig c;
  c.length_m = node.NonNegative("length_m", c.length_m);
  if (!(c.length_m > 0.0)) node.Fail("length_m", "must be > 0");
  c.damping_per_s = node.NonNegative("damping_per_s", 0.0);
  if (node.Has("c2_per_s2")) {
    c.c2_per_s2 = node.Double("c2_per_s2", 0.0);
    if (!(*c.c2_per_s2 > 0.0)) node.Fail("c2_per_s2", "must be > 0");
  }
  c.initial_angle_rad = node.Double("initial_angle_deg", 30.0, -179.0, 179.0) * kDegToRad;
  c.initial_rate_radps = node.Double("initial_rate_deg_s", 0.0) * kDegToRad;
  c.mounting_p_b = ParsePendulumMounting(node);
  c.angle_noise_rad = node.NonNegative("angle_noise_deg", 0.0) * kDegToRad;
  c.angle_quantum_rad = node.NonNegative("angle_quantum_deg", 0.0) * kDegToRad;
  return c;
}

// -------------------------------------------------------------------- output

}  // namespace

Eigen::Matrix3d ParsePendulumMounting(const ConfigNode& node) {
  if (node.Has("mounting") && node.Has("mounting_deg")) {
    node.Fail("mounting_deg", "give either mounting (letters) or mounting_deg, not both");
  }
  if (node.Has("mounting_deg")) {
    const Eigen::Vector3d e = DegVector(node, "mounting_deg");
    return DcmFromEuler(e.x(), e.y(), e.z());
  }
  if (!node.Has("mounting")) return Eigen::Matrix3d::Identity();
  // "NED", "DNE", ...: the bob-frame direction (N, E, D, S, W, U) of the IMU x, y, z axes.
  const std::string letters = node.String("mounting", "");
  const char* shape =
      "expected three of N, E, D, S, W, U (the directions of the IMU x, y, z "
      "axes in the bob frame) forming a right-handed frame, e.g. NED, DNE, EDN";
  if (letters.size() != 3) node.Fail("mounting", shape);
  Eigen::Matrix3d R;
  for (int k = 0; k < 3; ++k) {
    const char c = static_cast<char>(std::toupper(static_cast<unsigned char>(letters[k])));
    const std::string axes = "NEDSWU";
    const std::size_t i = axes.find(c);
    if (i == std::string::npos) node.Fail("mounting", shape);
    R.col(k) = Eigen::Vector3d::Unit(static_cast<int>(i % 3)) * (i < 3 ? 1.0 : -1.0);
  }
  if (!(R.transpose() * R).isIdentity(0.0) || R.determinant() < 0.0) node.Fail("mounting", shape);
  return R;
}

CalibrationRigConfig ParseCalibrationRigConfig(const ConfigNode& node) {
  CalibrationRigConfig c;
  const std::string kind = node.String("kind", "");
  if (kind == "multiposition") {
    c.kind = CalibrationRigConfig::Kind::kMultiPosition;
    c.table = ParseMultiPosition(node);
  } else if (kind == "handheld") {
    c.kind = CalibrationRigConfig::Kind::kHandheld;
    c.handheld = ParseHandheld(node);
    c.table = HandheldSchedule(c.handheld);
  } else if (kind == "pendulum") {
    c.kind = CalibrationRigConfig::Kind::kPendulum;
    c.pendulum = ParsePendulum(node);
    try {
      PendulumRig check(c.pendulum);  // rejects swings over the top and near-vertical IMU x
    } catch (const std::invalid_argument& e) {
      node.Fail("", e.what());
    }
  } else {
    node.Fail("kind", "expected multiposition, pendulum or handheld, got '" + kind + "'");
  }
  return c;
}

std::unique_ptr<CalibrationRig> MakeCalibrationRig(const CalibrationRigConfig& config) {
  if (config.kind == CalibrationRigConfig::Kind::kPendulum) {
    return std::make_unique<PendulumRig>(config.pendulum);
  }
  return std::make_unique<MultiPositionRig>(config.table);
}

MultiPositionConfig HandheldSchedule(const HandheldConfig& config) {
  if (config.positions < 1 || !(config.still_min_s > 0.0) || !(config.still_max_s >= config.still_min_s) ||
      !(config.turn_min_s > 0.0) || !(config.turn_max_s >= config.turn_min_s) || !(config.initial_still_s >= 0.0)) {
    throw std::invalid_argument("HandheldSchedule: needs positions >= 1 and 0 < min <= max for still_s and turn_s");
  }
  Rng rng = Rng(config.placement_seed).Stream("handheld");
  const double max_sin_pitch = std::sin(config.max_pitch_rad);
  MultiPositionConfig table;
  table.rotation_s = config.turn_min_s;
  Eigen::Vector3d e = Eigen::Vector3d::Zero();
  for (int k = 0; k <= config.positions; ++k) {
    TableStep step;
    // Roll and yaw uniform, sin(pitch) uniform: gravity uniform over the body directions.
    const Eigen::Vector3d target(rng.Uniform(-M_PI, M_PI), std::asin(rng.Uniform(-max_sin_pitch, max_sin_pitch)),
                                 rng.Uniform(-M_PI, M_PI));
    if (k > 0) {
      // The short way round in roll and yaw.
      step.euler_rad = Eigen::Vector3d(e.x() + WrapPi(target.x() - e.x()), target.y(), e.z() + WrapPi(target.z() - e.z()));
      step.move_s = rng.Uniform(config.turn_min_s, config.turn_max_s);
    } else {
      step.euler_rad = target;
    }
    step.dwell_s = k == 0 ? config.initial_still_s : rng.Uniform(config.still_min_s, config.still_max_s);
    e = step.euler_rad;
    table.steps.push_back(step);
  }
  return table;
}

// -------------------------------------------------------- multi-position table

MultiPositionRig::MultiPositionRig(const MultiPositionConfig& config) {
  if (config.steps.empty() || !(config.rotation_s > 0.0)) {
    throw std::invalid_argument("MultiPositionRig: needs steps and rotation_s > 0");
  }
  const TableStep& first = config.steps.front();
  Eigen::Vector3d e =
      first.kind == TableStep::Kind::kPosition ? first.euler_rad : Eigen::Vector3d::Zero();
  double t = 0.0;
  for (std::size_t i = 0; i < config.steps.size(); ++i) {
    const TableStep& step = config.steps[i];
    if (!(step.dwell_s >= 0.0)) throw std::invalid_argument("MultiPositionRig: dwell_s < 0");
    if (step.kind == TableStep::Kind::kPosition && i > 0) {
      const double move_s = step.move_s > 0.0 ? step.move_s : config.rotation_s;
      segments_.push_back({Segment::Kind::kMove, t, t + move_s, e, step.euler_rad, 2, 0.0, 0.0});
      e = step.euler_rad;
    } else if (step.kind == TableStep::Kind::kRotation) {
      if (!(step.ramp_s > 0.0) || !(step.duration_s >= 0.0)) {
        throw std::invalid_argument("MultiPositionRig: rotation needs ramp_s > 0, duration_s >= 0");
      }
      Eigen::Vector3d end = e;
      end[step.axis] += step.rate_radps * (step.ramp_s + step.duration_s);
      segments_.push_back({Segment::Kind::kSpin, t, t + 2.0 * step.ramp_s + step.duration_s, e, end,
                           step.axis, step.rate_radps, step.ramp_s});
      e = end;
    }
    t = segments_.empty() ? 0.0 : segments_.back().t1_s;
    if (step.dwell_s > 0.0) {
      segments_.push_back({Segment::Kind::kHold, t, t + step.dwell_s, e, e, 2, 0.0, 0.0});
      static_intervals_.push_back({t, t + step.dwell_s, e});
      t += step.dwell_s;
    }
  }
  final_euler_rad_ = e;
}

double MultiPositionRig::duration_s() const {
  return segments_.empty() ? 0.0 : segments_.back().t1_s;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> MultiPositionRig::Evaluate(double t) const {
  // The last segment starting at or before t.
  const auto it = std::upper_bound(segments_.begin(), segments_.end(), t,
                                   [](double x, const Segment& s) { return x < s.t0_s; });
  if (it == segments_.begin()) {  // no segment (a single position) or t < 0
    return {segments_.empty() ? final_euler_rad_ : segments_.front().e0, Eigen::Vector3d::Zero()};
  }
  const Segment& s = *(it - 1);
  if (t >= s.t1_s) return {s.e1, Eigen::Vector3d::Zero()};  // after the schedule
  const double tau = t - s.t0_s;
  const double T = s.t1_s - s.t0_s;
  switch (s.kind) {
    case Segment::Kind::kHold:
      break;
    case Segment::Kind::kMove:
      return {s.e0 + Smooth(tau / T) * (s.e1 - s.e0), SmoothRate(tau / T) / T * (s.e1 - s.e0)};
    case Segment::Kind::kSpin: {
      const std::pair<double, double> spin = SpinProfile(s.rate_radps, s.ramp_s, T, tau);
      Eigen::Vector3d e = s.e0, de = Eigen::Vector3d::Zero();
      e[s.axis] += spin.first;
      de[s.axis] = spin.second;
      return {e, de};
    }
  }
  return {s.e0, Eigen::Vector3d::Zero()};
}

TrajectoryPoint MultiPositionRig::PointAt(double t_s) const {
  const auto [e, de] = Evaluate(t_s);
  return {e, de, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
}

Eigen::Vector3d MultiPositionRig::Euler_rad(double t_s) const { return Evaluate(t_s).first; }
Eigen::Vector3d MultiPositionRig::EulerRate_radps(double t_s) const { return Evaluate(t_s).second; }

void MultiPositionRig::EmitDrawn(YAML::Emitter& out) const {
  out << YAML::BeginMap;
  out << YAML::Key << "kind" << YAML::Value << "multiposition";
  out << YAML::Key << "duration_s" << YAML::Value << duration_s();
  out << YAML::Key << "static_intervals" << YAML::Value << YAML::BeginSeq;
  for (const StaticInterval& s : static_intervals_) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "start_s" << YAML::Value << s.start_s;
    out << YAML::Key << "end_s" << YAML::Value << s.end_s;
    EmitVector(out, "euler_deg", s.euler_rad, kDegToRad);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
}

// -------------------------------------------------------------------- pendulum

PendulumRig::PendulumRig(const PendulumConfig& config)
    : config_(config),
      c1_(config.damping_per_s),
      c2_(config.c2_per_s2.value_or(kStandardGravity_mps2 / config.length_m)),
      node_step_s_(0.0),
      pivot_axis_b_(config.mounting_p_b.transpose().col(1)) {
  if (!(config.length_m > 0.0) || !(c1_ >= 0.0) || !(c2_ > 0.0) ||
      !(config.mounting_p_b.transpose() * config.mounting_p_b).isIdentity(1e-9)) {
    throw std::invalid_argument("PendulumRig: needs length_m > 0, c1 >= 0, c2 > 0, a rotation");
  }
  // Energy per unit inertia; at or above 2 c2 the pendulum would go over the top.
  const double energy = 0.5 * config.initial_rate_radps * config.initial_rate_radps +
                        c2_ * (1.0 - std::cos(config.initial_angle_rad));
  if (!(energy < 2.0 * c2_ * (1.0 - 1e-9))) {
    throw std::invalid_argument("pendulum: the initial angle and rate make it go over the top");
  }
  const double period_s = 2.0 * M_PI / std::sqrt(c2_);
  node_step_s_ = std::min(kMaxNodeStep_s, period_s / kNodesPerPeriod);

  const Eigen::Matrix3d& R = config.mounting_p_b;
  planar_ = std::fabs(R(1, 0)) <= kInSwingPlane;
  mount_pitch_rad_ = std::atan2(-R(2, 0), R(0, 0));
  mount_roll_rad_ = std::atan2(-R(1, 2), R(1, 1));
  rest_roll_rad_ = EulerFromDcm(R).x();
  if (!planar_) RequireOneRollBranch(R, rest_roll_rad_, std::acos(1.0 - energy / c2_));
  nodes_.push_back(Derivatives(config.initial_angle_rad, config.initial_rate_radps));
}

PendulumRig::Node PendulumRig::Derivatives(double theta, double rate) const {
  return {theta, rate, -c1_ * rate - c2_ * std::sin(theta)};
}

void PendulumRig::ExtendTo(std::size_t count) const {
  const double h = node_step_s_ / kRk4StepsPerNode;
  while (nodes_.size() < count) {
    double th = nodes_.back().theta, w = nodes_.back().rate;
    for (int i = 0; i < kRk4StepsPerNode; ++i) {
      const Node k1 = Derivatives(th, w);
      const Node k2 = Derivatives(th + 0.5 * h * k1.rate, w + 0.5 * h * k1.accel);
      const Node k3 = Derivatives(th + 0.5 * h * k2.rate, w + 0.5 * h * k2.accel);
      const Node k4 = Derivatives(th + h * k3.rate, w + h * k3.accel);
      th += h / 6.0 * (k1.rate + 2.0 * k2.rate + 2.0 * k3.rate + k4.rate);
      w += h / 6.0 * (k1.accel + 2.0 * k2.accel + 2.0 * k3.accel + k4.accel);
    }
    nodes_.push_back(Derivatives(th, w));
  }
}

PendulumRig::Node PendulumRig::Swing(double t_s) const {
  if (!(t_s >= 0.0) || !std::isfinite(t_s)) {
    throw std::out_of_range("PendulumRig: defined for finite t >= 0");
  }
  const double x = t_s / node_step_s_;
  const std::size_t k = static_cast<std::size_t>(x);
  Node a, b;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (nodes_.size() < k + 2) ExtendTo(k + 2 + kNodeChunk);
    a = nodes_[k];
    b = nodes_[k + 1];
  }
  // Quintic Hermite p(s), s in [0, 1], matching value, slope and curvature at both nodes.
  const double H = node_step_s_, s = x - static_cast<double>(k);
  const double c0 = a.theta, c1 = a.rate * H, c2 = 0.5 * a.accel * H * H;
  const double A = b.theta - (c0 + c1 + c2);
  const double B = b.rate * H - (c1 + 2.0 * c2);
  const double C = b.accel * H * H - 2.0 * c2;
  const double c3 = 10.0 * A - 4.0 * B + 0.5 * C;
  const double c4 = -15.0 * A + 7.0 * B - C;
  const double c5 = 6.0 * A - 3.0 * B + 0.5 * C;
  Node n;
  n.theta = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))));
  n.rate = (c1 + s * (2.0 * c2 + s * (3.0 * c3 + s * (4.0 * c4 + s * 5.0 * c5)))) / H;
  n.accel = (2.0 * c2 + s * (6.0 * c3 + s * (12.0 * c4 + s * 20.0 * c5))) / (H * H);
  return n;
}

Eigen::Vector3d PendulumRig::EulerOf(const Node& n) const {
  if (planar_) return {mount_roll_rad_, mount_pitch_rad_ + n.theta, 0.0};
  const Eigen::Matrix3d R_n_b =
      Eigen::AngleAxisd(n.theta, Eigen::Vector3d::UnitY()).toRotationMatrix() * config_.mounting_p_b;
  Eigen::Vector3d e = EulerFromDcm(R_n_b);
  e.x() = rest_roll_rad_ + WrapPi(e.x() - rest_roll_rad_);
  return e;
}

Eigen::Vector3d PendulumRig::EulerRateOf(const Node& n, const Eigen::Vector3d& e) const {
  if (planar_) return {0.0, n.rate, 0.0};
  // Invert omega_nb_b = E(roll, pitch) * Euler rates for omega_nb_b = theta' * pivot axis.
  const Eigen::Vector3d w = n.rate * pivot_axis_b_;
  const double sr = std::sin(e.x()), cr = std::cos(e.x());
  const double tp = std::tan(e.y()), cp = std::cos(e.y());
  const double yz = w.y() * sr + w.z() * cr;
  return {w.x() + tp * yz, w.y() * cr - w.z() * sr, yz / cp};
}

Eigen::Vector3d PendulumRig::VelocityOf(const Node& n) const {
  return config_.length_m * n.rate * Eigen::Vector3d(std::cos(n.theta), 0.0, -std::sin(n.theta));
}

Eigen::Vector3d PendulumRig::AccelerationOf(const Node& n) const {
  // Tangential L theta'' and centripetal L theta'^2 (towards the pivot).
  const double L = config_.length_m;
  const double st = std::sin(n.theta), ct = std::cos(n.theta);
  return L * n.accel * Eigen::Vector3d(ct, 0.0, -st) -
         L * n.rate * n.rate * Eigen::Vector3d(st, 0.0, ct);
}

TrajectoryPoint PendulumRig::PointAt(double t_s) const {
  const Node n = Swing(t_s);
  const Eigen::Vector3d e = EulerOf(n);
  return {e, EulerRateOf(n, e), VelocityOf(n), AccelerationOf(n)};
}

Eigen::Vector3d PendulumRig::Euler_rad(double t_s) const { return EulerOf(Swing(t_s)); }

Eigen::Vector3d PendulumRig::EulerRate_radps(double t_s) const {
  const Node n = Swing(t_s);
  return EulerRateOf(n, EulerOf(n));
}

Eigen::Vector3d PendulumRig::Velocity_n_mps(double t_s) const { return VelocityOf(Swing(t_s)); }

Eigen::Vector3d PendulumRig::Acceleration_n_mps2(double t_s) const {
  return AccelerationOf(Swing(t_s));
}

void PendulumRig::EmitDrawn(YAML::Emitter& out) const {
  out << YAML::BeginMap;
  out << YAML::Key << "kind" << YAML::Value << "pendulum";
  out << YAML::Key << "length_m" << YAML::Value << config_.length_m;
  out << YAML::Key << "c1_per_s" << YAML::Value << c1_;
  out << YAML::Key << "c2_per_s2" << YAML::Value << c2_;
  out << YAML::Key << "initial_angle_deg" << YAML::Value << config_.initial_angle_rad * kRadToDeg;
  out << YAML::Key << "initial_rate_deg_s" << YAML::Value << config_.initial_rate_radps * kRadToDeg;
  EmitMatrix(out, "mounting_p_b", config_.mounting_p_b);
  EmitVector(out, "pivot_axis_b", pivot_axis_b_);
  out << YAML::Key << "angle_noise_deg" << YAML::Value << config_.angle_noise_rad * kRadToDeg;
  out << YAML::Key << "angle_quantum_deg" << YAML::Value << config_.angle_quantum_rad * kRadToDeg;
  out << YAML::EndMap;
}

}  // namespace navtwin::sim
