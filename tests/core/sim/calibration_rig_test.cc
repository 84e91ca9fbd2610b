// Calibration rigs: schedule and static intervals of the multi-position table, the
// pendulum's angle against its ODE and the small-angle solution, the seed's mountings,
// derivative consistency, and the exact-increment round trip through the strapdown.
#include "core/sim/calibration_rig.h"
#include "tests/core/sim/round_trip.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/io/input_error.h"
#include "core/rotation.h"
#include "core/strapdown.h"

namespace navtwin::sim {
namespace sim_calibration_rig_test {

const wgs84::Geodetic kLab{37.45 * kDegToRad, 126.65 * kDegToRad, 40.0};

// Six positions (every axis up and down), a full yaw turn at roll -90 deg, a full roll turn,
// and a last tilted position: 85.5 s.
const char* const kTable = R"(trajectory:
  kind: multiposition
  rotation_s: 4
  dwell_s: 5
  steps:
    - euler_deg: [0, 0, 0]
    - euler_deg: [180, 0, 0]
    - euler_deg: [0, 90, 0]
    - euler_deg: [0, -90, 0]
    - euler_deg: [90, 0, 0]
    - euler_deg: [-90, 0, 0]
    - {rotate: yaw, rate_deg_s: 30, duration_s: 11, ramp_s: 1}
    - {rotate: roll, rate_deg_s: -45, duration_s: 7.5, ramp_s: 0.5, dwell_s: 3}
    - {euler_deg: [-450, 30, 340], dwell_s: 2}
)";
CalibrationRigConfig Parse(const std::string& text) {
  return ParseCalibrationRigConfig(ParseYaml(text, "rig.yaml").Child("trajectory"));
}

std::string Pendulum(const std::string& extra) {
  return "trajectory:\n  kind: pendulum\n  length_m: 0.8\n  damping_per_s: 0.05\n"
         "  initial_angle_deg: 40\n" +
         extra;
}

/// Largest |central difference - derivative| over t in [t0, t1] of the Euler angles and
/// the velocity (h = 1e-5 s: truncation h^2/6 |f'''| < 1e-8, rounding ~1e-11).
double DerivativeMismatch(const AnalyticTrajectory& tr, double t0, double t1, double step) {
  constexpr double h = 1e-5;
  double worst = 0.0;
  for (double t = t0; t <= t1; t += step) {
    const Eigen::Vector3d de = (tr.Euler_rad(t + h) - tr.Euler_rad(t - h)) / (2 * h);
    const Eigen::Vector3d dv = (tr.Velocity_n_mps(t + h) - tr.Velocity_n_mps(t - h)) / (2 * h);
    worst = std::max({worst, (de - tr.EulerRate_radps(t)).cwiseAbs().maxCoeff(),
                      (dv - tr.Acceleration_n_mps2(t)).cwiseAbs().maxCoeff()});
  }
  return worst;
}

/// Largest difference between PointAt and the four separate queries (they must agree
/// exactly: PointAt only shares the work).
double PointMismatch(const AnalyticTrajectory& tr, double t0, double t1, double step) {
  double worst = 0.0;
  for (double t = t0; t <= t1; t += step) {
    const TrajectoryPoint p = tr.PointAt(t);
    worst = std::max({worst, (p.euler_rad - tr.Euler_rad(t)).cwiseAbs().maxCoeff(),
                      (p.euler_rate_radps - tr.EulerRate_radps(t)).cwiseAbs().maxCoeff(),
                      (p.v_n_mps - tr.Velocity_n_mps(t)).cwiseAbs().maxCoeff(),
                      (p.a_n_mps2 - tr.Acceleration_n_mps2(t)).cwiseAbs().maxCoeff()});
  }
  return worst;
}

struct RoundTrip {
  double attitude_deg = 0.0;
  double position_m = 0.0;
  double velocity_mps = 0.0;
};

/// The strapdown on the exact increments at 200 Hz against the truth: largest errors.
RoundTrip Mechanize(const AnalyticTrajectory& tr, double duration_s) {
  const testing::SynthesisRoundTrip m = testing::MechanizeExactIncrements(tr, kLab, 200.0, duration_s);
  return {m.max_attitude_deg, m.max_position_m, m.max_velocity_mps};
}

// ------------------------------------------------------------- multi-position table

TEST(CalibrationRigTest, TableScheduleAndStaticIntervals) {
  const CalibrationRigConfig c = Parse(kTable);
  ASSERT_EQ(c.kind, CalibrationRigConfig::Kind::kMultiPosition);
  MultiPositionRig rig(c.table);
  EXPECT_DOUBLE_EQ(rig.duration_s(), 85.5);
  const std::vector<StaticInterval>& s = rig.static_intervals();
  ASSERT_EQ(s.size(), 9u);
  EXPECT_EQ(s[0].start_s, 0.0);
  EXPECT_EQ(s[1].start_s, 9.0);  // 5 s dwell, 4 s move
  EXPECT_EQ(s[1].end_s, 14.0);
  EXPECT_NEAR(s[1].euler_rad.x(), M_PI, 1e-15);
  // After the turns (rate x (ramp + constant time)): yaw 360 deg, roll -90 - 360 deg
  // (Euler angles are not wrapped).
  EXPECT_NEAR(s[6].euler_rad.z() * kRadToDeg, 360.0, 1e-12);
  EXPECT_NEAR(s[7].euler_rad.x() * kRadToDeg, -450.0, 1e-12);
  for (const StaticInterval& i : s) {
    for (const double t : {i.start_s, 0.5 * (i.start_s + i.end_s), i.end_s - 1e-9}) {
      EXPECT_EQ(rig.Euler_rad(t), i.euler_rad) << t;
      EXPECT_EQ(rig.EulerRate_radps(t), Eigen::Vector3d::Zero()) << t;
    }
  }
  // After the schedule the last attitude is held.
  EXPECT_EQ(rig.Euler_rad(1000.0), s.back().euler_rad);
}

TEST(CalibrationRigTest, TableRatesAreTheDerivativesAndContinuous) {
  MultiPositionRig rig(Parse(kTable).table);
  EXPECT_LT(DerivativeMismatch(rig, 1e-4, 90.0, 0.0071), 1e-7);  // measured 5e-10
  EXPECT_EQ(PointMismatch(rig, 0.0, 90.0, 0.0071), 0.0);
  // The constant rate of the yaw spin (starts at 5 + 5 * 9 = 50 s, 1 s ramp).
  EXPECT_NEAR(rig.EulerRate_radps(57.0).z() * kRadToDeg, 30.0, 1e-12);
  // Angular acceleration continuous (C2) at every segment boundary: one-sided differences
  // of the rate agree to O(h |jerk|) (jerk < 300 rad/s^3 on the 0.5 s ramps).
  constexpr double h = 1e-6;
  for (const double tb : {5.0, 9.0, 50.0, 51.0, 62.0, 63.0, 68.0, 68.5, 75.5, 76.0, 79.0, 83.0}) {
    const Eigen::Vector3d before = (rig.EulerRate_radps(tb) - rig.EulerRate_radps(tb - h)) / h;
    const Eigen::Vector3d after = (rig.EulerRate_radps(tb + h) - rig.EulerRate_radps(tb)) / h;
    EXPECT_LT((after - before).cwiseAbs().maxCoeff(), 1e-3) << tb;
  }
}

TEST(CalibrationRigTest, TableExactIncrementsReproduceTheAttitude) {
  MultiPositionRig rig(Parse(kTable).table);
  const RoundTrip r = Mechanize(rig, 90.0);
  // The issue's bound is 1e-4 deg; measured 1.0e-6 deg, the two-sample coning error of the
  // strapdown during the 4 s moves (up to 1.5 rad/s about changing axes; it falls as dt^3),
  // pitch +-90 deg included. 1e-5 deg keeps a 10x margin.
  EXPECT_LT(r.attitude_deg, 1e-5);
  // The table does not move; the sculling error of those moves: measured 0.37 mm.
  EXPECT_LT(r.position_m, 0.01);
}

// ------------------------------------------------------------------- hand-placed sequence

const char* const kHandheld = R"(trajectory:
  kind: handheld
  positions: 200
  initial_still_s: 30
  still_s: [2, 5]
  turn_s: [1, 3]
  max_pitch_deg: 80
  placement_seed: 4
)";

// The schedule: the initial still period, then per placement a turn of 1-3 s (the short way
// round in roll and yaw) and 2-5 s still; the body gravity directions spread over the sphere;
// the same placement seed draws the same schedule, another seed another.
TEST(CalibrationRigTest, HandheldScheduleIsRandomWithinItsRanges) {
  const CalibrationRigConfig c = Parse(kHandheld);
  ASSERT_EQ(c.kind, CalibrationRigConfig::Kind::kHandheld);
  const MultiPositionRig rig(c.table);
  const std::vector<StaticInterval>& s = rig.static_intervals();
  ASSERT_EQ(s.size(), 201u);
  EXPECT_EQ(s[0].start_s, 0.0);
  EXPECT_EQ(s[0].end_s, 30.0);
  Eigen::Vector3d mean_g_b = Eigen::Vector3d::Zero();
  for (std::size_t k = 1; k < s.size(); ++k) {
    const double turn_s = s[k].start_s - s[k - 1].end_s, still_s = s[k].end_s - s[k].start_s;
    EXPECT_GE(turn_s, 1.0 - 1e-9);
    EXPECT_LE(turn_s, 3.0 + 1e-9);
    EXPECT_GE(still_s, 2.0 - 1e-9);
    EXPECT_LE(still_s, 5.0 + 1e-9);
    EXPECT_LE(std::abs(s[k].euler_rad.x() - s[k - 1].euler_rad.x()), M_PI + 1e-12) << k;
    EXPECT_LE(std::abs(s[k].euler_rad.z() - s[k - 1].euler_rad.z()), M_PI + 1e-12) << k;
    EXPECT_LE(std::abs(s[k].euler_rad.y()), 80.0 * kDegToRad + 1e-12) << k;
    mean_g_b += DcmFromEuler(s[k].euler_rad.x(), s[k].euler_rad.y(), s[k].euler_rad.z()).transpose().col(2);
  }
  // 200 directions uniform over (most of) the sphere: each component of their mean has a
  // sigma of 1/sqrt(3 x 200) = 0.041; 0.15 is 3.7 sigma.
  mean_g_b /= 200.0;
  EXPECT_LT(mean_g_b.cwiseAbs().maxCoeff(), 0.15) << mean_g_b.transpose();
  EXPECT_EQ(Parse(kHandheld).table.steps[7].euler_rad, c.table.steps[7].euler_rad);
  std::string other = kHandheld;
  other.replace(other.find("placement_seed: 4"), 17, "placement_seed: 5");
  EXPECT_NE(Parse(other).table.steps[7].euler_rad, c.table.steps[7].euler_rad);
}

TEST(CalibrationRigTest, HandheldExactIncrementsReproduceTheAttitude) {
  std::string few = kHandheld;
  few.replace(few.find("positions: 200"), 14, "positions: 12");
  const MultiPositionRig rig(Parse(few).table);
  const RoundTrip r = Mechanize(rig, rig.duration_s());
  std::printf("hand-placed sequence, 12 placements: largest attitude error %.3g deg\n", r.attitude_deg);
  // Turns of up to 180 deg in 1 s (peak rates ~5 rad/s about changing axes): the two-sample
  // coning error at 200 Hz, which grows as rate^3 dt^2; measured 1.5e-5 deg (the table's
  // 4 s moves: 1.0e-6). 1e-3 deg keeps a 60x margin.
  EXPECT_LT(r.attitude_deg, 1e-3);
}

TEST(CalibrationRigTest, HandheldBadRangesNameTheKey) {
  for (const auto& [from, to, key] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"still_s: [2, 5]", "still_s: [5, 2]", "still_s"},
           {"turn_s: [1, 3]", "turn_s: [0, 3]", "turn_s"},
           {"positions: 200", "positions: 0", "positions"},
           {"max_pitch_deg: 80", "max_pitch_deg: 95", "max_pitch_deg"}}) {
    std::string text = kHandheld;
    text.replace(text.find(from), from.size(), to);
    try {
      Parse(text);
      ADD_FAILURE() << to << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

// ----------------------------------------------------------------------- pendulum

TEST(CalibrationRigTest, PendulumAngleFollowsTheOde) {
  const CalibrationRigConfig c = Parse(Pendulum(""));
  ASSERT_EQ(c.kind, CalibrationRigConfig::Kind::kPendulum);
  PendulumRig rig(c.pendulum);
  EXPECT_DOUBLE_EQ(rig.c2_per_s2(), 9.80665 / 0.8);
  EXPECT_EQ(rig.c1_per_s(), 0.05);
  EXPECT_NEAR(rig.Angle_rad(0.0), 40.0 * kDegToRad, 1e-15);
  EXPECT_EQ(rig.AngleRate_radps(0.0), 0.0);
  double residual = 0.0;
  for (double t = 0.0; t < 120.0; t += 0.00737) {  // mostly between the 10 ms nodes
    residual = std::max(residual, std::fabs(rig.AngleAcceleration_rad_s2(t) +
                                            rig.c1_per_s() * rig.AngleRate_radps(t) +
                                            rig.c2_per_s2() * std::sin(rig.Angle_rad(t))));
  }
  // The quintic Hermite's theta'' between the 10 ms nodes: O(H^4 |theta^(6)|) ~ 1e-8 for
  // theta0 = 0.7 rad, omega0 = 3.5 rad/s; measured 1.3e-8 rad/s^2.
  EXPECT_LT(residual, 5e-8);
}

TEST(CalibrationRigTest, UndampedPendulumKeepsItsEnergy) {
  PendulumConfig c;
  c.length_m = 0.5;
  c.initial_angle_rad = 1.2;
  PendulumRig rig(c);
  const auto energy = [&](double t) {
    return 0.5 * std::pow(rig.AngleRate_radps(t), 2) - rig.c2_per_s2() * std::cos(rig.Angle_rad(t));
  };
  const double e0 = energy(0.0);
  double drift = 0.0;
  for (double t = 0.0; t < 600.0; t += 0.0913) drift = std::max(drift, std::fabs(energy(t) - e0));
  // RK4 at 0.71 ms steps (period 1.42 s / 100 / 10) over 600 s; measured 1e-10 of c2.
  EXPECT_LT(drift / rig.c2_per_s2(), 1e-9);
}

TEST(CalibrationRigTest, SmallSwingMatchesTheLinearSolution) {
  PendulumConfig c;
  c.c2_per_s2 = 9.0;  // omega0 = 3 rad/s
  c.damping_per_s = 0.2;
  c.initial_angle_rad = 1e-3;
  PendulumRig rig(c);
  const double w0 = 3.0, zeta = 0.2 / (2.0 * w0), wd = w0 * std::sqrt(1.0 - zeta * zeta);
  double worst = 0.0;
  for (double t = 0.0; t < 20.0; t += 0.0131) {
    const double linear =
        1e-3 * std::exp(-zeta * w0 * t) * (std::cos(wd * t) + zeta * w0 / wd * std::sin(wd * t));
    worst = std::max(worst, std::fabs(rig.Angle_rad(t) - linear));
  }
  // sin(theta) = theta - theta^3/6 shifts the frequency by theta0^2/16: a phase error
  // ~ w0 t theta0^2 / 16 = 4e-6 rad over 20 s, i.e. < 4e-9 rad of angle; measured 3.6e-10.
  EXPECT_LT(worst, 1e-8);
}

struct MountingCase {
  const char* yaml;       ///< the mounting key
  Eigen::Matrix3d R_p_b;  ///< expected mounting
};

std::vector<MountingCase> SeedMountings() {
  Eigen::Matrix3d ned = Eigen::Matrix3d::Identity(), dne, edn;
  dne << 0, 1, 0, 0, 0, 1, 1, 0, 0;  // x down, y north, z east
  edn << 0, 0, 1, 1, 0, 0, 0, 1, 0;  // x east, y down, z north
  return {{"  mounting: NED\n", ned},
          {"  mounting: DNE\n", dne},
          {"  mounting: edn\n", edn},
          {"  mounting_deg: [30, 0, 30]\n", DcmFromEuler(30 * kDegToRad, 0.0, 30 * kDegToRad)}};
}

TEST(CalibrationRigTest, PendulumMountingsGiveTheBobAttitudeAndRates) {
  for (const MountingCase& m : SeedMountings()) {
    const CalibrationRigConfig c = Parse(Pendulum(m.yaml));
    ASSERT_TRUE(c.pendulum.mounting_p_b.isApprox(m.R_p_b, 1e-15)) << m.yaml;
    PendulumRig rig(c.pendulum);
    double attitude = 0.0, rate = 0.0, position = 0.0;
    for (double t = 1e-4; t < 30.0; t += 0.0173) {
      const double theta = rig.Angle_rad(t);
      const Eigen::Matrix3d R_n_p =
          Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY()).toRotationMatrix();
      const Eigen::Vector3d e = rig.Euler_rad(t);
      attitude = std::max(attitude, AttitudeError(QuatFromEuler(e.x(), e.y(), e.z()),
                                                  QuatFromDcm(Eigen::Matrix3d(R_n_p * m.R_p_b)))
                                        .norm());
      // Body rate over NED: theta' about the pivot axis (east) in IMU axes.
      const Eigen::Vector3d de = rig.EulerRate_radps(t);
      const double sr = std::sin(e.x()), cr = std::cos(e.x()), sp = std::sin(e.y()),
                   cp = std::cos(e.y());
      const Eigen::Vector3d omega_nb_b(de.x() - de.z() * sp, de.y() * cr + de.z() * sr * cp,
                                       -de.y() * sr + de.z() * cr * cp);
      rate =
          std::max(rate, (omega_nb_b - rig.AngleRate_radps(t) * m.R_p_b.transpose().col(1)).norm());
      // The IMU moves on the circle L (sin theta, 0, cos theta) about the pivot.
      const auto bob = [&](double s) {
        const double th = rig.Angle_rad(s);
        return Eigen::Vector3d(0.8 * std::sin(th), 0.0, 0.8 * std::cos(th));
      };
      position = std::max(position,
                          ((bob(t + 1e-5) - bob(t - 1e-5)) / 2e-5 - rig.Velocity_n_mps(t)).norm());
    }
    EXPECT_LT(attitude, 1e-12) << m.yaml;  // rounding: measured 7e-16 rad
    EXPECT_LT(rate, 1e-12) << m.yaml;      // rounding: measured 6e-16 rad/s
    EXPECT_LT(position, 1e-8) << m.yaml;   // central difference, h = 1e-5 s: measured 6e-10
    EXPECT_LT(DerivativeMismatch(rig, 1e-4, 30.0, 0.0091), 1e-7) << m.yaml;  // measured 4e-9
    EXPECT_EQ(PointMismatch(rig, 0.0, 30.0, 0.0091), 0.0) << m.yaml;
  }
}

TEST(CalibrationRigTest, PendulumExactIncrementsReproduceTheAttitudeForEveryMounting) {
  for (const MountingCase& m : SeedMountings()) {
    PendulumRig rig(Parse(Pendulum(m.yaml)).pendulum);
    const RoundTrip r = Mechanize(rig, 120.0);
    // The issue's bound is 1e-4 deg; measured 4.2e-10 deg for every mounting (DNE passes
    // through pitch -90 deg): rotation about a fixed axis has no coning. 1e-8 deg: 20x.
    EXPECT_LT(r.attitude_deg, 1e-8) << m.yaml;
    // The strapdown's sculling error on a 0.56 Hz swing of 2.4 rad/s over 120 s: measured
    // 0.05 mm, 6e-7 m/s.
    EXPECT_LT(r.position_m, 1e-3) << m.yaml;
    EXPECT_LT(r.velocity_mps, 1e-5) << m.yaml;
  }
}

// ------------------------------------------------------------------------ parsing

TEST(CalibrationRigTest, BadRigConfigurationsNameTheKey) {
  const auto expect_error = [](const std::string& text, const std::string& part) {
    try {
      Parse(text);
      ADD_FAILURE() << "no InputError for " << part;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  expect_error("trajectory: {kind: turntable}", "trajectory.kind");
  expect_error("trajectory: {kind: multiposition}", "trajectory.steps");
  expect_error("trajectory: {kind: multiposition, steps: [{euler_deg: [0, 0, 0], rotate: yaw}]}",
               "either euler_deg");
  expect_error("trajectory: {kind: multiposition, steps: [{rotate: spin, rate_deg_s: 1}]}",
               "trajectory.steps[0].rotate");
  expect_error(
      "trajectory: {kind: multiposition, steps: [{rotate: yaw, rate_deg_s: 1, ramp_s: 0}]}",
      "must be > 0");
  expect_error("trajectory: {kind: multiposition, steps: [{euler_deg: [0, 0, 0], rate_deg_s: 1}]}",
               "only for a rotation");
  expect_error(Pendulum("  mounting: NND\n"), "trajectory.mounting");
  expect_error(Pendulum("  mounting: NEU\n"), "right-handed");
  expect_error(Pendulum("  mounting: NED\n  mounting_deg: [0, 0, 0]\n"), "not both");
  expect_error(Pendulum("  length: 1\n"), "unknown key");
  expect_error(Pendulum("  angle_noise_deg: -0.01\n"), "trajectory.angle_noise_deg");
  expect_error(Pendulum("  initial_rate_deg_s: 2000\n"), "over the top");
  // x within 0.01 deg of the swing plane passes within 0.01 deg of the vertical.
  std::string small_swing = Pendulum("  mounting_deg: [0, -89.99, 0.01]\n");
  small_swing.replace(small_swing.find("initial_angle_deg: 40"), 21, "initial_angle_deg: 5");
  expect_error(small_swing, "too close to the vertical");
}

TEST(CalibrationRigTest, PendulumMountingParserAndEncoderKeys) {
  // The parser the pendulum calibration record shares with the rig.
  const auto mounting = [](const std::string& text) { return ParsePendulumMounting(ParseYaml(text, "m.yaml")); };
  Eigen::Matrix3d dne;
  dne << 0, 1, 0, 0, 0, 1, 1, 0, 0;  // IMU x down, y north, z east: columns in the bob frame
  EXPECT_TRUE(mounting("mounting: DNE").isApprox(dne, 0.0));
  EXPECT_TRUE(mounting("other: 1").isIdentity(0.0));
  EXPECT_TRUE(mounting("mounting_deg: [30, 0, 30]").isApprox(DcmFromEuler(M_PI / 6, 0.0, M_PI / 6), 1e-15));
  const CalibrationRigConfig c = Parse(Pendulum("  angle_noise_deg: 0.01\n  angle_quantum_deg: 0.002\n"));
  EXPECT_DOUBLE_EQ(c.pendulum.angle_noise_rad, 0.01 * kDegToRad);
  EXPECT_DOUBLE_EQ(c.pendulum.angle_quantum_rad, 0.002 * kDegToRad);
  EXPECT_EQ(Parse(Pendulum("")).pendulum.angle_noise_rad, 0.0);  // default: a perfect encoder
}

TEST(CalibrationRigTest, EmitDrawnDescribesTheRig) {
  std::unique_ptr<CalibrationRig> table = MakeCalibrationRig(Parse(kTable));
  std::unique_ptr<CalibrationRig> pendulum =
      MakeCalibrationRig(Parse(Pendulum("  mounting: DNE\n")));
  YAML::Emitter out;
  out << YAML::BeginSeq;
  table->EmitDrawn(out);
  pendulum->EmitDrawn(out);
  out << YAML::EndSeq;
  ASSERT_TRUE(out.good());
  const YAML::Node y = YAML::Load(out.c_str());
  EXPECT_EQ(y[0]["static_intervals"].size(), 9u);
  EXPECT_DOUBLE_EQ(y[0]["static_intervals"][1]["euler_deg"][0].as<double>(), 180.0);
  EXPECT_DOUBLE_EQ(y[1]["c2_per_s2"].as<double>(), 9.80665 / 0.8);
  EXPECT_DOUBLE_EQ(y[1]["pivot_axis_b"][2].as<double>(), 1.0);  // DNE: the IMU z axis is east
}

}  // namespace sim_calibration_rig_test
}  // namespace navtwin::sim
