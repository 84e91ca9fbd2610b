// End-to-end checks of `navtwin navigate` and `navtwin smooth`: outputs and summary on a
// tiny hand-made record, the KF-GINS configuration taken unchanged, flag misuse, the bad
// input of issue 4 item 6 (each: non-zero exit, a message naming file and line or time and
// field, no output left), and the demo's accuracy (the seed-001 figures).
#include <dirent.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/apps/cli_util.h"
#include "tests/problems/gnss_ins/static_record.h"

#include "core/earth.h"

namespace navtwin {
namespace apps_navigate_cli_test {

using namespace cli_test;  // RunResult, Navtwin, ReadAll, MakeTempDir, Exists, JsonNumberAfter








// ---------------------------------------------------------------------------------------
// A tiny record: 20 s of a level, north-facing, static IMU at 100 Hz (gravity and Earth
// rate, no errors) and 1 Hz GNSS at its position.
using namespace static_record;  // kLatDeg, kImuSamples, ImuLine, GnssLine, ConfigYaml

struct Record {
  std::string dir, imu, gnss, config;
};

/// Writes the record; `imu_edit` / `gnss_edit` change single lines (1-based) or drop them.
Record WriteRecord(const std::string& tag, const std::string& config_extra = "",
                   int drop_imu_from = 0, int drop_imu_count = 0, int nan_imu_line = 0,
                   const std::vector<std::string>& gnss_lines = {}) {
  Record r;
  r.dir = MakeTempDir(tag);
  r.imu = r.dir + "/imu.txt";
  r.gnss = r.dir + "/gnss.txt";
  r.config = r.dir + "/navtwin.yaml";
  std::ofstream imu(r.imu);
  for (int k = 1; k <= kImuSamples; ++k) {
    if (k >= drop_imu_from && k < drop_imu_from + drop_imu_count) continue;
    if (k == nan_imu_line) {
      imu << k * 0.01 << " nan 0 0 0 0 -0.098\n";
      continue;
    }
    imu << ImuLine(k);
  }
  std::ofstream gnss(r.gnss);
  if (gnss_lines.empty()) {
    for (int t = 0; t <= 20; ++t) gnss << GnssLine(t);
  } else {
    for (const std::string& l : gnss_lines) gnss << l;
  }
  std::ofstream(r.config) << ConfigYaml() << config_extra;
  return r;
}

std::vector<std::string> GnssLines(int n) {
  std::vector<std::string> lines;
  for (int t = 0; t < n; ++t) lines.push_back(GnssLine(t));
  return lines;
}

std::string Args(const Record& r, const std::string& out) {
  return "--imu " + r.imu + " --gnss " + r.gnss + " --config " + r.config + " --out " + out;
}

TEST(NavigateCli, HelpAndMisuse) {
  const RunResult help = Navtwin("--help");
  EXPECT_NE(help.out.find("navigate"), std::string::npos);
  EXPECT_NE(help.out.find("smooth"), std::string::npos);
  const RunResult nav_help = Navtwin("navigate --help");
  EXPECT_EQ(nav_help.exit_code, 0);
  EXPECT_NE(nav_help.out.find("--kfgins_config"), std::string::npos);
  EXPECT_NE(nav_help.out.find("--outage_period_s"), std::string::npos);
  const RunResult no_config = Navtwin("navigate --imu a --gnss b --out c");
  EXPECT_EQ(no_config.exit_code, 2);
  EXPECT_NE(no_config.err.find("--config"), std::string::npos) << no_config.err;
  const RunResult both = Navtwin("navigate --imu a --gnss b --out c --config x --kfgins_config y");
  EXPECT_EQ(both.exit_code, 2);
  EXPECT_EQ(Navtwin("navigate --demo --out x").exit_code, 2);  // --demo is smooth's
  EXPECT_EQ(Navtwin("smooth --smoother=rts --config x --imu a --gnss b --out c").exit_code, 2);
  EXPECT_EQ(Navtwin("navigate --smoother=ukf --config x --imu a --gnss b --out c").exit_code, 2);
  const RunResult outage = Navtwin("navigate --config x --imu a --gnss b --out c --outage_len_s 5");
  EXPECT_EQ(outage.exit_code, 2);
  EXPECT_NE(outage.err.find("--outage_start_s"), std::string::npos) << outage.err;
}

TEST(NavigateCli, WritesTheSolutionAndSummary) {
  const Record r = WriteRecord("ok");
  const std::string out = r.dir + "/out";
  const RunResult run = Navtwin("navigate " + Args(r, out) + " --output_rate_hz 10 --truth " + r.gnss);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* f : {"nav.nav", "nav.csv", "std.csv", "imu_errors.csv", "summary.json"}) {
    EXPECT_TRUE(Exists(out + "/" + f)) << f;
  }
  // 10 Hz over (0, 20] s: the first IMU epoch, then 0.1 .. 20.0 s.
  std::ifstream nav(out + "/nav.csv");
  int lines = 0;
  for (std::string l; std::getline(nav, l);) ++lines;
  EXPECT_EQ(lines, 1 + 201);
  const std::string summary = ReadAll(out + "/summary.json");
  EXPECT_NE(summary.find("\"output_method\":\"filter\""), std::string::npos) << summary;
  EXPECT_EQ(JsonNumberAfter(summary, "\"gnss_position\"", "used"), 21.0) << summary;
  EXPECT_EQ(JsonNumberAfter(summary, "\"inputs\"", "imu_samples"), 2000.0);
  // Against the GNSS file itself (a GNSS reference: no attitude): the static solution
  // stays within the 1 m / 2 m GNSS noise-free positions to a few cm (0.2 m bound).
  EXPECT_NE(summary.find("\"reference\":\"gnss\""), std::string::npos);
  EXPECT_LT(JsonNumberAfter(summary, "\"all\"", "rms"), 0.2) << summary;
  EXPECT_NE(run.out.find("filter"), std::string::npos) << run.out;

  const std::string out_rts = r.dir + "/out_rts";
  const RunResult rts = Navtwin("navigate " + Args(r, out_rts) + " --smoother=rts --format=json");
  ASSERT_EQ(rts.exit_code, 0) << rts.err;
  EXPECT_NE(rts.out.find("\"output_method\":\"rts\""), std::string::npos) << rts.out;
  EXPECT_NE(rts.out.find("\"rts\":{"), std::string::npos) << rts.out;
  EXPECT_TRUE(Exists(out_rts + "/nav.nav"));
}

// Warnings go to stderr and summary.json with exit code 0; --strict makes them exit code 3,
// with the files written. Every other fix is 11 m north of the others with a stated 1 m
// sigma: the gate rejects them (about half of the fixes).
TEST(NavigateCli, WarningsAndStrict) {
  std::vector<std::string> jumping;
  for (int t = 0; t <= 20; ++t) jumping.push_back(GnssLine(t, kLatDeg + (t % 2 == 1 ? 1e-4 : 0.0)));
  const Record r = WriteRecord("strict", "", 0, 0, 0, jumping);
  const RunResult plain = Navtwin("navigate " + Args(r, r.dir + "/plain"));
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_NE(plain.err.find("navigate: warning: filter: gnss_position:"), std::string::npos) << plain.err;
  EXPECT_NE(plain.err.find("rejected by the chi-square gate"), std::string::npos) << plain.err;
  EXPECT_NE(plain.out.find("warnings ("), std::string::npos) << plain.out;
  EXPECT_NE(ReadAll(r.dir + "/plain/summary.json").find("\"warnings\":[\"filter: "), std::string::npos);
  const RunResult strict = Navtwin("navigate " + Args(r, r.dir + "/strict") + " --strict");
  EXPECT_EQ(strict.exit_code, 3) << strict.err;
  EXPECT_TRUE(Exists(r.dir + "/strict/nav.nav"));
  // Without a gate every fix is used: no rejection warning.
  const RunResult ungated = Navtwin("navigate " + Args(r, r.dir + "/ungated") + " --gate_probability 1");
  EXPECT_EQ(ungated.err.find("rejected by the chi-square gate"), std::string::npos) << ungated.err;
  const Record clean_record = WriteRecord("clean");
  const RunResult clean = Navtwin("navigate " + Args(clean_record, clean_record.dir + "/out") + " --strict");
  EXPECT_EQ(clean.exit_code, 0) << clean.err << clean.out;
  EXPECT_EQ(clean.err.find("warning"), std::string::npos) << clean.err;
  EXPECT_EQ(Navtwin("navigate " + Args(r, r.dir + "/bad") + " --gate_probability 0").exit_code, 2);
  EXPECT_EQ(Navtwin("navigate " + Args(r, r.dir + "/bad") + " --variance_components=false").exit_code, 2);
}

// The KF-GINS configuration names the files and the output folder; its units differ
// (deg/sqrt(h), mGal, hours).
TEST(NavigateCli, RunsAKfginsConfigurationUnchanged) {
  const Record r = WriteRecord("kfgins");
  const std::string kf = r.dir + "/kf-gins.yaml";
  std::ofstream(kf) << "imupath: \"" << r.imu << "\"\ngnsspath: \"" << r.gnss << "\"\noutputpath: \""
                    << r.dir << "/kf_out\"\nimudatalen: 7\nimudatarate: 100\nstarttime: 0\nendtime: -1\n"
                       "initpos: [30, 114, 20]\ninitvel: [0, 0, 0]\ninitatt: [0, 0, 0]\n"
                       "initgyrbias: [0, 0, 0]\ninitaccbias: [0, 0, 0]\ninitgyrscale: [0, 0, 0]\n"
                       "initaccscale: [0, 0, 0]\ninitposstd: [1, 1, 2]\ninitvelstd: [0.1, 0.1, 0.1]\n"
                       "initattstd: [0.5, 0.5, 2]\nimunoise:\n  arw: [0.2, 0.2, 0.2]\n  vrw: [0.1, 0.1, 0.1]\n"
                       "  gbstd: [10, 10, 10]\n  abstd: [1000, 1000, 1000]\n  gsstd: [1000, 1000, 1000]\n"
                       "  asstd: [1000, 1000, 1000]\n  corrtime: 1.0\nantlever: [0, 0, 0]\nodo: false\n";
  const RunResult run = Navtwin("navigate --kfgins_config " + kf);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("odo (line 27)"), std::string::npos) << run.err;
  EXPECT_TRUE(Exists(r.dir + "/kf_out/nav.nav"));
  // 21 states (KF-GINS estimates scale factors): the scale columns are written.
  EXPECT_NE(ReadAll(r.dir + "/kf_out/imu_errors.csv").find("sa_z_ppm"), std::string::npos);
}

// OB_GINS users bring their files unchanged: its YAML configuration, and its IMU text with
// the odometer speed as an 8th column (read as IMU + odometer; with isuseodo the NHC too).
TEST(NavigateCli, RunsAnObginsConfigurationWithItsOdometerColumn) {
  const Record r = WriteRecord("obgins");
  const std::string imu8 = r.dir + "/imu_odo.txt";
  {
    std::ofstream out(imu8);
    for (int k = 1; k <= kImuSamples; ++k) {
      std::string line = ImuLine(k);
      line.pop_back();
      out << line << " 0.0\n";  // standing: odometer speed 0
    }
  }
  const std::string ob = r.dir + "/ob_gins.yaml";
  std::ofstream(ob) << "imufile: \"" << imu8 << "\"\ngnssfile: \"" << r.gnss << "\"\noutputpath: \"" << r.dir
                    << "/ob_out\"\nwindows: 20\nstarttime: 0\nendtime: 0\ninitvel: [0, 0, 0]\ninitatt: [0, 0, 0]\n"
                       "initgb: [0, 0, 0]\ninitab: [0, 0, 0]\nimudatalen: 8\nimudatarate: 100\nisearth: true\n"
                       "antlever: [0, 0, 0]\nodolever: [0, 0, 0]\nbodyangle: [0, 0, 0]\n"
                       "odometer:\n    isuseodo: true\n    std: [0.05, 0.05, 0.05]\n    srw: 100\n"
                       "imumodel:\n    arw: 0.2\n    vrw: 0.1\n    gbstd: 10.0\n    abstd: 1000.0\n    corrtime: 1.0\n"
                       "isuseoutage: false\noutagetime: 0\noutagelen: 60\noutageperiod: 180\ngnssthreshold: 20.0\n";
  const RunResult run = Navtwin("navigate --obgins_config " + ob + " --format=json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("windows (line 4)"), std::string::npos) << run.err;  // listed as not used
  EXPECT_TRUE(Exists(r.dir + "/ob_out/nav.nav"));
  // The odometer column is used from the first fix on (19 s at 100 Hz, minus the start).
  const double odometer_used = JsonNumberAfter(run.out, "\"odometer\":", "used");
  EXPECT_GT(odometer_used, 1800.0) << run.out;
  // Standing still, the odometer's scale factor is not observable (d r / d s = v_x / sigma
  // = 0): it keeps its prior, OB_GINS' srw of 100 ppm, in the summary.
  EXPECT_NEAR(JsonNumberAfter(run.out, "\"odometer_scale\":", "std"), 100e-6, 1e-9) << run.out;
  EXPECT_NEAR(JsonNumberAfter(run.out, "\"odometer_scale\":", "value"), 0.0, 1e-12) << run.out;
  // A 7-column IMU file has no odometer column: named with file, line and field.
  const RunResult no_column = Navtwin("navigate --obgins_config " + ob + " --imu " + r.imu + " --out " + r.dir + "/o7");
  EXPECT_EQ(no_column.exit_code, 1);
  EXPECT_NE(no_column.err.find(r.imu), std::string::npos) << no_column.err;
  EXPECT_NE(no_column.err.find("odo"), std::string::npos) << no_column.err;
}

TEST(NavigateCli, VehicleFlagsRejectBadValues) {
  const Record r = WriteRecord("vehicle_flags");
  for (const std::string bad : {"--nhc_sigma_mps -1", "--vehicle_lever_arm_b_m 1,2",
                                "--vehicle_mounting_rpy_deg 0,0,x", "--vehicle_lever_arm_b_m 1,2,3,4"}) {
    const RunResult run = Navtwin("navigate " + Args(r, r.dir + "/out") + " --nhc " + bad);
    EXPECT_EQ(run.exit_code, 2) << bad << ": " << run.err;
  }
  const RunResult ok = Navtwin("navigate " + Args(r, r.dir + "/ok") + " --nhc --vehicle_lever_arm_b_m=-1.2,0,0.3");
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
}

/// Runs `navigate` on a bad record: exit 1, every part in the message, nothing in --out.
void ExpectBadInput(const Record& r, const std::vector<std::string>& parts) {
  const std::string out = r.dir + "/out";
  const RunResult run = Navtwin("navigate " + Args(r, out));
  EXPECT_EQ(run.exit_code, 1) << run.err;
  for (const std::string& p : parts) EXPECT_NE(run.err.find(p), std::string::npos) << run.err << " lacks " << p;
  EXPECT_TRUE(Entries(out).empty()) << "output left in " << out;
  EXPECT_FALSE(Exists(out)) << "the output folder made by the failed run is removed";
}

TEST(NavigateCli, BadInputZeroSigma) {
  const Record r = WriteRecord("sigma", "gnss:\n  default_pos_std_m: 0\n");
  ExpectBadInput(r, {r.config, "line 14", "gnss.default_pos_std_m", "> 0"});
}

TEST(NavigateCli, BadInputGnssOutOfOrder) {
  std::vector<std::string> lines = GnssLines(21);
  std::swap(lines[5], lines[6]);
  const Record r = WriteRecord("order", "", 0, 0, 0, lines);
  ExpectBadInput(r, {r.gnss, "line 7", "time"});
}

TEST(NavigateCli, BadInputGnssDuplicatedEpoch) {
  std::vector<std::string> lines = GnssLines(21);
  lines.insert(lines.begin() + 10, lines[9]);
  const Record r = WriteRecord("dup", "", 0, 0, 0, lines);
  ExpectBadInput(r, {r.gnss, "line 11", "time"});
}

TEST(NavigateCli, BadInputImuGapTooLong) {
  // Samples 1001..1030 missing: a 0.31 s interval from t = 10.00 to 10.31 s.
  const Record r = WriteRecord("gap", "", 1001, 30);
  ExpectBadInput(r, {r.imu, "IMU gap", "t = 10 s", "t = 10.31 s", "max_bridge_gap_s"});
}

TEST(NavigateCli, ShortImuGapIsBridged) {
  const Record r = WriteRecord("bridge", "", 1001, 3);  // 0.04 s <= 0.1 s
  const RunResult run = Navtwin("navigate " + Args(r, r.dir + "/out"));
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.err.find("bridged 1 short IMU gap"), std::string::npos) << run.err;
}

TEST(NavigateCli, BadInputNan) {
  const Record r = WriteRecord("nan", "", 0, 0, 500);
  ExpectBadInput(r, {r.imu, "line 500"});
}

TEST(NavigateCli, BadInputGnssFarFromTheTrack) {
  std::vector<std::string> lines = GnssLines(21);
  lines[12] = GnssLine(12.0, kLatDeg + 1.0);  // 111 km north
  const Record r = WriteRecord("far", "", 0, 0, 0, lines);
  ExpectBadInput(r, {r.gnss, "t = 12 s", "max_distance_m"});
}

// The README's main command: the seed-001 manoeuvring flight, smoothed; the figures
// for filter and batch: roll and pitch < 0.7 deg, heading < 1 deg, position < 1 m,
// velocity < 0.1 m/s RMS (position as the horizontal and vertical RMS).
TEST(NavigateCli, SmoothDemoMeetsTheSeedFigures) {
  const std::string dir = MakeTempDir("demo") + "/run";
  const RunResult run = Navtwin("smooth --demo --out " + dir + " --format=json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string& s = run.out;
  for (const char* method : {"\"filter\":{", "\"rts\":{", "\"batch\":{"}) {
    const std::size_t at = s.find(method);
    ASSERT_NE(at, std::string::npos) << method;
    const std::string m = s.substr(at);
    EXPECT_LT(JsonNumberAfter(m, "\"horizontal_m\"", "rms"), 1.0) << method;
    EXPECT_LT(JsonNumberAfter(m, "\"vertical_m\"", "rms"), 1.0) << method;
    EXPECT_LT(JsonNumberAfter(m, "\"velocity_rms_mps\"", "velocity_rms_mps"), 0.1) << method;
    EXPECT_LT(JsonNumberAfter(m, "\"roll_deg\"", "rms"), 0.7) << method;
    EXPECT_LT(JsonNumberAfter(m, "\"pitch_deg\"", "rms"), 0.7) << method;
    EXPECT_LT(JsonNumberAfter(m, "\"yaw_deg\"", "rms"), 1.0) << method;
  }
  EXPECT_TRUE(Exists(dir + "/sim/navtwin.yaml"));
  EXPECT_TRUE(Exists(dir + "/summary.json"));
  EXPECT_NE(ReadAll(dir + "/summary.json").find("\"output_method\":\"batch\""), std::string::npos);
}

}  // namespace apps_navigate_cli_test
}  // namespace navtwin
