// End to end on the ANSFL quadrotor data (docs/gnss-ins.md, "Smoothing an ANSFL DOT"):
// `navtwin convert --what gnss` from the DJI reference (synthetic GT.csv: values and misuse),
// and the whole chain on real data: transfer-align-ansfl --calibration_out, convert, smooth
// --calibration --init_from with 5 s outages every 15 s against the DJI solution
// (docs/gnss-ins-results.md, "ANSFL"); a mounting given twice is refused.
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "core/calibration_file.h"
#include "core/units.h"
#include "tests/apps/cli_util.h"
#include "tests/test_data.h"

namespace navtwin {
namespace apps_ansfl_cli_test {

using namespace cli_test;  // RunResult, Navtwin, ReadAll, MakeTempDir, Exists, JsonNumberAfter

/// A Horizontal-style GT.csv (no GTExtended.csv beside it), 10 Hz: 2 m/s north.
void WriteGt(const std::string& path, int rows) {
  std::ofstream out(path);
  out << "time,distance(meters),speed(m/s), compass_heading(degrees), pitch(degrees), "
         "roll(degrees),height_above_takeoff(meters),North,East,Down\n";
  for (int k = 0; k < rows; ++k) out << 0.1 * k << ",0,0,0,0,0,0," << 0.2 * k << ",0,0\n";
}

TEST(AnsflCli, ConvertWritesTheReferenceAsGnssWithTheStatedSigma) {
  const std::string dir = MakeTempDir("ansfl");
  WriteGt(dir + "/GT.csv", 5);
  // Defaults for the ANSFL reference (core/io/ansfl.h): 0.1 m and 0.15 m/s on every axis.
  const RunResult r = Navtwin("convert --in " + dir + "/GT.csv --what gnss --out " + dir + "/g.txt --format=json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(JsonNumberAfter(r.out, "{", "samples"), 5);
  EXPECT_NE(r.err.find("sigma 0.1 m and 0.15 m/s"), std::string::npos) << r.err;
  const std::string gnss = ReadAll(dir + "/g.txt");
  const std::string first = gnss.substr(0, gnss.find('\n'));
  EXPECT_NE(first.find(" 0.1 0.1 0.1 "), std::string::npos) << first;
  EXPECT_EQ(first.substr(first.size() - 14), "0.15 0.15 0.15") << first;
  // Stated sigmas replace them; the file is a GNSS input `info` recognises.
  ASSERT_EQ(Navtwin("convert --in " + dir + "/GT.csv --what gnss --pos_sigma_m 0.02 --vel_sigma_mps 0.05 --out " +
                    dir + "/s.txt").exit_code, 0);
  const std::string stated = ReadAll(dir + "/s.txt");
  EXPECT_NE(stated.find(" 0.02 0.02 0.02 "), std::string::npos) << stated;
  EXPECT_NE(Navtwin("info " + dir + "/s.txt --format=json").out.find("kfgins-gnss"), std::string::npos);
}

TEST(AnsflCli, ConvertMisuseIsACommandLineErrorAndWritesNothing) {
  const std::string dir = MakeTempDir("ansfl");
  WriteGt(dir + "/GT.csv", 5);
  const std::string convert = "convert --in " + dir + "/GT.csv --what gnss --out " + dir + "/out.txt ";
  // (--pos_sigma_m nan is the flags' "not given": FlagGiven cannot tell them apart.)
  for (const std::string& bad : {std::string("--pos_sigma_m 0"), std::string("--vel_sigma_mps -0.1"),
                                 std::string("--vel_sigma_mps inf")}) {
    const RunResult r = Navtwin(convert + bad);
    EXPECT_EQ(r.exit_code, 2) << bad;
    EXPECT_NE(r.err.find("must be > 0"), std::string::npos) << r.err;
  }
  // The sigma flags belong to fixes made from a navigation file.
  EXPECT_EQ(Navtwin("convert --in " + dir + "/GT.csv --what nav --pos_sigma_m 0.1 --out " + dir + "/out.txt").exit_code, 2);
  // A navigation file other than the ANSFL reference has no documented default sigma.
  ASSERT_EQ(Navtwin("convert --in " + dir + "/GT.csv --what nav --out " + dir + "/gt.nav").exit_code, 0);
  const RunResult nav = Navtwin("convert --in " + dir + "/gt.nav --what gnss --out " + dir + "/out.txt");
  EXPECT_EQ(nav.exit_code, 2);
  EXPECT_NE(nav.err.find("--pos_sigma_m is required"), std::string::npos) << nav.err;
  EXPECT_FALSE(Exists(dir + "/out.txt"));
}

// The documented chain on Horizontal/path_4 (the data set's own test path), DOT 1.
// Tolerances, from the measured run (docs/gnss-ins-results.md, "ANSFL"):
//  - mounting: the Horizontal paths' mean for DOT 1 (179.75 / -1.43 / -0.97 deg) within
//    0.5 deg, a little more than the 27 paths' max - min (0.36 / 0.09 / 0.16 deg); a
//    mounting taken as identity or in degrees would miss by 180 deg or be refused;
//  - time offset: this session's (paths 2-7) -0.06 s within 0.02 s (2.4 DOT samples);
//  - batch outage drift: measured 0.46 m horizontal and 0.10 m vertical RMS over the two
//    outages; bounds 1.0 m and 0.3 m (twice and three times), far below the filter's 4.3 m
//    and 2.9 m, and below what a wrong clock offset gives (the 0.06 s at 3-4.6 m/s is
//    0.2-0.3 m on every fix);
//  - batch RMS(err/sigma) inside the outages, horizontal position: measured 1.04 (N) and 0.36
//    (E); two outages of 50 strongly correlated epochs determine it only to a factor of
//    about 2, so the bounds [0.2, 3] catch a sigma off by an order of magnitude, not less.
TEST(AnsflCli, SmoothsADotWithTheCalibrationFromTransferAlignment) {
  const std::string data = testing::DataPath("ansfl-quadrotor");
  const std::string path = data + "/Horizontal/path_4";
  NAVTWIN_REQUIRE_DATA(path + "/IMU_1.csv");
  const std::string dir = MakeTempDir("ansfl");
  const RunResult align = Navtwin("transfer-align-ansfl --data " + data + " --path Horizontal/path_4 --dot 1 "
                                  "--method batch --calibration_out " + dir + "/cal.yaml");
  ASSERT_EQ(align.exit_code, 0) << align.err;
  const CalibrationFile cal = ReadCalibrationFile(dir + "/cal.yaml");
  ASSERT_TRUE(cal.installation && cal.imu);
  const Eigen::Vector3d rpy_deg = cal.installation->mounting_rpy_rad * kRadToDeg;
  EXPECT_NEAR(rpy_deg.x(), 179.75, 0.5);
  EXPECT_NEAR(rpy_deg.y(), -1.43, 0.5);
  EXPECT_NEAR(rpy_deg.z(), -0.97, 0.5);
  EXPECT_NEAR(cal.installation->time_offset_s, -0.06, 0.02);

  ASSERT_EQ(Navtwin("convert --in " + path + "/GT.csv --what gnss --out " + dir + "/gnss.txt").exit_code, 0);
  const std::string config = std::string(NAVTWIN_SOURCE_DIR) + "/data/configs/ansfl-dot.yaml";
  const std::string smooth = "smooth --imu " + path + "/IMU_1.csv --gnss " + dir + "/gnss.txt --calibration " + dir +
                             "/cal.yaml --init_from " + path + "/GT.csv --truth " + path +
                             "/GT.csv --outage_start_s 10 --outage_len_s 5 --outage_period_s 15";
  const RunResult run = Navtwin(smooth + " --config " + config + " --out " + dir + "/run --format=json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("smooth: IMU installation from " + dir + "/cal.yaml: mounting roll"), std::string::npos)
      << run.err;
  const std::size_t at = run.out.find("\"batch\":{");
  ASSERT_NE(at, std::string::npos);
  const std::string batch = run.out.substr(at);
  EXPECT_LT(JsonNumberAfter(batch, "\"errors\"", "outage_horizontal_rms_m"), 1.0);
  EXPECT_LT(JsonNumberAfter(batch, "\"errors\"", "outage_vertical_rms_m"), 0.3);
  const std::string consistency = batch.substr(batch.find("\"consistency\""));
  const std::string inside = consistency.substr(consistency.find("\"inside_outages\""));
  for (const char* axis : {"pos_n", "pos_e"}) {
    const double ratio = JsonNumberAfter(inside, "\"epochs\"", axis);
    EXPECT_GT(ratio, 0.2) << axis;
    EXPECT_LT(ratio, 3.0) << axis;
  }

  // The mounting from two places (configuration and calibration file) is refused.
  std::string twice = ReadAll(config);
  twice.replace(twice.find("imu_time_offset_s: 0"), 20, "imu_time_offset_s: 0.1");
  std::ofstream(dir + "/twice.yaml") << twice;
  const RunResult refused = Navtwin(smooth + " --config " + dir + "/twice.yaml --out " + dir + "/twice");
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find(dir + "/cal.yaml"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("installation"), std::string::npos) << refused.err;
  EXPECT_FALSE(Exists(dir + "/twice/summary.json"));
}

}  // namespace apps_ansfl_cli_test
}  // namespace navtwin
