// The GNSS/INS run pipeline on a tiny static record: every method computed, scored against
// the GNSS file, the chosen solution and summary.json written; a failing run leaves nothing.
#include "problems/gnss_ins/run.h"

#include <dirent.h>
#include <stdlib.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/io/input_error.h"
#include "tests/problems/gnss_ins/static_record.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_run_test {


std::string MakeTempDir(const std::string& tag) {
  std::string dir = ::testing::TempDir() + "navtwin_run_" + tag + "_XXXXXX";
  EXPECT_NE(::mkdtemp(dir.data()), nullptr);
  return dir;
}


/// 20 s of a level, north-facing, static IMU at 100 Hz (gravity and Earth rate, no errors),
/// 1 Hz GNSS at its position (with zero_sigma, the fix at 10 s has a zero sigma), and a
/// configuration starting from the known state.
struct Record {
  std::string dir, imu, gnss, config;
};

Record WriteRecord(const std::string& tag, bool zero_sigma = false) {
  Record r;
  r.dir = MakeTempDir(tag);
  r.imu = r.dir + "/imu.txt";
  r.gnss = r.dir + "/gnss.txt";
  r.config = r.dir + "/navtwin.yaml";
  std::ofstream imu(r.imu);
  for (int k = 1; k <= static_record::kImuSamples; ++k) imu << static_record::ImuLine(k);
  std::ofstream gnss(r.gnss);
  for (int t = 0; t <= 20; ++t) {
    gnss << static_record::GnssLine(t, static_record::kLatDeg, zero_sigma && t == 10 ? "0.0" : "1.0");
  }
  std::ofstream(r.config) << static_record::ConfigYaml();
  return r;
}

RunOptions Options(const Record& r, const std::string& out, RunMethods methods) {
  RunOptions o;
  o.paths.imu = r.imu;
  o.paths.gnss = r.gnss;
  o.truth = r.gnss;
  o.out_dir = out;
  o.config_path = r.config;
  o.command = "smooth";
  o.methods = methods;
  return o;
}

TEST(GnssInsRun, ComputesScoresAndWritesEveryMethod) {
  const Record r = WriteRecord("all");
  const std::string out = MakeTempDir("all_out");
  GnssInsConfig config = LoadGnssInsConfig(r.config);
  config.output_rate_hz = 10.0;
  const RunOptions options = Options(r, out, RunMethods::kAll);
  const GnssInsRun run = RunGnssIns(options, config);
  ASSERT_EQ(run.methods.size(), 3u);
  EXPECT_EQ(run.methods[0].name, "filter");
  EXPECT_EQ(run.methods[1].name, "rts");
  EXPECT_EQ(run.methods[2].name, "batch");
  EXPECT_EQ(run.output_method, "batch");
  EXPECT_EQ(run.inputs.imu_samples, 2000u);
  EXPECT_EQ(run.inputs.gnss_epochs, 21u);
  EXPECT_NEAR(run.inputs.t_start_s, 0.0, 1e-9);
  EXPECT_NEAR(run.inputs.t_end_s, 20.0, 1e-9);
  // 10 Hz over 20 s.
  EXPECT_GE(run.output_epochs, 195u);
  EXPECT_LE(run.output_epochs, 202u);
  for (const MethodRun& m : run.methods) {
    ASSERT_TRUE(m.errors.has_value()) << m.name;
    EXPECT_FALSE(m.errors->has_attitude) << m.name;  // a GNSS reference
    EXPECT_GT(m.errors->all.count(), 15u) << m.name;
    EXPECT_LT(m.errors->all.HorizontalRms_m(), 0.5) << m.name;
    EXPECT_GT(m.solution.epochs.size(), 0u) << m.name;
  }
  for (const char* file : {"nav.nav", "nav.csv", "std.csv", "imu_errors.csv", "summary.json"}) {
    std::ifstream f(out + "/" + file);
    EXPECT_TRUE(f.good()) << file;
  }
  std::stringstream summary;
  summary << std::ifstream(out + "/summary.json").rdbuf();
  EXPECT_NE(summary.str().find("\"output_method\":\"batch\""), std::string::npos) << summary.str();
  EXPECT_NE(summary.str().find("\"command\":\"smooth\""), std::string::npos);
  const std::string table = RunTable(options, run);
  EXPECT_NE(table.find("errors against " + r.gnss), std::string::npos) << table;
  EXPECT_NE(table.find("\nbatch "), std::string::npos) << table;
}

TEST(GnssInsRun, FilterOnlyWithoutTruthWritesTheFilterSolution) {
  const Record r = WriteRecord("filter");
  const std::string out = MakeTempDir("filter_out");
  RunOptions options = Options(r, out, RunMethods::kFilter);
  options.truth.clear();
  const GnssInsRun run = RunGnssIns(options, LoadGnssInsConfig(r.config));
  ASSERT_EQ(run.methods.size(), 1u);
  EXPECT_EQ(run.output_method, "filter");
  EXPECT_FALSE(run.methods[0].errors.has_value());
  EXPECT_EQ(run.output_epochs, 2000u);  // every IMU epoch
  const std::string table = RunTable(options, run);
  EXPECT_NE(table.find("knots"), std::string::npos) << table;
}

TEST(GnssInsRun, BadInputLeavesTheFolderEmpty) {
  const Record r = WriteRecord("bad", /*zero_sigma=*/true);
  const std::string out = MakeTempDir("bad_out");
  EXPECT_THROW(RunGnssIns(Options(r, out, RunMethods::kFilterRts), LoadGnssInsConfig(r.config)), InputError);
  EXPECT_TRUE(static_record::Entries(out).empty());
}

}  // namespace gnss_ins_run_test
}  // namespace navtwin::gnss_ins
