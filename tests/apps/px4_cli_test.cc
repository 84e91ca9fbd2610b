// End to end on PX4 logs: `navtwin convert --what imu|gnss|mag|baro|px4_estimate` onto GPS
// time, a log without GPS kept in boot time with a message, misuse, and `navtwin smooth`
// with data/configs/px4-multicopter.yaml on ekf_failure.ulg (docs/gnss-ins-results.md).
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/apps/cli_util.h"
#include "tests/test_data.h"

namespace navtwin {
namespace apps_px4_cli_test {

using namespace cli_test;  // RunResult, Navtwin, ReadAll, MakeTempDir, Exists, JsonNumberAfter

std::string EkfFailure() { return testing::DataPath("px4-ulog/ekf_failure.ulg"); }

struct Stream {
  const char* what;
  const char* file;
  double count;  // measured once; the file does not change
};
const Stream kStreams[] = {{"imu", "imu.txt", 15843},
                           {"gnss", "gnss.txt", 397},
                           {"mag", "mag.csv", 159},
                           {"baro", "baro.csv", 399},
                           {"px4_estimate", "px4_estimate.nav", 398}};

/// Converts every stream of ekf_failure.ulg into `dir`; false (with failures) on error.
bool ConvertAll(const std::string& dir) {
  for (const Stream& s : kStreams) {
    const RunResult r = Navtwin("convert --in " + EkfFailure() + " --what " + s.what + " --out " + dir + "/" +
                                s.file + " --format=json");
    EXPECT_EQ(r.exit_code, 0) << s.what << ": " << r.err;
    if (r.exit_code != 0) return false;
    EXPECT_EQ(JsonNumberAfter(r.out, "{", "samples"), s.count) << s.what;
    EXPECT_EQ(JsonNumberAfter(r.out, "{", "gps_week"), 2353) << s.what;
    EXPECT_NE(r.out.find("\"time_scale\":\"gps\""), std::string::npos) << r.out;
    EXPECT_NE(r.err.find("boot time -> GPS week 2353"), std::string::npos) << r.err;
  }
  return true;
}

TEST(Px4Cli, ConvertsEveryStreamOntoGpsTime) {
  NAVTWIN_REQUIRE_DATA(EkfFailure());
  const std::string dir = MakeTempDir("px4");
  ASSERT_TRUE(ConvertAll(dir));
  // CSV outputs say their time scale in a note the readers skip.
  for (const char* csv : {"mag.csv", "baro.csv"}) {
    EXPECT_EQ(ReadAll(dir + "/" + csv).rfind("# t_s: GPS seconds of week 2353", 0), 0u) << csv;
  }
  // The estimate is a KF-GINS navigation file with the week in its first column.
  EXPECT_EQ(ReadAll(dir + "/px4_estimate.nav").rfind("2353 136607.", 0), 0u);
  const RunResult info = Navtwin("info " + dir + "/px4_estimate.nav --format=json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("kfgins-nav"), std::string::npos) << info.out;
  for (const char* kind : {"csv-mag", "csv-baro"}) {
    const std::string file = dir + (std::string(kind) == "csv-mag" ? "/mag.csv" : "/baro.csv");
    const RunResult r = Navtwin("info " + file + " --format=json");
    EXPECT_NE(r.out.find(kind), std::string::npos) << r.out << r.err;
  }
}

TEST(Px4Cli, LogWithoutGpsKeepsBootTimeAndSaysSo) {
  const std::string path = testing::DataPath("px4-ulog/sample.ulg");
  NAVTWIN_REQUIRE_DATA(path);
  const std::string dir = MakeTempDir("px4");
  const RunResult r = Navtwin("convert --in " + path + " --what mag --out " + dir + "/mag.csv --format=json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("times stay seconds since boot, GPS week unknown"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("\"time_scale\":\"boot\""), std::string::npos) << r.out;
  EXPECT_EQ(ReadAll(dir + "/mag.csv").rfind("# t_s: seconds since boot", 0), 0u);
}

TEST(Px4Cli, MisuseAndWrongKindsLeaveNoOutput) {
  NAVTWIN_REQUIRE_DATA(EkfFailure());
  const std::string dir = MakeTempDir("px4");
  const RunResult to_kfgins = Navtwin("convert --in " + EkfFailure() + " --what mag --to kfgins --out " + dir + "/m");
  EXPECT_EQ(to_kfgins.exit_code, 2);
  EXPECT_NE(to_kfgins.err.find("csv only"), std::string::npos) << to_kfgins.err;
  EXPECT_EQ(Navtwin("convert --in " + EkfFailure() + " --what attitude --out " + dir + "/a").exit_code, 2);
  EXPECT_FALSE(Exists(dir + "/m") || Exists(dir + "/a"));
  // PX4's estimate from a file that is not a ULog: bad input (exit 1) naming the file.
  ASSERT_EQ(Navtwin("convert --in " + EkfFailure() + " --out " + dir + "/imu.txt").exit_code, 0);
  const RunResult wrong = Navtwin("convert --in " + dir + "/imu.txt --what px4_estimate --out " + dir + "/e.nav");
  EXPECT_EQ(wrong.exit_code, 1);
  EXPECT_NE(wrong.err.find(dir + "/imu.txt"), std::string::npos) << wrong.err;
  EXPECT_NE(wrong.err.find("px4_estimate"), std::string::npos) << wrong.err;
  EXPECT_FALSE(Exists(dir + "/e.nav"));
}

// The documented run (docs/gnss-ins-results.md, "Real data: PX4 ekf_failure.ulg"): every
// method follows the GNSS within its eph/epv class and the run prints the ULog's time scale.
// Bounds: about twice the measured RMS (filter 0.65 m / 0.83 m / 0.94 m/s, RTS and batch
// 0.50-0.55 m / 0.47-0.49 m/s), far below the 309 m of a diverging RTS (data-sheet noise).
TEST(Px4Cli, SmoothsEkfFailureWithTheMulticopterConfiguration) {
  NAVTWIN_REQUIRE_DATA(EkfFailure());
  const std::string dir = MakeTempDir("px4");
  ASSERT_TRUE(ConvertAll(dir));
  std::ofstream(dir + "/px4-multicopter.yaml")
      << ReadAll(std::string(NAVTWIN_SOURCE_DIR) + "/data/configs/px4-multicopter.yaml");
  const std::string files = " --imu " + dir + "/imu.txt --gnss " + dir + "/gnss.txt --mag " + dir + "/mag.csv --baro " +
                            dir + "/baro.csv --config " + dir + "/px4-multicopter.yaml";
  const RunResult run = Navtwin("smooth" + files + " --truth " + dir + "/gnss.txt --out " + dir + "/run --format=json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* method : {"\"filter\":{", "\"rts\":{", "\"batch\":{"}) {
    const std::size_t at = run.out.find(method);
    ASSERT_NE(at, std::string::npos) << method;
    const std::string m = run.out.substr(at);
    EXPECT_LT(JsonNumberAfter(m, "\"horizontal_m\"", "rms"), 1.5) << method;
    EXPECT_LT(JsonNumberAfter(m, "\"vertical_m\"", "rms"), 1.7) << method;
    EXPECT_LT(JsonNumberAfter(m, "\"velocity_rms_mps\"", "velocity_rms_mps"), 2.0) << method;
  }
  // Converted files on GPS time carry no ULog note; the ULog given directly does.
  EXPECT_EQ(run.err.find("boot time -> GPS"), std::string::npos);
  const RunResult direct = Navtwin("navigate --imu " + EkfFailure() + " --gnss " + EkfFailure() + " --mag " +
                                   EkfFailure() + " --baro " + EkfFailure() + " --config " + dir +
                                   "/px4-multicopter.yaml --out " + dir + "/direct");
  ASSERT_EQ(direct.exit_code, 0) << direct.err;
  EXPECT_NE(direct.err.find("navigate: " + EkfFailure() + ": boot time -> GPS week 2353"), std::string::npos)
      << direct.err;
}

}  // namespace apps_px4_cli_test
}  // namespace navtwin
