// The GNSS/INS run pipeline on a tiny static record: every method computed, scored against
// the GNSS file, the chosen solution, summary.json and each method's errors.csv written; a
// failing run leaves nothing. On a short simulated flight: the score does not depend on
// the output rate.
#include "problems/gnss_ins/run.h"

#include <dirent.h>
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/io/input_error.h"
#include "core/io/open.h"
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

/// With far_fix, the fix at 15 s is 1 deg (111 km) north: the filter stops there with an
/// InputError, after the run has begun writing.
Record WriteRecord(const std::string& tag, bool zero_sigma = false, bool far_fix = false) {
  Record r;
  r.dir = MakeTempDir(tag);
  r.imu = r.dir + "/imu.txt";
  r.gnss = r.dir + "/gnss.txt";
  r.config = r.dir + "/navtwin.yaml";
  std::ofstream imu(r.imu);
  for (int k = 1; k <= static_record::kImuSamples; ++k) imu << static_record::ImuLine(k);
  std::ofstream gnss(r.gnss);
  for (int t = 0; t <= 20; ++t) {
    const double lat_deg = static_record::kLatDeg + (far_fix && t == 15 ? 1.0 : 0.0);
    gnss << static_record::GnssLine(t, lat_deg, zero_sigma && t == 10 ? "0.0" : "1.0");
  }
  std::ofstream(r.config) << static_record::ConfigYaml();
  return r;
}

std::vector<std::string> Lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

/// errors.csv's header (output.h) and, for a GNSS reference, the reference-sigma columns.
const char* const kErrorsHeader =
    "t_s,pos_n_err_m,pos_e_err_m,pos_d_err_m,vel_n_err_mps,vel_e_err_mps,vel_d_err_mps,roll_err_deg,"
    "pitch_err_deg,yaw_err_deg,pos_n_std_m,pos_e_std_m,pos_d_std_m,vel_n_std_mps,vel_e_std_mps,vel_d_std_mps,"
    "roll_std_deg,pitch_std_deg,yaw_std_deg,in_outage";
const char* const kReferenceStdColumns =
    ",ref_pos_n_std_m,ref_pos_e_std_m,ref_pos_d_std_m,ref_vel_n_std_mps,ref_vel_e_std_mps,ref_vel_d_std_mps";

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
  // The record's stated sigmas do not fit its noise, so the batch's variance components
  // adapt it and the filter and RTS run again with the adapted noise.
  ASSERT_EQ(run.methods.size(), 5u);
  EXPECT_EQ(run.methods[0].name, "filter");
  EXPECT_EQ(run.methods[1].name, "rts");
  EXPECT_EQ(run.methods[2].name, "batch");
  EXPECT_EQ(run.methods[3].name, "filter_adapted");
  EXPECT_EQ(run.methods[4].name, "rts_adapted");
  EXPECT_FALSE(run.adapted_noise.empty());
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
  // errors.csv per method: a row per compared reference epoch; the GNSS file's sigmas.
  for (const MethodRun& m : run.methods) {
    EXPECT_EQ(m.errors_csv, out + "/" + m.name + "/errors.csv");
    const std::vector<std::string> rows = Lines(m.errors_csv);
    ASSERT_FALSE(rows.empty()) << m.name;
    EXPECT_EQ(rows[0], std::string(kErrorsHeader) + kReferenceStdColumns) << m.name;
    EXPECT_EQ(rows.size() - 1, m.errors->all.count()) << m.name;
    EXPECT_EQ(rows.size() - 1, m.errors->consistency_all.epochs()) << m.name;
    // No velocity and no attitude in this GNSS file: nan; the reference's 1 m north sigma.
    EXPECT_NE(rows[1].find(",nan,nan,nan,nan,nan,nan,"), std::string::npos) << rows[1];
    EXPECT_NE(rows[1].find(",0,1,1,2,nan,nan,nan"), std::string::npos) << rows[1];
  }
  std::stringstream summary;
  summary << std::ifstream(out + "/summary.json").rdbuf();
  EXPECT_NE(summary.str().find("\"output_method\":\"batch\""), std::string::npos) << summary.str();
  EXPECT_NE(summary.str().find("\"command\":\"smooth\""), std::string::npos);
  const std::string table = RunTable(options, run);
  EXPECT_NE(table.find("errors against " + r.gnss), std::string::npos) << table;
  EXPECT_NE(table.find("\nbatch "), std::string::npos) << table;
  EXPECT_NE(table.find(out + "/{filter,rts,batch,filter_adapted,rts_adapted}/errors.csv"), std::string::npos) << table;
  EXPECT_NE(table.find("err/sigma (RMS; 1 = honest sigma"), std::string::npos) << table;
  EXPECT_NE(summary.str().find("\"consistency\":{\"sigma\":\"sqrt(solution^2 + reference^2)\""), std::string::npos);
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
  EXPECT_TRUE(run.methods[0].errors_csv.empty());
  // The filter's folder holds its solution and residuals, no errors.csv.
  std::vector<std::string> filter_files = static_record::Entries(out + "/filter");
  std::sort(filter_files.begin(), filter_files.end());
  EXPECT_EQ(filter_files, (std::vector<std::string>{"nav.csv", "residuals.csv", "std.csv"}));
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

// A failure in the middle of the filter, after filter/errors.csv was opened: neither the
// file nor the method folder is left (nor anything else).
TEST(GnssInsRun, FailureDuringTheRunLeavesNoMethodFolder) {
  const Record r = WriteRecord("far", /*zero_sigma=*/false, /*far_fix=*/true);
  const std::string out = MakeTempDir("far_out");
  EXPECT_THROW(RunGnssIns(Options(r, out, RunMethods::kAll), LoadGnssInsConfig(r.config)), InputError);
  EXPECT_TRUE(static_record::Entries(out).empty());
  // The same record without the far fix writes the folder: the check above is not vacuous.
  const Record good = WriteRecord("near");
  const std::string out_good = MakeTempDir("near_out");
  RunGnssIns(Options(good, out_good, RunMethods::kFilter), LoadGnssInsConfig(good.config));
  // The header and the fixes at 1 .. 20 s (the one at 0 s precedes the first IMU epoch).
  EXPECT_EQ(Lines(out_good + "/filter/errors.csv").size(), 21u);
}

/// 40 s of a tactical-grade IMU at 100 Hz on a flight with wing rock (roll +-15 deg at
/// 0.4 Hz) and a turn, 1 Hz GNSS, no magnetometer.
constexpr const char* kWingRockScenario = R"(name: wing-rock-run
description: 40 s wing rock and a turn, tactical IMU at 100 Hz, 1 Hz GNSS
start: {lat_deg: 37.0, lon_deg: 127.0, h_m: 500}
trajectory:
  initial: {speed_mps: 40, heading_deg: 30}
  segments:
    - {kind: cruise, duration_s: 5}
    - {kind: wing_rock, duration_s: 25, roll_amplitude_deg: 15, roll_frequency_hz: 0.4}
    - {kind: turn, duration_s: 10, heading_change_deg: 60}
imu:
  rate_hz: 100
  errors:
    gyro: {bias_deg_h: 10, arw_deg_sqrt_h: 0.1, scale_factor_ppm: 100}
    accel: {bias_ug: 500, vrw_m_s_sqrt_h: 0.05, scale_factor_ppm: 100}
gnss: {rate_hz: 1, position_sigma_m: 0.5, velocity_sigma_mps: 0.05}
)";

/// Compares one statistic of two runs: the scorer saw the same states at every IMU epoch,
/// so they agree; 1e-9 relative leaves room for a multi-threaded solver's summation order.
void ExpectSame(double a, double b, const std::string& what) {
  if (std::isnan(a) && std::isnan(b)) return;
  EXPECT_NEAR(a, b, 1e-9 * std::max(1.0, std::abs(b))) << what;
}

// The score of every method is the same at output rate 1 Hz as at every IMU epoch (the
// scorer sees every IMU epoch either way), while the files hold the decimated epochs, each
// the same line as in the full-rate file. Scoring the 1 Hz file instead (what the run did
// before) misses the wing rock between its epochs: its roll RMS is several times larger,
// so the comparison above can fail.
TEST(GnssInsRun, ScoresDoNotDependOnTheOutputRate) {
  const std::string dir = MakeTempDir("rate");
  const std::string scenario = dir + "/wing_rock.yaml";
  std::ofstream(scenario) << kWingRockScenario;
  const DemoFiles sim = SimulateDemo(scenario, 7, "off", dir + "/sim", nullptr);
  RunOptions options;
  options.paths.imu = sim.imu;
  options.paths.gnss = sim.gnss;
  options.truth = sim.truth;
  options.config_path = sim.config;
  options.methods = RunMethods::kAll;
  GnssInsConfig config = LoadGnssInsConfig(sim.config);
  config.outages.start_s = 15.0;
  config.outages.len_s = 10.0;
  std::vector<GnssInsRun> runs;
  std::vector<std::string> outs;
  for (double rate_hz : {0.0, 1.0}) {
    outs.push_back(MakeTempDir(rate_hz > 0.0 ? "rate_1hz" : "rate_full"));
    options.out_dir = outs.back();
    config.output_rate_hz = rate_hz;
    runs.push_back(RunGnssIns(options, config));
  }
  const GnssInsRun& full = runs[0];
  const GnssInsRun& slow = runs[1];
  EXPECT_EQ(full.output_epochs, 4000u);
  EXPECT_EQ(slow.output_epochs, 41u);  // 0.01 s, then 1, 2, ... 40 s
  ASSERT_GE(full.methods.size(), 3u);  // filter, rts, batch (and the adapted filter and RTS)
  ASSERT_EQ(slow.methods.size(), full.methods.size());
  for (std::size_t i = 0; i < full.methods.size(); ++i) {
    const ScoreReport& a = *full.methods[i].errors;
    const ScoreReport& b = *slow.methods[i].errors;
    const std::string& name = full.methods[i].name;
    ASSERT_EQ(a.all.count(), b.all.count()) << name;
    ASSERT_EQ(a.inside.count(), b.inside.count()) << name;
    EXPECT_GT(a.inside.count(), 900u) << name;  // truth at 100 Hz over the 10 s outage
    for (int c = 0; c < kScoredComponents; ++c) {
      const std::string what = name + " component " + std::to_string(c);
      ExpectSame(a.all.Rms(c), b.all.Rms(c), what);
      ExpectSame(a.inside.Rms(c), b.inside.Rms(c), what + " inside");
      ExpectSame(a.consistency_all.RmsRatio(c), b.consistency_all.RmsRatio(c), what + " err/sigma");
      ExpectSame(a.consistency_inside.RmsRatio(c), b.consistency_inside.RmsRatio(c), what + " err/sigma inside");
    }
    ExpectSame(a.consistency_inside.PosNeesMean(), b.consistency_inside.PosNeesMean(), name + " NEES");
    ExpectSame(a.outage_horizontal_rms_m, b.outage_horizontal_rms_m, name + " drift");
    EXPECT_EQ(Lines(full.methods[i].errors_csv).size(), a.all.count() + 1) << name;
  }
  // The 1 Hz solution file: the full-rate file's lines at the decimated epochs.
  const std::vector<std::string> full_rows = Lines(outs[0] + "/nav.csv");
  const std::set<std::string> full_set(full_rows.begin(), full_rows.end());
  const std::vector<std::string> slow_rows = Lines(outs[1] + "/nav.csv");
  ASSERT_EQ(slow_rows.size(), 42u);
  for (const std::string& row : slow_rows) EXPECT_EQ(full_set.count(row), 1u) << row;
  // Scoring the 1 Hz file itself, as the run did before: the roll RMS is far off.
  auto old_way = OpenReference(sim.truth, {}, Eigen::Vector3d::Zero());
  const auto reader = OpenNav(outs[1] + "/nav.nav");
  NavEpoch e;
  while (reader->Next(&e.state.nav)) old_way->Add(e);
  const double roll_full = full.methods.back().errors->all.Rms(6);
  EXPECT_GT(old_way->Report().all.Rms(6), 3.0 * roll_full) << roll_full;
}

}  // namespace gnss_ins_run_test
}  // namespace navtwin::gnss_ins
