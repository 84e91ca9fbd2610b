// The run folder (docs/run-folder.md) of a GNSS/INS run with every method: each file with
// its header and row count, gnss.csv with the outage flags, the per-method nav.csv and
// std.csv the same as the top-level ones for the written method, residuals.csv of the
// filter and the batch against the counts and chi-square statistics of summary.json, and
// nothing left by a run that fails in the middle or at the final commit.
#include <stdlib.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "problems/gnss_ins/run.h"
#include "tests/problems/gnss_ins/static_record.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_run_folder_test {

std::string MakeTempDir(const std::string& tag) {
  std::string dir = ::testing::TempDir() + "navtwin_folder_" + tag + "_XXXXXX";
  EXPECT_NE(::mkdtemp(dir.data()), nullptr);
  return dir;
}

/// The static record of static_record.h with ZUPTs on and the fix at 12 s 30 m north of the
/// others (sigma 1 m: the filter's gate rejects it, the batch's Huber loss down-weights it).
struct Record {
  std::string imu, gnss, config;
};

constexpr double kOutlierNorth_m = 30.0;
constexpr double kOutlierTime_s = 12.0;

Record WriteRecord(const std::string& dir) {
  Record r{dir + "/imu.txt", dir + "/gnss.txt", dir + "/navtwin.yaml"};
  std::ofstream imu(r.imu);
  for (int k = 1; k <= static_record::kImuSamples; ++k) imu << static_record::ImuLine(k);
  std::ofstream gnss(r.gnss);
  const double outlier_deg = kOutlierNorth_m / 111000.0;  // about 1 m per 1/111000 deg of latitude
  for (int t = 0; t <= 20; ++t) {
    gnss << static_record::GnssLine(t, static_record::kLatDeg + (t == kOutlierTime_s ? outlier_deg : 0.0));
  }
  std::ofstream(r.config) << static_record::ConfigYaml() << "zupt:\n  enabled: true\n";
  return r;
}

RunOptions Options(const Record& r, const std::string& out) {
  RunOptions o;
  o.paths.imu = r.imu;
  o.paths.gnss = r.gnss;
  o.truth = r.gnss;
  o.out_dir = out;
  o.config_path = r.config;
  o.command = "smooth";
  o.methods = RunMethods::kAll;
  return o;
}

/// The configuration of the runs: 10 Hz output and an outage removing the fixes at 5, 6, 7 s.
GnssInsConfig Config(const Record& r) {
  GnssInsConfig config = LoadGnssInsConfig(r.config);
  config.output_rate_hz = 10.0;
  config.outages.start_s = 4.5;
  config.outages.len_s = 3.0;
  return config;
}

std::string ReadAll(const std::string& path) {
  std::stringstream s;
  s << std::ifstream(path).rdbuf();
  return s.str();
}

std::vector<std::string> Lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

std::vector<std::string> Fields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream s(line);
  for (std::string f; std::getline(s, f, ',');) fields.push_back(f);
  return fields;
}

bool Exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

/// residuals.csv per sensor: rows, rejected rows, and sums over the accepted rows of dof,
/// chi2 and the Huber loss of chi2 (threshold huber_k sigmas; Ceres' HuberLoss).
struct SensorRows {
  std::size_t rows = 0, rejected = 0;
  double dof = 0.0, chi2 = 0.0, huber_chi2 = 0.0;
};

std::map<std::string, SensorRows> ReadResiduals(const std::string& path, double huber_k) {
  const std::vector<std::string> lines = Lines(path);
  EXPECT_FALSE(lines.empty()) << path;
  if (lines.empty()) return {};
  EXPECT_EQ(lines[0], "t_s,sensor,dof,chi2,rejected") << path;
  std::map<std::string, SensorRows> out;
  double previous_t_s = -INFINITY;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> f = Fields(lines[i]);
    EXPECT_EQ(f.size(), 5u) << lines[i];
    if (f.size() != 5) continue;
    const double t_s = std::stod(f[0]);
    EXPECT_GE(t_s, previous_t_s) << path << ": rows in time order";
    previous_t_s = t_s;
    SensorRows& s = out[f[1]];
    ++s.rows;
    if (f[4] == "1") {
      ++s.rejected;
      continue;
    }
    if (f[3] == "nan") continue;  // counted without an update
    const double chi2 = std::stod(f[3]);
    s.dof += std::stod(f[2]);
    s.chi2 += chi2;
    const double k2 = huber_k * huber_k;
    s.huber_chi2 += huber_k > 0.0 && chi2 > k2 ? 2.0 * huber_k * std::sqrt(chi2) - k2 : chi2;
  }
  return out;
}

/// JSON numbers carry 10 significant digits (JsonWriter): sums agree to 1e-8 relative.
void ExpectSameSum(double file_sum, double summary, const std::string& what) {
  EXPECT_NEAR(file_sum, summary, 1e-8 * std::max(1.0, std::abs(summary))) << what;
}

/// The filter's residuals.csv: a row per counted sample; the accepted rows' NIS and
/// dimensions sum to the summary's residual statistics of the key.
void CheckFilterResiduals(const std::string& out, const std::string& method, const YAML::Node& summary) {
  const std::map<std::string, SensorRows> rows = ReadResiduals(out + "/" + method + "/residuals.csv", 0.0);
  const YAML::Node m = summary["methods"][method];
  for (const auto& kv : m["counts"]) {
    const std::string key = kv.first.as<std::string>();
    const auto used = kv.second["used"].as<std::size_t>(), rejected = kv.second["rejected"].as<std::size_t>();
    const SensorRows s = rows.count(key) ? rows.at(key) : SensorRows{};
    EXPECT_EQ(s.rows, used + rejected) << method << " " << key;
    EXPECT_EQ(s.rejected, rejected) << method << " " << key;
    if (!m["residuals"][key]) continue;
    ExpectSameSum(s.chi2, m["residuals"][key]["chi2"].as<double>(), method + " " + key + " chi2");
    ExpectSameSum(s.dof, m["residuals"][key]["rows"].as<double>(), method + " " + key + " rows");
  }
  EXPECT_EQ(rows.at("gnss_position").rejected, 1u) << method << ": the outlier";
  EXPECT_GT(rows.at("zupt").rows, 100u) << method << ": 0.1 s ZUPTs over 20 s";
}

/// The batch's residuals.csv: a row per residual block (the used count); per key the rows'
/// chi2 through the Huber loss sum to the summary's chi2 of the key's groups (a block with
/// the loss counts rho(chi2), ResidualGroups::Evaluate), with the adapted noise.
void CheckBatchResiduals(const std::string& out, const YAML::Node& summary, double huber_k) {
  const std::map<std::string, SensorRows> rows = ReadResiduals(out + "/batch/residuals.csv", huber_k);
  const YAML::Node m = summary["methods"]["batch"];
  for (const auto& kv : m["counts"]) {
    const std::string key = kv.first.as<std::string>();
    const SensorRows s = rows.count(key) ? rows.at(key) : SensorRows{};
    EXPECT_EQ(s.rows, kv.second["used"].as<std::size_t>()) << key;
    EXPECT_EQ(s.rejected, 0u) << key;
    double groups_chi2 = 0.0, groups_rows = 0.0;
    for (const auto& group : m["residuals"]) {
      if (group.first.as<std::string>().rfind(key, 0) != 0) continue;  // gnss_position_h, _v
      groups_chi2 += group.second["chi2"].as<double>();
      groups_rows += group.second["rows"].as<double>();
    }
    ExpectSameSum(s.huber_chi2, groups_chi2, "batch " + key + " chi2");
    ExpectSameSum(s.dof, groups_rows, "batch " + key + " rows");
  }
  // The outlier is beyond the Huber threshold, so the relation above is not the identity.
  EXPECT_GT(rows.at("gnss_position").chi2, rows.at("gnss_position").huber_chi2 + 1.0);
  EXPECT_TRUE(m["residuals"]["gnss_position_h"]["adapted"].as<bool>()) << "the noise the batch was solved with";
}

/// gnss.csv: every fix read, those of the outage flagged.
void CheckGnssCsv(const std::string& out, const GnssInsRun& run) {
  const std::vector<std::string> lines = Lines(out + "/gnss.csv");
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], "t_s,lat_deg,lon_deg,h_m,pos_n_std_m,pos_e_std_m,pos_d_std_m,in_outage");
  EXPECT_EQ(lines.size() - 1, run.inputs.gnss_epochs + run.inputs.gnss_removed_by_outages);
  ASSERT_EQ(lines.size(), 22u);  // 0 .. 20 s
  for (int t = 0; t <= 20; ++t) {
    const std::vector<std::string> f = Fields(lines[static_cast<std::size_t>(t) + 1]);
    ASSERT_EQ(f.size(), 8u) << lines[static_cast<std::size_t>(t) + 1];
    EXPECT_EQ(std::stod(f[0]), t);
    EXPECT_EQ(f[4] + "," + f[5] + "," + f[6], "1,1,2") << "the file's sigmas";
    EXPECT_EQ(f[7], t >= 5 && t <= 7 ? "1" : "0") << "t = " << t;
  }
  EXPECT_NEAR(std::stod(Fields(lines[13])[1]), static_record::kLatDeg + kOutlierNorth_m / 111000.0, 1e-9)
      << "positions as given";
}

const char* const kNavHeader = "t_s,lat_deg,lon_deg,h_m,vn_mps,ve_mps,vd_mps,roll_deg,pitch_deg,yaw_deg";

// smooth's folder: summary.json, the written solution, gnss.csv, and per method its
// nav.csv, std.csv, errors.csv and (filter, batch, filter_adapted) residuals.csv.
TEST(GnssInsRunFolder, EveryMethodWritesItsFiles) {
  const std::string dir = MakeTempDir("all");
  const Record r = WriteRecord(dir);
  const std::string out = dir + "/out";
  ASSERT_EQ(::mkdir(out.c_str(), 0755), 0);
  const GnssInsConfig config = Config(r);
  const GnssInsRun run = RunGnssIns(Options(r, out), config);
  ASSERT_EQ(run.methods.size(), 5u) << "filter, rts, batch, filter_adapted, rts_adapted";
  EXPECT_EQ(run.inputs.gnss_removed_by_outages, 3u);
  for (const char* file : {"summary.json", "nav.nav", "nav.csv", "std.csv", "imu_errors.csv", "gnss.csv"}) {
    EXPECT_TRUE(Exists(out + "/" + file)) << file;
  }
  CheckGnssCsv(out, run);
  const std::string top_std = ReadAll(out + "/std.csv");
  for (const MethodRun& m : run.methods) {
    const std::string folder = out + "/" + m.name;
    const std::vector<std::string> nav = Lines(folder + "/nav.csv"), std = Lines(folder + "/std.csv");
    ASSERT_FALSE(nav.empty()) << m.name;
    EXPECT_EQ(nav[0], kNavHeader) << m.name;
    EXPECT_EQ(nav.size(), run.output_epochs + 1) << m.name << ": the same output rate";
    // std.csv at std_rate_hz (1 Hz by default): the first output epoch of every second.
    std::vector<std::string> std_epochs;
    long second = -1;
    for (std::size_t i = 1; i < nav.size(); ++i) {
      const std::string t = Fields(nav[i])[0];
      if (static_cast<long>(std::floor(std::stod(t) + 1e-6)) == second) continue;
      second = static_cast<long>(std::floor(std::stod(t) + 1e-6));
      std_epochs.push_back(t);
    }
    EXPECT_EQ(config.std_rate_hz, 1.0);
    ASSERT_EQ(std.size(), std_epochs.size() + 1) << m.name;
    EXPECT_LT(std.size(), nav.size()) << m.name << ": the comparison can fail";
    EXPECT_EQ(std[0], Lines(out + "/std.csv")[0]) << m.name;
    for (std::size_t i = 0; i < std_epochs.size(); ++i) {
      EXPECT_EQ(Fields(std[i + 1])[0], std_epochs[i]) << m.name << ": the std epochs";
    }
    EXPECT_TRUE(Exists(folder + "/errors.csv")) << m.name;
    const bool residuals = m.name == "filter" || m.name == "batch" || m.name == "filter_adapted";
    EXPECT_EQ(Exists(folder + "/residuals.csv"), residuals) << m.name;
  }
  EXPECT_EQ(ReadAll(out + "/batch/nav.csv"), ReadAll(out + "/nav.csv")) << "the written method's, byte for byte";
  EXPECT_EQ(ReadAll(out + "/batch/std.csv"), top_std);
  EXPECT_NE(ReadAll(out + "/rts/nav.csv"), ReadAll(out + "/nav.csv")) << "the comparison above can fail";

  const YAML::Node summary = YAML::LoadFile(out + "/summary.json");
  CheckFilterResiduals(out, "filter", summary);
  CheckFilterResiduals(out, "filter_adapted", summary);
  CheckBatchResiduals(out, summary, config.batch.huber_k);
}

// A failure in the middle (the batch's folder cannot be made: a file is in its place,
// after the filter's and RTS's folders were written) and one at the final commit (gnss.csv
// cannot be renamed onto a folder, after the method folders were committed) leave the
// output folder as it was.
TEST(GnssInsRunFolder, FailingRunsLeaveNothing) {
  const std::string dir = MakeTempDir("fail");
  const Record r = WriteRecord(dir);
  const std::string mid = dir + "/mid";
  ASSERT_EQ(::mkdir(mid.c_str(), 0755), 0);
  std::ofstream(mid + "/batch") << "in the way\n";
  EXPECT_THROW(RunGnssIns(Options(r, mid), Config(r)), std::runtime_error);
  EXPECT_EQ(static_record::Entries(mid), std::vector<std::string>{"batch"});

  const std::string commit = dir + "/commit";
  ASSERT_EQ(::mkdir(commit.c_str(), 0755), 0);
  ASSERT_EQ(::mkdir((commit + "/gnss.csv").c_str(), 0755), 0);
  EXPECT_THROW(RunGnssIns(Options(r, commit), Config(r)), std::runtime_error);
  EXPECT_EQ(static_record::Entries(commit), std::vector<std::string>{"gnss.csv"});
  EXPECT_TRUE(static_record::Entries(commit + "/gnss.csv").empty());
}

}  // namespace gnss_ins_run_folder_test
}  // namespace navtwin::gnss_ins
