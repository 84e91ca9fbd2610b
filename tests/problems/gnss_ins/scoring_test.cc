// TrajectoryScorer: interpolation of the solution (and its sigma) to the reference epochs,
// RMS / max per component, outage drifts, GNSS references at the antenna, err/sigma and the
// position NEES.
#include "problems/gnss_ins/scoring.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/io/kfgins.h"
#include "core/rotation.h"
#include "tests/core/io/io_test_util.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_scoring_test {

using navtwin::testing::TempFilePath;

/// A straight drive north-east at 10 m/s from (30 deg, 114 deg, 20 m), yaw 45 deg unless
/// given (the body need not point along the track).
NavState Truth(double t, double yaw_deg = 45.0) {
  const double v = 10.0;
  NavState s;
  s.t_s = t;
  const wgs84::Geodetic origin{30.0 * kDegToRad, 114.0 * kDegToRad, 20.0};
  const Eigen::Vector3d ned(v * t / std::sqrt(2.0), v * t / std::sqrt(2.0), 0.0);
  const wgs84::Geodetic p = wgs84::NedToGeodetic(ned, origin);
  s.lat_rad = p.lat_rad;
  s.lon_rad = p.lon_rad;
  s.h_m = p.h_m;
  s.v_n_mps = Eigen::Vector3d(v / std::sqrt(2.0), v / std::sqrt(2.0), 0.0);
  s.q_n_b = QuatFromEuler(0.0, 0.0, yaw_deg * kDegToRad);
  return s;
}

/// A solution epoch: `s` with the error-state std (15 entries, ins_state.h) `std`, none
/// when empty.
NavEpoch Epoch(const NavState& s, const Eigen::VectorXd& std = Eigen::VectorXd()) {
  NavEpoch e;
  e.state.nav = s;
  e.std = std;
  return e;
}

/// A 15-entry std: position N, E, D (m), velocity N, E, D (m/s), phi_n N, E, D (rad); the
/// IMU-error entries 1.
Eigen::VectorXd Std(const Eigen::Vector3d& pos_m, const Eigen::Vector3d& vel_mps, const Eigen::Vector3d& att_rad) {
  Eigen::VectorXd sd = Eigen::VectorXd::Ones(15);
  sd.segment<3>(0) = pos_m;
  sd.segment<3>(3) = vel_mps;
  sd.segment<3>(6) = att_rad;
  return sd;
}

/// `s` moved by d_ned metres (first order, exact enough over metres).
NavState Moved(NavState s, const Eigen::Vector3d& d_ned) {
  s.lat_rad += d_ned.x() / (wgs84::MeridianRadius(s.lat_rad) + s.h_m);
  s.lon_rad += d_ned.y() / ((wgs84::PrimeVerticalRadius(s.lat_rad) + s.h_m) * std::cos(s.lat_rad));
  s.h_m -= d_ned.z();
  return s;
}

/// Truth file at 10 Hz over [0, 100] s.
std::string TruthFile(double yaw_deg = 45.0) {
  const std::string path = TempFilePath("truth.nav");
  KfginsNavWriter w(path);
  for (int k = 0; k <= 1000; ++k) w.Write(Truth(k / 10.0, yaw_deg));  // k / 10.0: exact at whole tenths
  w.Commit();
  return path;
}

// Solution at 200 Hz with a constant 1 m north error, 0.1 m/s east velocity error and a
// 0.5 deg yaw error: RMS = max = the offsets; every truth epoch in [0, 100] is compared.
TEST(TrajectoryScorer, ConstantOffsetsAgainstANavigationReference) {
  auto scorer = OpenReference(TruthFile(), {}, Eigen::Vector3d::Zero());
  for (int k = 0; k <= 20000; ++k) {
    NavState s = Moved(Truth(k / 200.0), {1.0, 0.0, 0.0});
    s.v_n_mps.y() += 0.1;
    s.q_n_b = QuatFromEuler(0.0, 0.0, 45.5 * kDegToRad);
    scorer->Add(Epoch(s));
  }
  const ScoreReport r = scorer->Report();
  EXPECT_TRUE(r.has_attitude);
  EXPECT_EQ(r.all.count(), 1001u);
  EXPECT_EQ(r.outside.count(), 1001u);
  EXPECT_EQ(r.inside.count(), 0u);
  // 1e-3 m: the first-order move and the NED conversion agree to mm over 1 km.
  EXPECT_NEAR(r.all.Rms(0), 1.0, 1e-3);
  EXPECT_NEAR(r.all.Max(0), 1.0, 1e-3);
  EXPECT_NEAR(r.all.Rms(1), 0.0, 1e-3);
  EXPECT_NEAR(r.all.Rms(4), 0.1, 1e-12);
  EXPECT_NEAR(r.all.Rms(8), 0.5 * kDegToRad, 1e-9);
  EXPECT_NEAR(r.all.HorizontalRms_m(), 1.0, 1e-3);
  EXPECT_TRUE(r.outages.empty());
  EXPECT_TRUE(std::isnan(r.outage_horizontal_rms_m));
}

// The solution at 1 Hz is interpolated to the 10 Hz truth epochs: exact for this
// straight, constant-velocity drive (linear in latitude/longitude to 1 mm over 10 m).
TEST(TrajectoryScorer, InterpolatesTheSolutionToReferenceEpochs) {
  auto scorer = OpenReference(TruthFile(), {}, Eigen::Vector3d::Zero());
  for (int k = 10; k <= 50; ++k) scorer->Add(Epoch(Truth(k)));
  const ScoreReport r = scorer->Report();
  EXPECT_EQ(r.all.count(), 401u);  // truth epochs 10.0 .. 50.0 s
  EXPECT_LT(r.all.HorizontalMax_m(), 1e-3);
  EXPECT_LT(r.all.Max(8), 1e-9);
}

// Two outages; inside them the solution drifts as a ramp (horizontal 0.1 m/s, vertical
// 0.05 m/s): each outage's drift is the ramp at its last compared epoch.
TEST(TrajectoryScorer, OutageDrifts) {
  const TrajectoryScorer::Intervals outages = {{20.0, 30.0}, {60.0, 75.0}};
  auto scorer = OpenReference(TruthFile(), outages, Eigen::Vector3d::Zero());
  for (int k = 0; k <= 20000; ++k) {
    const double t = k / 200.0;
    double ramp = 0.0;
    for (const auto& o : outages) {
      if (t >= o.first && t < o.second) ramp = t - o.first;
    }
    scorer->Add(Epoch(Moved(Truth(t), {0.06 * ramp, 0.08 * ramp, -0.05 * ramp})));
  }
  const ScoreReport r = scorer->Report();
  ASSERT_EQ(r.outages.size(), 2u);
  EXPECT_EQ(r.outages[0].epochs, 100u);  // 20.0 .. 29.9 s
  EXPECT_EQ(r.outages[1].epochs, 150u);
  // Last epochs inside: 29.9 s (ramp 9.9 s) and 74.9 s (ramp 14.9 s). 1e-3 m as above.
  EXPECT_NEAR(r.outages[0].max_horizontal_m, 0.1 * 9.9, 1e-3);
  EXPECT_NEAR(r.outages[0].max_vertical_m, 0.05 * 9.9, 1e-3);
  EXPECT_NEAR(r.outages[1].max_horizontal_m, 0.1 * 14.9, 1e-3);
  EXPECT_NEAR(r.outage_horizontal_rms_m, std::sqrt((0.99 * 0.99 + 1.49 * 1.49) / 2), 1e-3);
  EXPECT_NEAR(r.outage_vertical_rms_m, 0.5 * r.outage_horizontal_rms_m, 1e-3);
  EXPECT_EQ(r.inside.count(), 250u);
  EXPECT_EQ(r.outside.count(), 1001u - 250u);
  EXPECT_NEAR(r.outside.HorizontalMax_m(), 0.0, 1e-3);
}

// A GNSS reference sits at the antenna: a solution at the IMU with the right lever arm
// scores zero; without the lever arm it is off by R_n_b l (here yaw 45 deg, l = 1 m
// forward: 0.707 m north and east).
TEST(TrajectoryScorer, GnssReferenceAtTheAntenna) {
  const Eigen::Vector3d lever(1.0, 0.0, -0.5);
  const std::string path = TempFilePath("gnss.txt");
  {
    KfginsGnssWriter w(path);
    for (int k = 0; k <= 100; ++k) {
      const NavState t = Truth(k);
      const NavState a = Moved(t, t.q_n_b * lever);
      GnssSample g;
      g.t_s = k;
      g.lat_rad = a.lat_rad;
      g.lon_rad = a.lon_rad;
      g.h_m = a.h_m;
      g.pos_std_ned_m = Eigen::Vector3d::Constant(0.02);
      g.has_velocity = true;
      g.v_n_mps = t.v_n_mps;
      g.vel_std_ned_mps = Eigen::Vector3d::Constant(0.01);
      w.Write(g);
    }
    w.Commit();
  }
  auto with = OpenReference(path, {}, lever);
  auto without = OpenReference(path, {}, Eigen::Vector3d::Zero());
  for (int k = 0; k <= 2000; ++k) {
    with->Add(Epoch(Truth(0.05 * k)));
    without->Add(Epoch(Truth(0.05 * k)));
  }
  const ScoreReport r = with->Report();
  EXPECT_FALSE(r.has_attitude);
  EXPECT_TRUE(r.has_velocity);
  EXPECT_EQ(r.all.count(), 101u);
  EXPECT_LT(r.all.HorizontalMax_m(), 1e-3);
  EXPECT_LT(r.all.Max(2), 1e-3);
  EXPECT_LT(r.all.Max(3), 1e-9);
  const ScoreReport r0 = without->Report();
  EXPECT_NEAR(r0.all.Rms(0), 1.0 / std::sqrt(2.0), 1e-3);
  EXPECT_NEAR(r0.all.Rms(1), 1.0 / std::sqrt(2.0), 1e-3);
  EXPECT_NEAR(r0.all.Rms(2), 0.5, 1e-3);
}

// Errors that are known multiples of the solution's sigma give those ratios: position
// 1 m, -0.3 m, 0.2 m against sigmas 0.5, 0.1, 0.4 m (ratios 2, 3, 0.5; NEES 4 + 9 + 0.25),
// velocity 0.1, -0.2, 0.05 m/s against 0.1, 0.1, 0.05 (1, 2, 1), roll 0.1, pitch 0.3, yaw
// 0.5 deg against phi sigmas 0.2, 0.2, 0.25 deg (heading 45 deg and equal N, E sigmas: roll
// and pitch sigmas 0.2 deg; ratios 0.5, 1.5, 2). Inside the outage [20, 30) s every error
// is doubled: the ratios there double and the NEES is four times. Tolerances: 1e-6 on the
// position ratios (the first-order move of Moved is exact to (1 m)^2 / R ~ 1e-7 m), 1e-9
// on the others (rounding of the Euler angles and velocities).
TEST(TrajectoryScorer, ErrorsInKnownMultiplesOfSigmaGiveThoseRatios) {
  const TrajectoryScorer::Intervals outages = {{20.0, 30.0}};
  auto scorer = OpenReference(TruthFile(), outages, Eigen::Vector3d::Zero());
  EXPECT_FALSE(scorer->reference_has_std());
  std::size_t rows = 0, rows_inside = 0;
  scorer->OnEpoch([&](const ScoredEpoch& e) {
    ++rows;
    rows_inside += e.in_outage ? 1 : 0;
    EXPECT_TRUE(std::isnan(e.ref_std[0]));  // truth has no sigma
  });
  const Eigen::VectorXd sd = Std({0.5, 0.1, 0.4}, {0.1, 0.1, 0.05}, Eigen::Vector3d(0.2, 0.2, 0.25) * kDegToRad);
  for (int k = 0; k <= 20000; ++k) {
    const double t = k / 200.0;
    const double f = (t >= 20.0 && t < 30.0) ? 2.0 : 1.0;
    NavState s = Moved(Truth(t), {f * 1.0, f * -0.3, f * 0.2});
    s.v_n_mps += f * Eigen::Vector3d(0.1, -0.2, 0.05);
    s.q_n_b = QuatFromEuler(f * 0.1 * kDegToRad, f * 0.3 * kDegToRad, (45.0 + f * 0.5) * kDegToRad);
    scorer->Add(Epoch(s, sd));
  }
  const ScoreReport r = scorer->Report();
  const double ratios[9] = {2.0, 3.0, 0.5, 1.0, 2.0, 1.0, 0.5, 1.5, 2.0};
  const ConsistencyStats& out = r.consistency_outside;
  const ConsistencyStats& in = r.consistency_inside;
  const ConsistencyStats& all = r.consistency_all;
  ASSERT_EQ(out.epochs(), 901u);
  ASSERT_EQ(in.epochs(), 100u);  // 20.0 .. 29.9 s
  EXPECT_EQ(all.epochs(), 1001u);
  EXPECT_EQ(rows, 1001u);
  EXPECT_EQ(rows_inside, 100u);
  for (int c = 0; c < 9; ++c) {
    const double tol = c < 3 ? 1e-6 : 1e-9;
    EXPECT_NEAR(out.RmsRatio(c), ratios[c], tol) << c;
    EXPECT_NEAR(in.RmsRatio(c), 2.0 * ratios[c], 2.0 * tol) << c;
    EXPECT_NEAR(all.RmsRatio(c), ratios[c] * std::sqrt((901.0 + 4.0 * 100.0) / 1001.0), tol) << c;
    EXPECT_EQ(all.count(c), 1001u) << c;
    EXPECT_EQ(all.missing(c), 0u) << c;
  }
  EXPECT_NEAR(out.PosNeesMean(), 13.25, 1e-5);
  EXPECT_NEAR(in.PosNeesMean(), 4.0 * 13.25, 4e-5);
  EXPECT_EQ(all.nees_count(), 1001u);
}

// The roll / pitch sigmas are the phi sigmas about the level-projected body x and y axes:
// heading 30 deg, phi sigmas N 0.1, E 0.3 deg: roll^2 = 0.75 * 0.01 + 0.25 * 0.09 = 0.03,
// pitch^2 = 0.25 * 0.01 + 0.75 * 0.09 = 0.07 (deg^2); yaw = the D sigma. Exact up to
// rounding (1e-12 deg).
TEST(TrajectoryScorer, AttitudeSigmasFollowTheHeading) {
  auto scorer = OpenReference(TruthFile(30.0), {}, Eigen::Vector3d::Zero());
  std::vector<ScoredEpoch> rows;
  scorer->OnEpoch([&](const ScoredEpoch& e) { rows.push_back(e); });
  const Eigen::VectorXd sd = Std({1, 1, 1}, {1, 1, 1}, Eigen::Vector3d(0.1, 0.3, 0.7) * kDegToRad);
  for (int k = 0; k <= 100; ++k) scorer->Add(Epoch(Truth(k / 10.0, 30.0), sd));
  ASSERT_EQ(rows.size(), 101u);
  for (const ScoredEpoch& e : rows) {
    EXPECT_NEAR(e.sol_std[6] * kRadToDeg, std::sqrt(0.03), 1e-12);
    EXPECT_NEAR(e.sol_std[7] * kRadToDeg, std::sqrt(0.07), 1e-12);
    EXPECT_NEAR(e.sol_std[8] * kRadToDeg, 0.7, 1e-12);
    EXPECT_EQ(e.err[6], 0.0);
  }
}

// Between two solution epochs the sigma is interpolated linearly, like the position: a
// solution at 1 Hz whose sigmas alternate between 1 and 3 (every component) gives, at the
// 10 Hz reference epochs in between, 1 + 2 w or 3 - 2 w, w the fraction of the second.
// Exact up to rounding (1e-12).
TEST(TrajectoryScorer, SigmaIsInterpolatedLinearlyBetweenSolutionEpochs) {
  auto scorer = OpenReference(TruthFile(), {}, Eigen::Vector3d::Zero());
  std::vector<ScoredEpoch> rows;
  scorer->OnEpoch([&](const ScoredEpoch& e) { rows.push_back(e); });
  const auto sigma = [](int k) { return k % 2 == 0 ? 1.0 : 3.0; };
  for (int k = 10; k <= 20; ++k) scorer->Add(Epoch(Truth(k), Eigen::VectorXd::Constant(15, sigma(k))));
  ASSERT_EQ(rows.size(), 101u);  // 10.0 .. 20.0 s
  for (const ScoredEpoch& e : rows) {
    const int k = static_cast<int>(std::floor(e.t_s + 1e-9));
    const double w = e.t_s - k;
    const double expected = k == 20 ? sigma(20) : (1.0 - w) * sigma(k) + w * sigma(k + 1);
    for (int c = 0; c < 9; ++c) EXPECT_NEAR(e.sol_std[c], expected, 1e-12) << e.t_s << " " << c;
  }
  EXPECT_NEAR(rows[13].sol_std[0], 3.0 - 2.0 * 0.3, 1e-12);  // 11.3 s, between 3 (11 s) and 1 (12 s)
}

// With a GNSS reference the reference's sigma adds: a 1 m north error with solution sigma
// 0.4 m and reference sigma 0.3 m is 1 / 0.5 = 2 sigmas; both sigmas reach the rows. A
// solution without std (not computed) leaves every epoch out of the ratios and says so.
TEST(TrajectoryScorer, GnssReferenceSigmaIsCombinedAndMissingSigmaIsLeftOut) {
  const std::string path = TempFilePath("gnss_sigma.txt");
  {
    KfginsGnssWriter w(path);
    for (int k = 0; k <= 10; ++k) {
      const NavState t = Truth(k);
      GnssSample g;
      g.t_s = k;
      g.lat_rad = t.lat_rad;
      g.lon_rad = t.lon_rad;
      g.h_m = t.h_m;
      g.pos_std_ned_m = Eigen::Vector3d(0.3, 0.3, 0.6);
      w.Write(g);
    }
    w.Commit();
  }
  auto scorer = OpenReference(path, {}, Eigen::Vector3d::Zero());
  EXPECT_TRUE(scorer->reference_has_std());
  std::vector<ScoredEpoch> rows;
  scorer->OnEpoch([&](const ScoredEpoch& e) { rows.push_back(e); });
  auto no_std = OpenReference(path, {}, Eigen::Vector3d::Zero());
  const Eigen::VectorXd sd = Std({0.4, 0.4, 0.8}, {1, 1, 1}, {1, 1, 1});
  for (int k = 0; k <= 200; ++k) {
    const NavState s = Moved(Truth(0.05 * k), {1.0, 0.0, 0.0});
    scorer->Add(Epoch(s, sd));
    no_std->Add(Epoch(s));
  }
  const ScoreReport r = scorer->Report();
  EXPECT_TRUE(r.reference_has_std);
  ASSERT_EQ(rows.size(), 11u);
  EXPECT_EQ(rows[0].ref_std[0], 0.3);
  EXPECT_EQ(rows[0].sol_std[0], 0.4);
  EXPECT_TRUE(std::isnan(rows[0].err[3]));  // no velocity in the file
  EXPECT_TRUE(std::isnan(rows[0].err[6]));  // no attitude in a GNSS reference
  EXPECT_NEAR(r.consistency_all.RmsRatio(0), 2.0, 1e-6);  // 1e-6: Moved, as above
  EXPECT_NEAR(r.consistency_all.RmsRatio(1), 0.0, 1e-6);
  EXPECT_EQ(r.consistency_all.count(3), 0u);    // no velocity error: neither used
  EXPECT_EQ(r.consistency_all.missing(3), 0u);  // nor missing
  EXPECT_NEAR(r.consistency_all.PosNeesMean(), 4.0, 1e-5);
  const ScoreReport n = no_std->Report();
  EXPECT_EQ(n.consistency_all.epochs(), 11u);
  EXPECT_EQ(n.consistency_all.count(0), 0u);
  EXPECT_EQ(n.consistency_all.missing(0), 11u);
  EXPECT_TRUE(std::isnan(n.consistency_all.RmsRatio(0)));
  EXPECT_EQ(n.consistency_all.nees_count(), 0u);
  EXPECT_TRUE(std::isnan(n.consistency_all.PosNeesMean()));
}

TEST(TrajectoryScorer, SolutionTimesMustIncrease) {
  auto scorer = OpenReference(TruthFile(), {}, Eigen::Vector3d::Zero());
  scorer->Add(Epoch(Truth(1.0)));
  EXPECT_THROW(scorer->Add(Epoch(Truth(1.0))), std::invalid_argument);
}

}  // namespace gnss_ins_scoring_test
}  // namespace navtwin::gnss_ins
