// End-to-end checks of `navtwin transfer-align` (issue 6): usage errors (exit 2 with the
// usage line, nothing on stdout), the JSON of the issue on a shortened scenario given as a
// YAML file (--scenario accepts a path; the preset itself runs in the evidence, not here),
// the file mode with and without truth, and a malformed master file (exit 1, message with
// the file and the line, nothing on stdout).
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/apps/cli_util.h"

namespace navtwin {
namespace apps_transfer_cli_test {

using namespace cli_test;  // RunResult, Navtwin, ReadAll, MakeTempDir, Exists, JsonNumberAfter

/// The preset's first 12 s (cruise 2 s, wing rock 10 s): the same slave IMU, master and
/// init errors, short enough to run every method in about a second.
constexpr const char* kShortScenario = R"(name: transfer-short
start: {lat_deg: 36.0, lon_deg: 127.5, h_m: 3000}
trajectory:
  initial: {speed_mps: 200, heading_deg: 0}
  segments:
    - {kind: cruise, duration_s: 2}
    - {kind: wing_rock, duration_s: 10, roll_amplitude_deg: 30, roll_frequency_hz: 0.5, pitch_amplitude_deg: 5, pitch_frequency_hz: 0.25, yaw_amplitude_deg: 5, yaw_frequency_hz: 0.25}
imu:
  rate_hz: 100
  mounting_deg: [0.5, -0.3, 0.8]
  errors:
    gyro: {bias_deg_h: 1.0, arw_deg_sqrt_h: 0.05, scale_factor_ppm: 100, misalignment_arcsec: 20}
    accel: {bias_ug: 200, vrw_m_s_sqrt_h: 0.05, scale_factor_ppm: 100, misalignment_arcsec: 20}
master:
  rate_hz: 50
  transfer_delay_s: 0.3
  attitude_error_sigma_mrad: 0.05
  velocity_noise_mps: 0.01
init_errors: {velocity_ned_mps: [0.5, -0.5, 0.2], attitude_deg: [0.5, -0.5, 1.0]}
)";

/// A folder with short.yaml (the scenario), settle.yaml (a configuration scoring after 4 s
/// instead of 20 s) and the scenario's simulated files (seed 1); made once.
const std::string& Folder() {
  static const std::string dir = [] {
    const std::string d = MakeTempDir("transfer_cli");
    std::ofstream(d + "/short.yaml") << kShortScenario;
    std::ofstream(d + "/settle.yaml") << "settle_s: 4\n";
    const RunResult r = Navtwin("simulate --scenario " + d + "/short.yaml --seed 1 --out " + d);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return d;
  }();
  return dir;
}

TEST(TransferCliTest, MisuseIsAUsageError) {
  const std::string s = "--scenario transfer-alignment-high-maneuver";
  const std::string files = "--master m.nav --slave_imu imu.txt --init_from init.nav";
  // Each fails before any simulation or reading.
  const std::vector<std::string> misuse = {
           "transfer-align " + s,                                   // no --method
           "transfer-align --method order3 " + s,                   // unknown method
           "transfer-align --method order2 --master m.nav " + s,    // --scenario with a file
           "transfer-align --method order2 --delay_s -0.1 " + s,    // negative delay
           std::string("transfer-align --method order2 --master m.nav --slave_imu imu.txt"),  // no --init_from
           std::string("transfer-align --method order2 --slave_imu imu.txt --init_from i.nav"),  // no --master
           "transfer-align --method order2 --seed 3 " + files,      // --seed without --scenario
           "transfer-align --method order2 --delay_s 0.2 " + files,  // --delay_s without --scenario
           "transfer-align --method batch extra " + s,              // positional argument
           "transfer-align --method batch --imu a.txt " + s,        // a flag of another command
  };
  for (const std::string& args : misuse) {
    const RunResult r = Navtwin(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("usage: navtwin transfer-align"), std::string::npos) << args << "\n" << r.err;
    EXPECT_TRUE(r.out.empty()) << args;
  }
}

TEST(TransferCliTest, ScenarioJsonHasTheIssuesKeys) {
  const std::string d = Folder();
  const RunResult r = Navtwin("transfer-align --scenario " + d + "/short.yaml --seed 1 --delay_s 0.2 --config " + d +
                              "/settle.yaml --method all --format=json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // An array of the four methods' objects, each starting with the issue's keys in order.
  EXPECT_EQ(r.out.rfind("[{\"method\":\"order1\",\"roll_rms_mrad\":", 0), 0u) << r.out;
  for (const char* method : {"order1", "order2", "history", "batch"}) {
    const std::string anchor = std::string("{\"method\":\"") + method + "\"";
    ASSERT_NE(r.out.find(anchor), std::string::npos) << method << "\n" << r.out;
    for (const char* key : {"roll_rms_mrad", "pitch_rms_mrad", "heading_rms_mrad", "roll_max_mrad", "pitch_max_mrad",
                            "heading_max_mrad", "delay_est_s", "delay_sigma_s", "run_time_s"}) {
      EXPECT_TRUE(std::isfinite(JsonNumberAfter(r.out, anchor, key))) << method << " " << key << "\n" << r.out;
    }
    // The override reached the simulated master.
    EXPECT_EQ(JsonNumberAfter(r.out, anchor, "delay_true_s"), 0.2) << method;
    EXPECT_NE(r.out.find("\"misalignment_deg\":[", r.out.find(anchor)), std::string::npos) << method;
    EXPECT_NE(r.err.find(std::string("transfer-align: running ") + method), std::string::npos) << r.err;  // progress
  }
  EXPECT_NE(r.err.find("transfer delay 0.2 s"), std::string::npos) << r.err;
}

/// Rows of a CSV file (the header excluded) and its header.
std::size_t DataRows(const std::string& text, std::string* header) {
  *header = text.substr(0, text.find('\n'));
  std::size_t rows = 0;
  for (char c : text) rows += c == '\n' ? 1 : 0;
  return rows - 1;
}

// --out DIR: summary.json with the four methods, per method the estimates against time
// (a row per update for the filters, per state for the batch, whose one estimate every row
// repeats) and the attitude errors, with the same last estimate as summary.json; --report
// adds the page (and needs --out).
TEST(TransferCliTest, OutWritesTheRunFolder) {
  const std::string d = Folder();
  const std::string out = MakeTempDir("transfer_run") + "/run";
  const RunResult r = Navtwin("transfer-align --scenario " + d + "/short.yaml --seed 1 --config " + d +
                              "/settle.yaml --method all --format=json --out " + out + " --report");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // --report: the page of the folder, its three figures (misalignment, delay, attitude
  // errors) embedded.
  EXPECT_EQ(Occurrences(ReadAll(out + "/report.html"), "data:image/svg+xml;base64,"), 3u);
  const RunResult no_out = Navtwin("transfer-align --scenario " + d + "/short.yaml --method order1 --report");
  EXPECT_EQ(no_out.exit_code, 2) << no_out.err;
  const std::string summary = ReadAll(out + "/summary.json");
  EXPECT_EQ(summary.rfind("{\"command\":\"transfer-align\",\"methods\":{\"order1\":{\"method\":\"order1\"", 0), 0u)
      << summary;
  for (const char* method : {"order1", "order2", "history", "batch"}) {
    std::string header;
    const std::string estimates = ReadAll(out + "/" + method + "/estimates.csv");
    EXPECT_GT(DataRows(estimates, &header), 10u) << method;
    EXPECT_EQ(header,
              "t_s,mis_roll_deg,mis_pitch_deg,mis_yaw_deg,mis_roll_std_mrad,mis_pitch_std_mrad,mis_yaw_std_mrad,"
              "delay_s,delay_std_s");
    // The last row's delay is the reported estimate (printed to 17 digits in both).
    const std::string last = estimates.substr(estimates.rfind('\n', estimates.size() - 2) + 1);
    double t = 0, m[6], delay = NAN;
    ASSERT_EQ(std::sscanf(last.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &t, &m[0], &m[1], &m[2], &m[3], &m[4],
                          &m[5], &delay),
              8)
        << last;
    const std::string anchor = std::string("\"") + method + "\":{";
    EXPECT_NEAR(delay, JsonNumberAfter(summary, anchor, "delay_est_s"), 1e-9) << method;
    const std::string errors = ReadAll(out + "/" + method + "/attitude_errors.csv");
    EXPECT_GT(DataRows(errors, &header), 10u) << method;
    EXPECT_EQ(header, "t_s,roll_err_mrad,pitch_err_mrad,heading_err_mrad");
  }
}

TEST(TransferCliTest, FilesWithAndWithoutTruth) {
  const std::string d = Folder();
  const std::string files =
      "--master " + d + "/master.nav --slave_imu " + d + "/imu.txt --init_from " + d + "/init.nav --config " + d +
      "/settle.yaml --method order2";
  RunResult r = Navtwin("transfer-align " + files + " --truth " + d + "/truth.nav");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("method order2"), std::string::npos) << r.out;
  // Files carry no mounting: the body estimate is scored against the body truth.
  EXPECT_NE(r.out.find("body truth"), std::string::npos) << r.out;
  r = Navtwin("transfer-align " + files + " --format=json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"roll_rms_mrad\":null"), std::string::npos) << r.out;  // no truth
  EXPECT_TRUE(std::isfinite(JsonNumberAfter(r.out, "{", "delay_est_s"))) << r.out;
  EXPECT_NE(r.err.find("no --truth"), std::string::npos) << r.err;
}

TEST(TransferCliTest, MalformedMasterFileNamesFileAndLine) {
  const std::string d = Folder();
  // master.nav with its 5th line broken (a velocity that is not a number).
  std::istringstream in(ReadAll(d + "/master.nav"));
  const std::string bad = d + "/bad_master.nav";
  {
    std::ofstream out(bad);
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      if (n == 5) {
        std::istringstream fields(line);
        std::vector<std::string> f;
        for (std::string x; fields >> x;) f.push_back(x);
        ASSERT_GE(f.size(), 6u);
        f[5] = "fast";
        line.clear();
        for (const std::string& x : f) line += (line.empty() ? "" : " ") + x;
      }
      out << line << "\n";
    }
  }
  const RunResult r = Navtwin("transfer-align --master " + bad + " --slave_imu " + d + "/imu.txt --init_from " + d +
                              "/init.nav --method order2 --format=json");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(bad), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("line 5"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;  // no partial output
}

}  // namespace apps_transfer_cli_test
}  // namespace navtwin
