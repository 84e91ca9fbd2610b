// TrajectoryScorer: interpolation of the solution to the reference epochs, RMS / max per
// component, outage drifts, and GNSS references at the antenna.
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

/// A straight drive north-east at 10 m/s from (30 deg, 114 deg, 20 m), yaw 45 deg.
NavState Truth(double t) {
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
  s.q_n_b = QuatFromEuler(0.0, 0.0, 45.0 * kDegToRad);
  return s;
}

/// `s` moved by d_ned metres (first order, exact enough over metres).
NavState Moved(NavState s, const Eigen::Vector3d& d_ned) {
  s.lat_rad += d_ned.x() / (wgs84::MeridianRadius(s.lat_rad) + s.h_m);
  s.lon_rad += d_ned.y() / ((wgs84::PrimeVerticalRadius(s.lat_rad) + s.h_m) * std::cos(s.lat_rad));
  s.h_m -= d_ned.z();
  return s;
}

/// Truth file at 10 Hz over [0, 100] s.
std::string TruthFile() {
  const std::string path = TempFilePath("truth.nav");
  KfginsNavWriter w(path);
  for (int k = 0; k <= 1000; ++k) w.Write(Truth(k / 10.0));  // k / 10.0: exact at whole tenths
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
    scorer->Add(s);
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
  for (int k = 10; k <= 50; ++k) scorer->Add(Truth(k));
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
    scorer->Add(Moved(Truth(t), {0.06 * ramp, 0.08 * ramp, -0.05 * ramp}));
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
    with->Add(Truth(0.05 * k));
    without->Add(Truth(0.05 * k));
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

TEST(TrajectoryScorer, SolutionTimesMustIncrease) {
  auto scorer = OpenReference(TruthFile(), {}, Eigen::Vector3d::Zero());
  scorer->Add(Truth(1.0));
  EXPECT_THROW(scorer->Add(Truth(1.0)), std::invalid_argument);
}

}  // namespace gnss_ins_scoring_test
}  // namespace navtwin::gnss_ins
