// `navtwin convert` to KML, GPX and RTKLIB .pos (core/io/track_export.h): the format from
// the output's extension, the .pos read back by `navtwin info`, and the refusals (no --std
// for .pos, an epoch std.csv lacks), each with nothing written.
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "core/io/kfgins.h"
#include "core/units.h"
#include "tests/apps/cli_util.h"

namespace navtwin {
namespace apps_convert_export_cli_test {

using namespace cli_test;  // RunResult, Navtwin, ReadAll, MakeTempDir, Exists

/// A 2 s navigation file at 10 Hz (GPS week 2275) and its std.csv in a new folder.
std::string MakeRun() {
  const std::string dir = MakeTempDir("convert_export");
  KfginsNavWriter nav(dir + "/nav.nav");
  std::string std_csv = "t_s,pos_n_std_m,pos_e_std_m,pos_d_std_m,vel_n_std_mps,vel_e_std_mps,vel_d_std_mps\n";
  for (int k = 0; k <= 20; ++k) {
    NavState s;
    s.t_s = 100.0 + 0.1 * k;
    s.gps_week = 2275;
    s.lat_rad = (45.0 + 1e-6 * k) * kDegToRad;
    s.lon_rad = 10.0 * kDegToRad;
    s.h_m = 300.0;
    s.v_n_mps = Eigen::Vector3d(1.1, 0.0, 0.0);
    nav.Write(s);
    std_csv += std::to_string(s.t_s) + ",0.5,0.6,0.9,0.05,0.06,0.09\n";
  }
  nav.Commit();
  std::ofstream(dir + "/std.csv") << std_csv;
  return dir;
}

TEST(ConvertExport, KmlGpxAndPosFromTheExtension) {
  const std::string d = MakeRun();
  const RunResult pos = Navtwin("convert --in " + d + "/nav.nav --std " + d + "/std.csv --out " + d + "/t.pos");
  ASSERT_EQ(pos.exit_code, 0) << pos.err;
  EXPECT_NE(pos.out.find("converted 21 nav samples"), std::string::npos) << pos.out;
  const RunResult info = Navtwin("info " + d + "/t.pos");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("rtklib-pos"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("21 samples"), std::string::npos) << info.out;
  const RunResult kml = Navtwin("convert --in " + d + "/nav.nav --std " + d + "/std.csv --ellipse_sigma 3 --out " +
                                d + "/t.kml");
  ASSERT_EQ(kml.exit_code, 0) << kml.err;
  // One ellipse per second by default over 2 s: at 100, 101 and 102 s.
  const std::string text = ReadAll(d + "/t.kml");
  std::size_t polygons = 0;
  for (std::size_t at = text.find("<Polygon>"); at != std::string::npos; at = text.find("<Polygon>", at + 1)) {
    ++polygons;
  }
  EXPECT_EQ(polygons, 3u);
  const RunResult gpx = Navtwin("convert --in " + d + "/nav.nav --out " + d + "/t.gpx");
  ASSERT_EQ(gpx.exit_code, 0) << gpx.err;
  EXPECT_NE(ReadAll(d + "/t.gpx").find("<time>"), std::string::npos);
}

TEST(ConvertExport, InfoAndConvertRefuseAValueThatOverflowsInSiUnits) {
  // 1e308 g is finite; in m/s^2 it is not. Both commands name the file, line and field.
  const std::string dir = MakeTempDir("overflow");
  const std::string imu = dir + "/imu.csv";
  std::ofstream(imu) << "t_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,acc_x_g,acc_y_g,acc_z_g\n"
                        "0,0,0,0,0,0,1\n0.01,0,0,0,0,1e308,1\n0.02,0,0,0,0,0,1\n";
  for (const std::string& command : {"info " + imu, "convert --in " + imu + " --out " + dir + "/imu.txt"}) {
    const RunResult r = Navtwin(command);
    EXPECT_EQ(r.exit_code, 1) << command;
    for (const char* part : {"imu.csv", "line 3", "field 'acc_y_g'", "finite"}) {
      EXPECT_NE(r.err.find(part), std::string::npos) << command << ": " << part << " not in " << r.err;
    }
  }
  EXPECT_FALSE(Exists(dir + "/imu.txt"));
}

TEST(ConvertExport, RefusalsWriteNothing) {
  const std::string d = MakeRun();
  const RunResult no_std = Navtwin("convert --in " + d + "/nav.nav --out " + d + "/a.pos");
  EXPECT_EQ(no_std.exit_code, 2);
  EXPECT_NE(no_std.err.find("--to pos needs --std"), std::string::npos) << no_std.err;
  EXPECT_FALSE(Exists(d + "/a.pos"));
  const RunResult ellipse = Navtwin("convert --in " + d + "/nav.nav --ellipse_sigma 3 --out " + d + "/a.kml");
  EXPECT_EQ(ellipse.exit_code, 2);
  EXPECT_FALSE(Exists(d + "/a.kml"));
  // std.csv without the last epoch: the .pos has no sigma for it.
  std::string std_csv = ReadAll(d + "/std.csv");
  std_csv.erase(std_csv.rfind('\n', std_csv.size() - 2) + 1);
  std::ofstream(d + "/short.csv") << std_csv;
  const RunResult short_std = Navtwin("convert --in " + d + "/nav.nav --std " + d + "/short.csv --out " + d + "/b.pos");
  EXPECT_EQ(short_std.exit_code, 1);
  EXPECT_NE(short_std.err.find("short.csv"), std::string::npos) << short_std.err;
  EXPECT_NE(short_std.err.find("t_s"), std::string::npos) << short_std.err;
  EXPECT_FALSE(Exists(d + "/b.pos"));
}

}  // namespace apps_convert_export_cli_test
}  // namespace navtwin
