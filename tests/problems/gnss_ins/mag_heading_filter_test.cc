// Regression: the 3-axis tilt-compensated heading (MagConfig::Mode::kHeading, MagHeading)
// with its honest sigma (0.1 uT per-axis noise over the 27 uT horizontal field = 0.21 deg)
// at 50 Hz in the simulated straight and level MEMS flight. The former bare-angle model
// walked roll and pitch to ~28 deg in 300 s while reporting 0.5 deg std (errors in
// variables, factors/mag_heading.h); the filter must now stay accurate and consistent.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <stdlib.h>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "core/io/open.h"
#include "core/rotation.h"
#include "core/sim/scenario.h"
#include "core/sim/simulator.h"
#include "core/units.h"
#include "problems/gnss_ins/filter.h"
#include "problems/ins/nav_error.h"
#include "tests/problems/gnss_ins/sim_record.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_mag_heading_filter_test {

using namespace test_records;  // SimulateRecord, Vec3, TruthAt

TEST(MagHeadingFilter, LevelFlightHonestSigmaStaysAccurateAndConsistent) {
  // Simulate the preset (seed 1) and read it as a user would.
  const SimRecord r = SimulateRecord(sim::LoadScenario("mems-gps-mag-level-flight"), 1);
  const Inputs& in = r.inputs;
  const std::vector<NavState>& truth = r.truth;
  const NavState& init = r.init;
  const YAML::Node& errors = r.errors;

  // The seed-001 MEMS configuration of filter_test.cc (MemsConfig): doubled ARW and VRW,
  // the preset's bias sigmas, 1 h Gauss-Markov; tilt 0.5 deg, heading 10 deg initial std.
  GnssInsConfig c;
  const YAML::Node imu = errors["imu"]["errors"];
  c.imu_noise.gyro_arw_rad_per_sqrt_s = 2.0 * imu["gyro"]["arw_deg_sqrt_h"].as<double>() * kDegToRad / 60.0;
  c.imu_noise.accel_vrw_mps_per_sqrt_s = 2.0 * imu["accel"]["vrw_m_s_sqrt_h"].as<double>() / 60.0;
  c.imu_noise.gyro_bias_std_radps = 144.0 * kDegToRad / 3600.0;
  c.imu_noise.accel_bias_std_mps2 = 25500.0 * kMicroG_mps2;
  c.imu_noise.correlation_time_s = 3600.0;
  c.init.source = InitConfig::Source::kGiven;
  c.init.state = InsState{init, ImuErrors{}};
  c.init.std.pos_ned_m.setConstant(5.0);
  c.init.std.vel_ned_mps.setConstant(0.5);
  c.init.std.att_rad = Eigen::Vector3d(0.5, 0.5, 10.0) * kDegToRad;
  c.installation.antenna_lever_arm_b_m = Vec3(errors["gnss"]["lever_arm_b_m"]);
  const YAML::Node mag = errors["mag"];
  c.mag.mode = MagConfig::Mode::kHeading;
  c.mag.declination_rad = mag["declination_deg"].as<double>() * kDegToRad;
  c.mag.iron.hard_iron_uT = Vec3(mag["hard_iron_uT"]);
  for (int i = 0; i < 3; ++i) c.mag.iron.soft_iron.row(i) = Vec3(mag["soft_iron"][i]).transpose();
  // The projected noise: per-axis noise over the horizontal intensity, 0.1 / 27.2 uT =
  // 0.21 deg (the vertical noise does not enter to first order). No field vector given.
  c.mag.heading_std_rad = mag["noise_uT"].as<double>() / Vec3(mag["field_ned_uT"]).head<2>().norm();

  const FilterResult result = RunFilter(in, c, false, {}, nullptr);
  EXPECT_GT(result.filter.counts.at("mag").used, 14900u);  // 50 Hz over 300 s
  NavErrorStats stats;
  double worst_ratio = 0.0;  // max over knots after 60 s of |error| / std, roll pitch yaw
  for (const NavEpoch& e : result.filter.epochs) {
    if (e.state.nav.t_s < 60.0) continue;
    const NavError err = CompareNav(e.state.nav, TruthAt(truth, e.state.nav.t_s));
    stats.Add(err);
    for (int i = 0; i < 3; ++i) worst_ratio = std::max(worst_ratio, std::abs(err.rpy_rad[i]) / e.std[err::kAtt + i]);
  }
  const double roll = stats.Rms(6) * kRadToDeg, pitch = stats.Rms(7) * kRadToDeg, yaw = stats.Rms(8) * kRadToDeg;
  std::printf("[ figures  ] heading mode, sigma %.2f deg, 50 Hz, level flight: RMS roll %.2f, pitch %.2f, yaw "
              "%.2f deg; max |error| / std %.2f\n",
              c.mag.heading_std_rad * kRadToDeg, roll, pitch, yaw, worst_ratio);
  // Issue 4 / seed 001 bounds (filter_test.cc ExpectSeedAccuracy). Fixed: 0.49, 0.58,
  // 0.29 deg; the bare-angle model: 19, 12, 3.4 deg (yaw 4 deg with only its bias fixed).
  EXPECT_LT(roll, 0.7);
  EXPECT_LT(pitch, 0.7);
  EXPECT_LT(yaw, 1.0);
  // Consistency: the errors stay inside 3 std of the reported attitude std (fixed: 1.3;
  // bare angle: 48, the 28 deg tilt against 0.56 deg std).
  EXPECT_LT(worst_ratio, 3.0);
}

}  // namespace gnss_ins_mag_heading_filter_test
}  // namespace navtwin::gnss_ins
