// End-to-end checks of `navtwin inflight-align` and `navtwin inflight-mc` (issue 7): usage
// errors (exit 2 with the usage line), the JSON shape of the issue on the simulated preset,
// the file mode with a good and a malformed GNSS file (message with file and line, no
// output file), and a two-run Monte Carlo. Few runs: each simulates the preset.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/apps/cli_util.h"

namespace navtwin {
namespace apps_inflight_cli_test {

using namespace cli_test;  // RunResult, Navtwin, ReadAll, MakeTempDir, Exists, JsonNumberAfter

const char* const kPreset = "--scenario inflight-mach07-south";

TEST(InflightCliTest, MisuseIsAUsageError) {
  // Each fails before any simulation or reading.
  for (const std::string& args :
       {std::string("inflight-align ") + kPreset,                          // no --method
        std::string("inflight-align --method ekf ") + kPreset,             // unknown method
        std::string("inflight-align --method kalman --imu a.txt ") + kPreset,  // --scenario with --imu
        std::string("inflight-align --method kalman --imu a.txt --gnss b.txt"),  // no --init_from
        std::string("inflight-align --method kalman --imu a.txt --gnss b.txt --init_from c.nav --seed 3"),
        std::string("inflight-align --method kalman --outlier_fraction 0.01 --imu a --gnss b --init_from c"),
        std::string("inflight-align --method kalman --outlier_m 100 ") + kPreset,  // size without fraction
        std::string("inflight-align --method batch extra ") + kPreset,
        std::string("inflight-mc --runs 0"), std::string("inflight-mc --runs 2 --threads -1"),
        std::string("inflight-mc --runs 2 --imu a.txt")}) {
    const RunResult r = Navtwin(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("usage: navtwin inflight-"), std::string::npos) << args << "\n" << r.err;
    EXPECT_TRUE(r.out.empty()) << args;
  }
}

TEST(InflightCliTest, ScenarioKalmanJsonHasTheIssuesKeys) {
  const RunResult r = Navtwin(std::string("inflight-align ") + kPreset + " --seed 1 --method kalman --format=json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("{\"method\":\"kalman\",\"heading_error_arcmin_at_km\":{\"10\":", 0), 0u) << r.out;
  for (const char* km : {"10", "20", "50", "100"}) {
    EXPECT_TRUE(std::isfinite(JsonNumberAfter(r.out, "\"heading_error_arcmin_at_km\":", km))) << km << "\n" << r.out;
  }
  for (const char* key : {"final_heading_error_arcmin", "heading_sigma_arcmin", "run_time_s"}) {
    EXPECT_TRUE(std::isfinite(JsonNumberAfter(r.out, "{", key))) << key << "\n" << r.out;
  }
  EXPECT_GT(JsonNumberAfter(r.out, "{", "heading_sigma_arcmin"), 0.0);
  EXPECT_NE(r.err.find("inflight-align: running kalman"), std::string::npos) << r.err;  // progress on stderr
}

/// The preset's files, simulated once for the file-mode tests.
const std::string& SimulatedDir() {
  static const std::string dir = [] {
    const std::string d = MakeTempDir("inflight_files");
    const RunResult r = Navtwin(std::string("simulate ") + kPreset + " --seed 1 --out " + d);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return d;
  }();
  return dir;
}

TEST(InflightCliTest, FilesWithTruthWriteTheTrack) {
  const std::string d = SimulatedDir();
  const std::string csv = d + "/track.csv";
  const RunResult r = Navtwin("inflight-align --imu " + d + "/imu.txt --gnss " + d + "/gnss.txt --baro " + d +
                              "/baro.csv --init_from " + d + "/init.nav --truth " + d +
                              "/truth.nav --method kalman --track_csv " + csv);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("method kalman"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("final"), std::string::npos) << r.out;
  std::istringstream in(ReadAll(csv));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t_s,path_length_km,yaw_deg,sigma_arcmin,error_arcmin");
  int rows = 0;
  while (std::getline(in, line)) ++rows;
  EXPECT_GT(rows, 500);  // one per 1 Hz fix of the 545 s flight
  std::remove(csv.c_str());
}

// --out DIR: summary.json with every method, and each method's track (the same rows as
// --track_csv writes); --report adds the page.
TEST(InflightCliTest, OutWritesTheRunFolder) {
  const std::string d = SimulatedDir();
  const std::string out = MakeTempDir("inflight_run") + "/run";
  const RunResult r = Navtwin("inflight-align --imu " + d + "/imu.txt --gnss " + d + "/gnss.txt --baro " + d +
                              "/baro.csv --init_from " + d + "/init.nav --truth " + d +
                              "/truth.nav --method all --out " + out + " --report");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // --report: the page with its three figures (heading error against distance, over the
  // second half, and sigma against distance).
  EXPECT_EQ(Occurrences(ReadAll(out + "/report.html"), "data:image/svg+xml;base64,"), 3u);
  const std::string summary = ReadAll(out + "/summary.json");
  EXPECT_EQ(summary.rfind("{\"command\":\"inflight-align\",\"methods\":{\"distance\":{", 0), 0u) << summary;
  for (const char* method : {"distance", "kalman", "batch"}) {
    EXPECT_NE(summary.find(std::string("\"") + method + "\":{"), std::string::npos) << method;
    std::istringstream in(ReadAll(out + "/" + method + "/track.csv"));
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "t_s,path_length_km,yaw_deg,sigma_arcmin,error_arcmin") << method;
    int rows = 0;
    while (std::getline(in, line)) ++rows;
    EXPECT_GT(rows, 500) << method;  // one per 1 Hz fix of the 545 s flight
  }
}

TEST(InflightCliTest, MalformedGnssNamesFileAndLineAndWritesNothing) {
  const std::string d = SimulatedDir();
  // Line 101 cut short (a truncated record in the middle of the file).
  std::istringstream in(ReadAll(d + "/gnss.txt"));
  const std::string bad = d + "/gnss_bad.txt";
  {
    std::ofstream out(bad);
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) out << (n == 101 ? line.substr(0, 20) : line) << "\n";
  }
  const std::string csv = d + "/bad_track.csv";
  const RunResult r = Navtwin("inflight-align --imu " + d + "/imu.txt --gnss " + bad + " --init_from " + d +
                              "/init.nav --method batch --track_csv " + csv);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("gnss_bad.txt:line 101"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_FALSE(Exists(csv));
  std::remove(bad.c_str());
}

TEST(InflightCliTest, MonteCarloOfTwoRuns) {
  const std::string dir = MakeTempDir("inflight_mc");
  const std::string csv = dir + "/errors.csv";
  const RunResult r = Navtwin("inflight-mc --runs 2 --seed 5 --threads 2 --format=json --errors_csv " + csv);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("{\"scenario\":\"inflight-mach07-south\",\"runs\":2,\"seed\":5,", 0), 0u) << r.out;
  for (const char* m : {"distance", "kalman", "batch"}) {
    const std::string anchor = "\"" + std::string(m) + "\":{\"final_heading_error_arcmin\":";
    EXPECT_TRUE(std::isfinite(JsonNumberAfter(r.out, anchor, "mean"))) << m << "\n" << r.out;
    EXPECT_GE(JsonNumberAfter(r.out, anchor, "rms"), 0.0) << m;
    EXPECT_EQ(JsonNumberAfter(r.out, anchor, "runs"), 2.0) << m;
    EXPECT_TRUE(std::isfinite(JsonNumberAfter(r.out, "\"" + std::string(m) + "\":{", "mean_heading_sigma_arcmin")));
  }
  // One row per run and method, seeds seed + run.
  std::istringstream in(ReadAll(csv));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("run,seed,method,error_10km_arcmin,", 0), 0u) << line;
  std::vector<std::string> rows;
  while (std::getline(in, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 6u);
  EXPECT_EQ(rows[0].rfind("0,5,distance,", 0), 0u) << rows[0];
  EXPECT_EQ(rows[5].rfind("1,6,batch,", 0), 0u) << rows[5];
  std::remove(csv.c_str());
  ::rmdir(dir.c_str());
}

}  // namespace apps_inflight_cli_test
}  // namespace navtwin
