// NavOutputWriter: the four files, their columns and units, and atomicity;
// MethodOutputWriter (a method's folder) and gnss.csv.
#include "problems/gnss_ins/output.h"

#include <sys/stat.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/kfgins.h"
#include "core/rotation.h"
#include "core/units.h"
#include "tests/core/io/io_test_util.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_output_test {

using navtwin::testing::MakeTempDir;
using navtwin::testing::ReadAllSamples;

bool Exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

std::vector<std::string> Lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

std::vector<double> Numbers(const std::string& csv_line) {
  std::vector<double> v;
  std::stringstream ss(csv_line);
  for (std::string f; std::getline(ss, f, ',');) v.push_back(std::stod(f));
  return v;
}

NavEpoch Epoch(double t, int n_std) {
  NavEpoch e;
  e.state.nav.t_s = t;
  e.state.nav.gps_week = 2200;
  e.state.nav.lat_rad = 30.0 * kDegToRad;
  e.state.nav.lon_rad = 114.0 * kDegToRad;
  e.state.nav.h_m = 20.0;
  e.state.nav.v_n_mps = Eigen::Vector3d(1.0, 2.0, -0.5);
  e.state.nav.q_n_b = QuatFromEuler(1.0 * kDegToRad, -2.0 * kDegToRad, 100.0 * kDegToRad);
  e.state.imu.bg_radps = Eigen::Vector3d(10.0, 0, 0) * kDegToRad / 3600.0;  // 10 deg/h
  e.state.imu.ba_mps2 = Eigen::Vector3d(0, 2.0 * kMilliG_mps2, 0);            // 2 mg
  e.state.imu.sg = Eigen::Vector3d(0, 0, 300e-6);                          // 300 ppm
  e.state.imu.sa = Eigen::Vector3d(100e-6, 0, 0);
  e.std = Eigen::VectorXd::Constant(n_std, 0.0);
  if (n_std > 0) {
    e.std.segment<3>(0).setConstant(0.5);                              // m
    e.std.segment<3>(3).setConstant(0.05);                             // m/s
    e.std.segment<3>(6).setConstant(0.2 * kDegToRad);                  // 0.2 deg
    e.std.segment<3>(9).setConstant(5.0 * kDegToRad / 3600.0);         // 5 deg/h
    e.std.segment<3>(12).setConstant(0.5 * kMilliG_mps2);                // 0.5 mg
  }
  if (n_std == 21) e.std.segment<6>(15).setConstant(200e-6);           // 200 ppm
  return e;
}

// Unit conversions multiply by exact constants: 1e-9 relative covers the shortest-form
// printing and the conversions' rounding.
constexpr double kTol = 1e-9;

TEST(NavOutputWriter, WritesFourFilesInTheirUnits) {
  const std::string dir = MakeTempDir();
  {
    NavOutputWriter w(dir, /*scale_factors=*/false);
    w.Write(Epoch(100.0, 15), true);
    w.Write(Epoch(100.005, 15), true);
    EXPECT_EQ(w.count(), 2u);
    for (const char* f : NavOutputWriter::kFiles) EXPECT_FALSE(Exists(dir + "/" + f)) << f;
    w.Commit();
  }
  // nav.nav reads back with the KF-GINS reader.
  auto reader = OpenKfginsNav(dir + "/nav.nav");
  const std::vector<NavState> nav = ReadAllSamples(*reader);
  ASSERT_EQ(nav.size(), 2u);
  EXPECT_EQ(nav[1].t_s, 100.005);
  EXPECT_EQ(nav[1].gps_week, 2200);
  EXPECT_NEAR(nav[1].lat_rad, 30.0 * kDegToRad, 1e-15);

  const auto csv = Lines(dir + "/nav.csv");
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_EQ(csv[0], "t_s,lat_deg,lon_deg,h_m,vn_mps,ve_mps,vd_mps,roll_deg,pitch_deg,yaw_deg");
  const std::vector<double> row = Numbers(csv[1]);
  ASSERT_EQ(row.size(), 10u);
  EXPECT_NEAR(row[1], 30.0, kTol);
  EXPECT_NEAR(row[2], 114.0, kTol);
  EXPECT_EQ(row[6], -0.5);
  EXPECT_NEAR(row[7], 1.0, kTol);
  EXPECT_NEAR(row[8], -2.0, kTol);
  EXPECT_NEAR(row[9], 100.0, kTol);

  const auto sd = Lines(dir + "/std.csv");
  ASSERT_EQ(sd.size(), 3u);
  EXPECT_EQ(Numbers(sd[1]).size(), 16u);
  EXPECT_NE(sd[0].find("att_n_std_deg"), std::string::npos);
  EXPECT_EQ(sd[0].find("sg_x_std_ppm"), std::string::npos);
  const std::vector<double> s = Numbers(sd[1]);
  EXPECT_NEAR(s[1], 0.5, kTol);
  EXPECT_NEAR(s[4], 0.05, kTol);
  EXPECT_NEAR(s[7], 0.2, kTol);
  EXPECT_NEAR(s[10], 5.0, kTol);
  EXPECT_NEAR(s[13], 0.5, kTol);

  const auto err = Lines(dir + "/imu_errors.csv");
  ASSERT_EQ(err.size(), 3u);
  EXPECT_EQ(err[0], "t_s,bg_x_deg_h,bg_y_deg_h,bg_z_deg_h,ba_x_mg,ba_y_mg,ba_z_mg");
  const std::vector<double> e = Numbers(err[1]);
  ASSERT_EQ(e.size(), 7u);
  EXPECT_NEAR(e[1], 10.0, kTol);
  EXPECT_NEAR(e[5], 2.0, kTol);
}

TEST(NavOutputWriter, ScaleFactorColumnsAndMissingStd) {
  const std::string dir = MakeTempDir();
  NavOutputWriter w(dir, /*scale_factors=*/true);
  w.Write(Epoch(1.0, 21), true);
  w.Write(Epoch(2.0, 0), true);  // no standard deviations computed: nan
  w.Commit();
  const auto sd = Lines(dir + "/std.csv");
  ASSERT_EQ(sd.size(), 3u);
  const std::vector<double> s = Numbers(sd[1]);
  ASSERT_EQ(s.size(), 22u);
  EXPECT_NEAR(s[16], 200.0, kTol);
  EXPECT_NE(sd[0].find("sa_z_std_ppm"), std::string::npos);
  const std::vector<double> missing = Numbers(sd[2]);
  ASSERT_EQ(missing.size(), 22u);
  EXPECT_TRUE(std::isnan(missing[1]));
  const std::vector<double> e = Numbers(Lines(dir + "/imu_errors.csv")[1]);
  ASSERT_EQ(e.size(), 13u);
  EXPECT_NEAR(e[9], 300.0, kTol);   // sg_z
  EXPECT_NEAR(e[10], 100.0, kTol);  // sa_x
}

// Rows cross the writer thread in batches: 5,000 epochs (more than two batches), σ every
// 200th, come out in order and byte for byte as the one-record writer formats them.
TEST(NavOutputWriter, ManyEpochsComeOutInOrderAsTheRecordWriterFormatsThem) {
  const std::string dir = MakeTempDir();
  const std::string reference = dir + "/reference.nav";
  {
    NavOutputWriter w(dir, false);
    KfginsNavWriter one_by_one(reference);
    for (int k = 0; k < 5000; ++k) {
      NavEpoch e = Epoch(100.0 + 0.005 * k, 15);
      e.state.nav.lat_rad += 1e-9 * k;
      e.state.nav.h_m += 0.001 * k;
      w.Write(e, k % 200 == 0);
      one_by_one.Write(e.state.nav);
    }
    w.Commit();
    one_by_one.Commit();
  }
  const auto nav = Lines(dir + "/nav.nav");
  const auto expected = Lines(reference);
  ASSERT_EQ(nav.size(), 5000u);
  EXPECT_EQ(nav, expected);
  const auto csv = Lines(dir + "/nav.csv");
  ASSERT_EQ(csv.size(), 5001u);
  for (std::size_t k = 0; k < 5000; ++k) {
    std::string as_csv = expected[k].substr(expected[k].find(' ') + 1);  // without the week
    for (char& c : as_csv) c = c == ' ' ? ',' : c;
    ASSERT_EQ(csv[k + 1], as_csv) << "row " << k;
  }
  const auto sd = Lines(dir + "/std.csv");
  ASSERT_EQ(sd.size(), 26u);  // header + 25
  EXPECT_EQ(Numbers(sd[25])[0], 100.0 + 0.005 * 4800);
  EXPECT_EQ(Lines(dir + "/imu_errors.csv").size(), 26u);
}

// A run that fails (the writer destroyed before Commit) leaves no file behind.
TEST(NavOutputWriter, NothingAppearsWithoutCommit) {
  const std::string dir = MakeTempDir();
  {
    NavOutputWriter w(dir, false);
    w.Write(Epoch(1.0, 15), true);
  }
  {
    NavOutputWriter w(dir, false);  // batches already on the writer thread when it fails
    for (int k = 0; k < 5000; ++k) w.Write(Epoch(1.0 + 0.005 * k, 15), true);
  }
  EXPECT_EQ(::rmdir(dir.c_str()), 0) << "the folder should be empty";
}

TEST(NavOutputWriter, RejectsNonFiniteStates) {
  const std::string dir = MakeTempDir();
  NavOutputWriter w(dir, false);
  NavEpoch e = Epoch(1.0, 15);
  e.state.nav.h_m = std::nan("");
  EXPECT_THROW(w.Write(e, true), std::invalid_argument);
}

// A method's folder: nav.csv and std.csv the same lines as the top-level files, residuals.csv
// with its nan and rejected fields; Revoke takes the committed files and the folder back.
TEST(MethodOutputWriter, WritesTheMethodsFilesAndRevokesThem) {
  const std::string dir = MakeTempDir();
  NavOutputWriter top(dir, false);
  MethodOutputWriter method(dir, "batch", false);
  for (double t : {1.0, 2.0}) {
    top.Write(Epoch(t, 15), true);
    method.Write(Epoch(t, 15), true);
  }
  const double nan = std::nan("");
  method.WriteResiduals({{1.5, "gnss_position", 3, 2.25, false}, {2.0, "baro", 0, nan, true}});
  EXPECT_THROW(method.WriteResiduals({}), std::logic_error);
  EXPECT_FALSE(Exists(dir + "/batch/nav.csv")) << "before the commit";
  top.Commit();
  method.Commit();
  EXPECT_EQ(Lines(dir + "/batch/nav.csv"), Lines(dir + "/nav.csv"));
  EXPECT_EQ(Lines(dir + "/batch/std.csv"), Lines(dir + "/std.csv"));
  EXPECT_EQ(Lines(dir + "/batch/residuals.csv"),
            (std::vector<std::string>{"t_s,sensor,dof,chi2,rejected", "1.5,gnss_position,3,2.25,0", "2,baro,0,nan,1"}));
  EXPECT_FALSE(Exists(dir + "/batch/errors.csv")) << "only with OpenErrors";
  method.Revoke();
  top.Revoke();
  EXPECT_EQ(::rmdir(dir.c_str()), 0) << "the folder should be empty";
}

// The output method's folder shares the top-level nav.csv and std.csv (hard links, the same
// file); std.csv and imu_errors.csv only hold the epochs marked with_std; Revoke removes
// the links with the folder.
TEST(MethodOutputWriter, OutputMethodSharesTheTopLevelFiles) {
  const std::string dir = MakeTempDir();
  NavOutputWriter top(dir, false);
  MethodOutputWriter method(dir, "filter", false);
  method.ShareTopLevelFiles();
  for (double t : {1.0, 1.5, 2.0}) top.Write(Epoch(t, 15), /*with_std=*/t != 1.5);
  EXPECT_THROW(method.Write(Epoch(3.0, 15), true), std::logic_error);
  top.Commit();
  method.Commit();
  EXPECT_EQ(Lines(dir + "/nav.csv").size(), 4u);
  EXPECT_EQ(Lines(dir + "/std.csv").size(), 3u);  // header, t = 1 and 2
  EXPECT_EQ(Lines(dir + "/imu_errors.csv").size(), 3u);
  EXPECT_EQ(Lines(dir + "/nav.nav").size(), 3u);
  for (const char* name : {"nav.csv", "std.csv"}) {
    struct stat a, b;
    ASSERT_EQ(::stat((dir + "/" + name).c_str(), &a), 0);
    ASSERT_EQ(::stat((dir + "/filter/" + name).c_str(), &b), 0);
    EXPECT_EQ(a.st_ino, b.st_ino) << name << ": one file, two names";
  }
  method.Revoke();
  top.Revoke();
  EXPECT_EQ(::rmdir(dir.c_str()), 0) << "the folder should be empty";
}

// A writer destroyed before Commit (a failed run) removes its files and the folder it made.
TEST(MethodOutputWriter, NothingAppearsWithoutCommit) {
  const std::string dir = MakeTempDir();
  {
    MethodOutputWriter w(dir, "filter", true);
    w.Write(Epoch(1.0, 21), true);
    w.OpenErrors(true);
    w.WriteResiduals({});
  }
  EXPECT_EQ(::rmdir(dir.c_str()), 0) << "the folder should be empty";
}

// gnss.csv: used and removed fixes merged in time order, sigmas as given (nan when none).
TEST(WriteGnssCsv, MergesTheRemovedFixesInTimeOrder) {
  GnssSample g;
  g.lat_rad = 30.0 * kDegToRad;
  g.lon_rad = 114.0 * kDegToRad;
  g.h_m = 20.0;
  g.pos_std_ned_m = Eigen::Vector3d(1.0, 1.5, 2.0);
  std::vector<GnssSample> used(3, g), removed(2, g);
  used[0].t_s = 1.0;
  removed[0].t_s = 2.0;
  removed[1].t_s = 3.0;
  removed[1].pos_std_ned_m.setConstant(std::nan(""));
  used[1].t_s = 4.0;
  used[2].t_s = 5.0;
  std::ostringstream out;
  WriteGnssCsv(out, used, removed);
  std::vector<std::string> lines;
  std::stringstream in(out.str());
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  ASSERT_EQ(lines.size(), 6u);
  EXPECT_EQ(lines[0], "t_s,lat_deg,lon_deg,h_m,pos_n_std_m,pos_e_std_m,pos_d_std_m,in_outage");
  // Latitude and longitude pass through rad and back: compared to 1e-9 deg; the rest as text.
  const char* const expected[5] = {"1,20,1,1.5,2,0", "2,20,1,1.5,2,1", "3,20,nan,nan,nan,1", "4,20,1,1.5,2,0",
                                   "5,20,1,1.5,2,0"};
  for (int i = 0; i < 5; ++i) {
    std::vector<std::string> f;
    std::stringstream ss(lines[static_cast<std::size_t>(i) + 1]);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    ASSERT_EQ(f.size(), 8u) << lines[static_cast<std::size_t>(i) + 1];
    EXPECT_NEAR(std::stod(f[1]), 30.0, 1e-9);
    EXPECT_NEAR(std::stod(f[2]), 114.0, 1e-9);
    EXPECT_EQ(f[0] + "," + f[3] + "," + f[4] + "," + f[5] + "," + f[6] + "," + f[7], expected[i]);
  }
}

TEST(WriteJsonFile, WritesAtomically) {
  const std::string dir = MakeTempDir();
  WriteJsonFile(dir + "/s.json", [](JsonWriter& w) { w.BeginObject().Field("a", 1.5).EndObject(); });
  EXPECT_EQ(Lines(dir + "/s.json").at(0), "{\"a\":1.5}");
  EXPECT_THROW(WriteJsonFile(dir + "/t.json", [](JsonWriter&) { throw std::runtime_error("x"); }),
               std::runtime_error);
  EXPECT_FALSE(Exists(dir + "/t.json"));
}

}  // namespace gnss_ins_output_test
}  // namespace navtwin::gnss_ins
