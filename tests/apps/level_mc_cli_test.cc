// End-to-end checks of `navtwin level-mc`: the JSON shape of issue 5, the text table, the
// per-run errors CSV, and usage errors (exit 2 with the usage line).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/apps/cli_util.h"

namespace navtwin {
namespace apps_level_mc_cli_test {

using namespace cli_test;  // RunResult, Navtwin, ReadAll, MakeTempDir, Exists, JsonNumberAfter

const char* const kMethods[] = {"plain_mean", "period_average", "filter", "batch"};

TEST(LevelMcCliTest, JsonHasTheIssuesShape) {
  const RunResult r = Navtwin("level-mc --runs 40 --seed 3 --format=json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("{\"runs\":40,\"run_time_s\":", 0), 0u) << r.out;
  EXPECT_NE(r.out.find("\"methods\":{\"plain_mean\":{"), std::string::npos) << r.out;
  for (const char* m : kMethods) {
    const std::string anchor = "\"" + std::string(m) + "\":{";
    for (const char* key : {"pitch_rms_deg", "pitch_max_deg", "roll_rms_deg", "roll_max_deg"}) {
      const double v = JsonNumberAfter(r.out, anchor, key);
      EXPECT_TRUE(std::isfinite(v)) << m << " " << key << "\n" << r.out;
      EXPECT_GE(v, 0.0) << m << " " << key;
    }
  }
  // The largest error is at least the RMS.
  EXPECT_GE(JsonNumberAfter(r.out, "\"plain_mean\":{", "pitch_max_deg"),
            JsonNumberAfter(r.out, "\"plain_mean\":{", "pitch_rms_deg"));
}

TEST(LevelMcCliTest, TextTableListsEveryMethod) {
  const RunResult r = Navtwin("level-mc --runs 20 --vib_axes x,y,z --vib_tones 2 --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("vibration on xyz"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("2 tones"), std::string::npos) << r.out;
  for (const char* m : kMethods) EXPECT_NE(r.out.find(std::string("\n") + m + " "), std::string::npos) << m;
  EXPECT_NE(r.out.find("run time"), std::string::npos);
}

TEST(LevelMcCliTest, ErrorsCsvHasOneRowPerRunMatchingTheJson) {
  const std::string dir = MakeTempDir("level_mc");
  const std::string csv = dir + "/errors.csv";
  const RunResult r = Navtwin("level-mc --runs 25 --seed 9 --format=json --errors_csv " + csv);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::istringstream in(ReadAll(csv));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line,
            "run,plain_mean_pitch_deg,plain_mean_roll_deg,period_average_pitch_deg,period_average_roll_deg,"
            "filter_pitch_deg,filter_roll_deg,batch_pitch_deg,batch_roll_deg");
  int rows = 0;
  double sum2 = 0.0;
  while (std::getline(in, line)) {
    double run = 0.0, plain_pitch = 0.0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf", &run, &plain_pitch), 2) << line;
    EXPECT_EQ(run, rows);
    sum2 += plain_pitch * plain_pitch;
    ++rows;
  }
  EXPECT_EQ(rows, 25);
  // The CSV holds the exact doubles (shortest round-trip form); the JSON's RMS is computed
  // from the same values in the same order, printed with ~15 significant digits.
  EXPECT_NEAR(std::sqrt(sum2 / rows), JsonNumberAfter(r.out, "\"plain_mean\":{", "pitch_rms_deg"), 1e-9);
  std::remove(csv.c_str());
  ::rmdir(dir.c_str());
}

// --out DIR: the same errors.csv as --errors_csv, and summary.json the --format=json object
// led by the command's name; --report adds the page (and needs --out).
TEST(LevelMcCliTest, OutWritesTheRunFolder) {
  const std::string dir = MakeTempDir("level_mc_run") + "/run";
  const RunResult r = Navtwin("level-mc --runs 25 --seed 9 --format=json --out " + dir + " --report");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // --report: the page with its two histograms (pitch, roll).
  EXPECT_EQ(Occurrences(ReadAll(dir + "/report.html"), "data:image/svg+xml;base64,"), 2u);
  EXPECT_EQ(Navtwin("level-mc --runs 5 --report").exit_code, 2);
  const std::string summary = ReadAll(dir + "/summary.json");
  EXPECT_EQ(summary, "{\"command\":\"level-mc\"," + r.out.substr(1)) << summary;
  std::istringstream in(ReadAll(dir + "/errors.csv"));
  std::string line;
  int rows = -1;
  while (std::getline(in, line)) ++rows;
  EXPECT_EQ(rows, 25);
}

TEST(LevelMcCliTest, BadFlagsAreUsageErrors) {
  for (const std::string flags :
       {"--runs 0", "--rate_hz 0", "--window_s 0.001", "--vib_freq_hz 24:22", "--vib_freq_hz 0:5",
        "--vib_freq_hz 290:310", "--vib_freq_hz 22-24", "--noise_mg -1", "--vib_axes xw", "--vib_axes ,",
        "--vib_tones 0", "--vib_tones 13", "--threads -1", "--true_pitch_deg 90", "extra_argument"}) {
    const RunResult r = Navtwin("level-mc --runs 5 " + flags);
    EXPECT_EQ(r.exit_code, 2) << flags << "\n" << r.err;
    EXPECT_NE(r.err.find("usage: navtwin level-mc"), std::string::npos) << flags << "\n" << r.err;
    EXPECT_TRUE(r.out.empty()) << flags;
  }
}

TEST(LevelMcCliTest, FailedRunLeavesNoCsv) {
  const std::string dir = MakeTempDir("level_mc_bad");
  const std::string csv = dir + "/errors.csv";
  const RunResult r = Navtwin("level-mc --runs 0 --errors_csv " + csv);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(Exists(csv));
  ::rmdir(dir.c_str());
}

}  // namespace apps_level_mc_cli_test
}  // namespace navtwin
