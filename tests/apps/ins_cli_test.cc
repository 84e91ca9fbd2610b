// navtwin ins on hostile input: IMU gaps, polar starts and impossible solutions are refused
// with exit 1, a message naming the file and the time, and no output left behind.
#include <cstdio>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/apps/cli_util.h"

namespace navtwin {
namespace ins_cli_test {

using namespace cli_test;  // RunResult, Navtwin, MakeTempDir, Exists

/// A KF-GINS IMU file of `n` samples at 100 Hz (level, at rest: dv_z = -g dt), the last one
/// `gap_s` after the one before it.
std::string WriteImu(const std::string& dir, int n, double gap_s) {
  const std::string path = dir + "/imu.txt";
  std::ofstream f(path);
  f.precision(17);
  for (int i = 1; i <= n; ++i) {
    const double dt = i == n ? gap_s : 0.01;
    const double t = i == n ? (n - 1) * 0.01 + gap_s : i * 0.01;
    f << t << " 0 0 0 0 0 " << -9.80665 * dt << "\n";
  }
  return path;
}

/// The initial state file: at rest at `lat_deg`, 45 deg E, 100 m, at t = 0.
std::string WriteInit(const std::string& dir, double lat_deg) {
  const std::string path = dir + "/init.nav";
  std::ofstream(path) << "0 0.0 " << lat_deg << " 45.0 100.0 0 0 0 0 0 0\n";
  return path;
}

RunResult RunIns(const std::string& dir, const std::string& imu, const std::string& init) {
  return Navtwin("ins --imu " + imu + " --init_from " + init + " --out " + dir + "/out");
}

void ExpectRefused(const RunResult& r, const std::string& dir, std::initializer_list<std::string> parts) {
  EXPECT_EQ(r.exit_code, 1) << r.err;
  for (const std::string& p : parts) EXPECT_NE(r.err.find(p), std::string::npos) << p << " not in: " << r.err;
  EXPECT_FALSE(Exists(dir + "/out")) << "a failed run leaves no output folder";
}

TEST(InsCli, RefusesAHugeImuGap) {
  // 100 samples, the last 1e7 s after the one before: integrated across, the solution
  // reached latitude -180.9 deg and a height of 7e19 m.
  const std::string dir = MakeTempDir("ins_gap");
  const std::string imu = WriteImu(dir, 100, 1e7);
  ExpectRefused(RunIns(dir, imu, WriteInit(dir, 30.0)), dir,
                {imu, "IMU gap of 10000000 s", "t = 0.99", "t = 10000000.99 s", "max_bridge_gap_s"});
}

TEST(InsCli, RefusesAThousandSecondImuGap) {
  const std::string dir = MakeTempDir("ins_gap");
  const std::string imu = WriteImu(dir, 100, 1000.0);
  ExpectRefused(RunIns(dir, imu, WriteInit(dir, 30.0)), dir, {imu, "IMU gap of 1000 s", "max_bridge_gap_s"});
}

TEST(InsCli, BridgesAShortImuGap) {
  const std::string dir = MakeTempDir("ins_gap");
  const std::string imu = WriteImu(dir, 100, 0.05);
  const RunResult r = RunIns(dir, imu, WriteInit(dir, 30.0));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(Exists(dir + "/out/nav.nav"));
  // A longer gap is bridged when the flag allows it.
  const std::string imu2 = WriteImu(dir, 100, 0.5);
  const RunResult r2 = Navtwin("ins --imu " + imu2 + " --init_from " + dir + "/init.nav --out " + dir +
                               "/out2 --max_bridge_gap_s 1");
  EXPECT_EQ(r2.exit_code, 0) << r2.err;
}

TEST(InsCli, RefusesAPolarStart) {
  // From latitude 90 deg the next epoch was at -38.5 deg with v_N = -5.7e9 m/s.
  const std::string dir = MakeTempDir("ins_pole");
  const std::string imu = WriteImu(dir, 100, 0.01);
  const std::string init = WriteInit(dir, 90.0);
  ExpectRefused(RunIns(dir, imu, init), dir, {init, "initial state at t = 0 s", "latitude 90", "pole"});
  ExpectRefused(RunIns(dir, imu, WriteInit(dir, -89.995)), dir, {"latitude -89.995", "pole"});
  const RunResult flags = Navtwin("ins --imu " + imu + " --init_lat_deg 90 --init_lon_deg 0 --init_yaw_deg 0 --out " +
                                  dir + "/out");
  ExpectRefused(flags, dir, {"--init_lat_deg", "pole"});
  // 89.9 deg (11 km from the pole) is still navigated.
  const RunResult near = RunIns(dir, imu, WriteInit(dir, 89.9));
  EXPECT_EQ(near.exit_code, 0) << near.err;
}

TEST(InsCli, RefusesAnImpossibleStartHeight) {
  const std::string dir = MakeTempDir("ins_height");
  const std::string imu = WriteImu(dir, 100, 0.01);
  const std::string init = dir + "/init.nav";
  std::ofstream(init) << "0 0.0 30.0 45.0 7e19 0 0 0 0 0 0\n";
  ExpectRefused(RunIns(dir, imu, init), dir, {init, "line 1", "field 'h'", "implausible height"});
  const RunResult flags = Navtwin("ins --imu " + imu + " --init_lat_deg 30 --init_lon_deg 0 --init_yaw_deg 0 "
                                  "--init_h_m -5e6 --out " + dir + "/out");
  ExpectRefused(flags, dir, {"--init_h_m", "initial state at t = 0 s", "height -5000000 m", "plausible band"});
}

TEST(InsCli, RefusesAnImpossibleSolution) {
  // 1 s samples (each plausible: 410 m/s^2 upwards) that accelerate the solution out of the
  // Earth's surroundings: the height passes 1e7 m (at about 220 s, below 1e5 m/s); with
  // 9999 m/s^2 the velocity passes 1e5 m/s first (at 11 s).
  const std::string dir = MakeTempDir("ins_escape");
  for (const double f : {410.0, 9999.0}) {
    const std::string imu = dir + "/imu.txt";
    {
      std::ofstream f_out(imu);
      for (int i = 1; i <= 400; ++i) f_out << i << " 0 0 0 0 0 " << -f << "\n";
    }
    const RunResult r = Navtwin("ins --imu " + imu + " --init_from " + WriteInit(dir, 30.0) + " --out " + dir +
                                "/out --max_bridge_gap_s 2");
    if (f < 1000.0) {
      ExpectRefused(r, dir, {imu, "the solution (pure inertial navigation) at t = ", "height", "plausible band"});
    } else {
      ExpectRefused(r, dir, {imu, "the solution (pure inertial navigation) at t = 11 s", "velocity component"});
    }
  }
}

}  // namespace ins_cli_test
}  // namespace navtwin
