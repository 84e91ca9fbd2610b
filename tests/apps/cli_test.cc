// End-to-end checks of the navtwin command: exit codes, messages that name file and
// line, no partial output, the demo's error table, and the acceptance facts of `info`.
#include <dirent.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/apps/cli_util.h"

#include "tests/test_data.h"

namespace navtwin {
namespace apps_cli_test {

using namespace cli_test;  // RunResult, Navtwin, ReadAll, MakeTempDir, Exists, JsonNumberAfter







TEST(Cli, HelpListsSubcommandsAndFlags) {
  const RunResult main_help = Navtwin("--help");
  EXPECT_EQ(main_help.exit_code, 0);
  for (const char* sub : {"info", "convert", "ins"}) {
    EXPECT_NE(main_help.out.find(sub), std::string::npos) << sub;
  }
  const RunResult ins_help = Navtwin("ins --help");
  EXPECT_EQ(ins_help.exit_code, 0);
  EXPECT_NE(ins_help.out.find("--init_lat_deg"), std::string::npos);
  EXPECT_NE(ins_help.out.find("--format"), std::string::npos);
}

TEST(Cli, MisuseExitsWithUsageCode) {
  EXPECT_EQ(Navtwin("").exit_code, 2);
  EXPECT_EQ(Navtwin("no-such-subcommand").exit_code, 2);
  const RunResult no_out = Navtwin("ins --imu x.txt --init_from y.nav");
  EXPECT_EQ(no_out.exit_code, 2);
  EXPECT_NE(no_out.err.find("--out"), std::string::npos);
  // A flag of another subcommand is refused rather than silently ignored.
  const RunResult foreign = Navtwin("info --init_lat_deg 3 x.txt");
  EXPECT_EQ(foreign.exit_code, 2);
  EXPECT_NE(foreign.err.find("init_lat_deg"), std::string::npos);
}

TEST(Cli, UnknownFlagExitsWithUsageCode) {
  const RunResult r = Navtwin("navigate --nosuchflag");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown flag --nosuchflag"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("usage: navtwin navigate"), std::string::npos) << r.err;
  EXPECT_EQ(Navtwin("info --nosuchflag=3 x.txt").exit_code, 2);
  EXPECT_EQ(Navtwin("simulate --noperfectly").exit_code, 2);
}

TEST(Cli, BadFlagValueExitsWithUsageCode) {
  const RunResult seed = Navtwin("simulate --scenario mems-gps-mag-maneuver --seed=abc --out x");
  EXPECT_EQ(seed.exit_code, 2);
  EXPECT_NE(seed.err.find("bad value 'abc' for --seed"), std::string::npos) << seed.err;
  EXPECT_EQ(Navtwin("navigate --output_rate_hz fast").exit_code, 2);
  EXPECT_EQ(Navtwin("level-mc --runs=1.5").exit_code, 2);
  EXPECT_EQ(Navtwin("ins --demo=maybe").exit_code, 2);
  const RunResult missing = Navtwin("allan --axis");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("--axis needs a value"), std::string::npos) << missing.err;
}

TEST(Cli, FlagSyntaxFollowsGflags) {
  // --name value, --name=value, a boolean without a value, and "--" before positional arguments.
  const std::string dir = MakeTempDir("flag_syntax");
  const RunResult demo = Navtwin("ins --demo --demo_duration_s=2 --out " + dir);
  ASSERT_EQ(demo.exit_code, 0) << demo.err;
  const RunResult info = Navtwin("info --format=json -- " + dir + "/imu.txt");
  EXPECT_EQ(info.exit_code, 0) << info.err;
}

TEST(Cli, VersionPrintsProjectVersionAndCommit) {
  const RunResult r = Navtwin("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_TRUE(std::regex_match(r.out, std::regex("navtwin [0-9]+\\.[0-9]+\\.[0-9]+ \\(commit ([0-9a-f]{4,}|unknown)\\)\n")))
      << r.out;
}

TEST(Cli, InfoNamesTheLineWhereTimeGoesBackwards) {
  const std::string path = MakeTempDir("cli") + "/imu.txt";
  {
    std::ofstream f(path);
    f.precision(12);
    for (int line = 1; line <= 2000; ++line) {
      const double t = line == 1234 ? 1000.0 : 1000.0 + 0.005 * line;  // line 1234 goes back
      f << t << " 1e-5 -2e-5 3e-5 0.001 -0.002 -0.049\n";
    }
  }
  const RunResult r = Navtwin("info " + path);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(path), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("line 1234"), std::string::npos) << r.err;
}

TEST(Cli, DemoNavigatesWithSmallErrorsAndWritesTheSolution) {
  const std::string dir = MakeTempDir("cli");
  const RunResult r = Navtwin("ins --demo --demo_duration_s 60 --out " + dir + " --format=json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Exact increments through 17-digit text files: micrometres and 1e-10 deg over 60 s
  // (the strapdown tests); 0.1 mm and 1e-7 deg catch any unit or frame slip.
  EXPECT_LT(JsonNumberAfter(r.out, "\"horizontal_m\"", "max"), 1e-4) << r.out;
  EXPECT_LT(JsonNumberAfter(r.out, "\"yaw_deg\"", "max"), 1e-7) << r.out;
  EXPECT_EQ(JsonNumberAfter(r.out, "{", "imu_samples"), 6000) << r.out;
  EXPECT_TRUE(Exists(dir + "/nav.nav"));
  // The text table has the same rows.
  const RunResult text = Navtwin("ins --imu " + dir + "/imu.txt --init_from " + dir +
                                 "/truth.nav --truth " + dir + "/truth.nav --out " + dir + "/again");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("pos N [m]"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("yaw [deg]"), std::string::npos) << text.out;
}

TEST(Cli, BadInputLeavesNoPartialOutput) {
  const std::string dir = MakeTempDir("cli");
  const std::string imu = dir + "/imu.txt", nav = dir + "/init.nav";
  {
    std::ofstream f(imu);
    f << "0.005 0 0 0 0 0 -0.049\n0.010 0 0 0 0 0 -0.049\n0.015 0 nan 0 0 0 -0.049\n";
    std::ofstream g(nav);
    g << "0 0.0 45.0 7.0 100.0 0 0 0 0 0 0\n";
  }
  const RunResult r = Navtwin("ins --imu " + imu + " --init_from " + nav + " --out " + dir + "/out");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("line 3"), std::string::npos) << r.err;
  // No temporary file and no output folder left behind either: the run created the folder.
  EXPECT_FALSE(Exists(dir + "/out"));
  // A folder that existed before stays (empty).
  ASSERT_EQ(::mkdir((dir + "/existing").c_str(), 0755), 0);
  EXPECT_EQ(Navtwin("ins --imu " + imu + " --init_from " + nav + " --out " + dir + "/existing").exit_code, 1);
  DIR* d = ::opendir((dir + "/existing").c_str());
  ASSERT_NE(d, nullptr);
  int entries = 0;
  while (const dirent* e = ::readdir(d)) entries += e->d_name[0] != '.';
  ::closedir(d);
  EXPECT_EQ(entries, 0);
}

TEST(Cli, InfoOnRealUlogShowsImuAndGpsRates) {
  const std::string path = testing::DataPath("px4-ulog/ekf_failure.ulg");
  NAVTWIN_REQUIRE_DATA(path);
  const RunResult r = Navtwin("info " + path + " --format=json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The facts: sensor_combined near 199 Hz, vehicle_gps_position at 5 Hz.
  // Median interval 5.000 ms (jitter 4.875-5.125 ms): nominal 200 Hz; 15843 samples over
  // 79.54 s: mean 199.18 Hz.
  EXPECT_NEAR(JsonNumberAfter(r.out, "\"name\":\"sensor_combined\"", "rate_hz"), 200.0, 0.1) << r.out;
  EXPECT_NEAR(JsonNumberAfter(r.out, "\"name\":\"sensor_combined\"", "mean_rate_hz"), 199.18, 0.05) << r.out;
  EXPECT_NEAR(JsonNumberAfter(r.out, "\"name\":\"vehicle_gps_position\"", "rate_hz"), 5.0, 0.2) << r.out;
}

TEST(Cli, ConvertRoundTripsThroughCsvExactly) {
  const std::string dir = MakeTempDir("cli");
  ASSERT_EQ(Navtwin("ins --demo --demo_duration_s 5 --out " + dir).exit_code, 0);
  const RunResult to_csv = Navtwin("convert --in " + dir + "/imu.txt --out " + dir + "/imu.csv");
  ASSERT_EQ(to_csv.exit_code, 0) << to_csv.err;
  EXPECT_NE(to_csv.out.find("converted 500 imu samples"), std::string::npos) << to_csv.out;
  const RunResult back = Navtwin("convert --in " + dir + "/imu.csv --out " + dir + "/imu2.txt --format=json");
  ASSERT_EQ(back.exit_code, 0) << back.err;
  EXPECT_EQ(JsonNumberAfter(back.out, "{", "samples"), 500) << back.out;
  // 17 significant digits both ways: the text is identical.
  EXPECT_TRUE(ReadAll(dir + "/imu.txt") == ReadAll(dir + "/imu2.txt"));
  // Navigation (attitude goes through a quaternion, so only the count is compared) and a
  // refused combination.
  const RunResult nav = Navtwin("convert --in " + dir + "/truth.nav --out " + dir + "/truth2.nav --format=json");
  EXPECT_EQ(nav.exit_code, 0) << nav.err;
  EXPECT_EQ(JsonNumberAfter(nav.out, "{", "samples"), 501) << nav.out;
  const RunResult refused = Navtwin("convert --in " + dir + "/truth.nav --out " + dir + "/x.csv");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_FALSE(Exists(dir + "/x.csv"));
}

TEST(Cli, ConvertsRealUlogImuToKfgins) {
  const std::string path = testing::DataPath("px4-ulog/ekf_failure.ulg");
  NAVTWIN_REQUIRE_DATA(path);
  const std::string out = MakeTempDir("cli") + "/imu.txt";
  const RunResult r = Navtwin("convert --in " + path + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const RunResult info = Navtwin("info " + out + " --format=json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  // Every sensor_combined sample of the log (count measured by the ULog tests).
  EXPECT_EQ(JsonNumberAfter(info.out, "\"name\"", "count"), 15843) << info.out;
  EXPECT_NE(info.out.find("kfgins-imu"), std::string::npos) << info.out;
}

// The simulator issue's acceptance: a perfect one-hour navigation-grade record, navigated
// by `navtwin ins` from its first truth record, ends within 1 cm and 1e-4 deg of the truth.
TEST(Cli, PerfectNavGradeHourRoundTripsThroughIns) {
  const std::string dir = MakeTempDir("cli");
  const RunResult sim =
      Navtwin("simulate --scenario nav-grade-vehicle-1h --perfect --seed 3 --out " + dir + " --format=json");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  EXPECT_EQ(JsonNumberAfter(sim.out, "{", "imu_samples"), 720000) << sim.out;
  EXPECT_EQ(JsonNumberAfter(sim.out, "{", "gnss_samples"), 3601) << sim.out;
  const RunResult ins = Navtwin("ins --imu " + dir + "/imu.txt --init_from " + dir + "/truth.nav --truth " +
                                dir + "/truth.nav --out " + dir + "/ins --output_rate_hz 1 --format=json");
  ASSERT_EQ(ins.exit_code, 0) << ins.err;
  const double final_pos_m = std::hypot(JsonNumberAfter(ins.out, "\"pos_n_m\"", "final"),
                                        JsonNumberAfter(ins.out, "\"pos_e_m\"", "final"),
                                        JsonNumberAfter(ins.out, "\"pos_d_m\"", "final"));
  EXPECT_LT(final_pos_m, 0.01) << ins.out;
  for (const char* axis : {"\"roll_deg\"", "\"pitch_deg\"", "\"yaw_deg\""}) {
    EXPECT_LT(std::abs(JsonNumberAfter(ins.out, axis, "final")), 1e-4) << axis << ins.out;
  }
  for (const char* f : {"/imu.txt", "/truth.nav", "/gnss.txt", "/ins/nav.nav"}) std::remove((dir + f).c_str());
}

TEST(Cli, AllanReadsBackTheSimulatedNoise) {
  const std::string dir = MakeTempDir("cli");
  const std::string yaml = dir + "/static.yaml";
  std::ofstream(yaml) << "name: static-noise\nstart: {lat_deg: 45, lon_deg: 0, h_m: 0}\n"
                         "trajectory:\n  segments:\n    - {kind: static, duration_s: 1800}\n"
                         "imu:\n  rate_hz: 100\n  errors:\n    gyro: {arw_deg_sqrt_h: 0.1}\n";
  ASSERT_EQ(Navtwin("simulate --scenario " + yaml + " --seed 5 --out " + dir).exit_code, 0);
  const RunResult r = Navtwin("allan " + dir + "/imu.txt --axis gx --format=json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // 0.1 deg/sqrt(h) in, read off at tau = 1 s from 180,000 samples: the Allan deviation
  // there has ~0.2 % sampling error; 10 % covers the fit's slope window.
  EXPECT_NEAR(JsonNumberAfter(r.out, "\"gx\"", "arw_deg_sqrt_h"), 0.1, 0.01) << r.out;
}

}  // namespace apps_cli_test
}  // namespace navtwin
