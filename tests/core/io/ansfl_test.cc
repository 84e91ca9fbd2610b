// ANSFL quadrotor files: DOT IMU (processed and raw), GT and GTExtended, synthetic and real.
#include "core/io/ansfl.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "core/earth.h"
#include "core/rotation.h"
#include "tests/core/io/io_test_util.h"
#include "tests/test_data.h"

namespace navtwin {
namespace io_ansfl_test {

using testing::ExpectInputError;
using testing::MakeTempDir;
using testing::ReadAllSamples;
using testing::WriteFile;

constexpr double kPeriod = 1.0 / 120.0;

std::size_t CountLines(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::size_t n = 0;
  while (std::getline(in, line)) ++n;
  return n;
}

const char kDotHeader[] = "time,Euler_X,Euler_Y,Euler_Z,Acc_X,Acc_Y,Acc_Z,Gyr_X,Gyr_Y,Gyr_Z\n";

/// A processed DOT row: rotating at 90 deg/s about z, 9.81 m/s^2 on z.
std::string DotRow(double t) { return std::to_string(t) + ",0,0,0,0.1,0,9.81,0,0,90\n"; }

TEST(AnsflTest, ProcessedDotRatesBecomeIncrementsInSensorAxes) {
  const std::string dir = MakeTempDir();
  std::string text = kDotHeader;
  for (int k = 0; k < 5; ++k) text += DotRow(k * 0.008333);
  const std::vector<ImuSample> s =
      ReadAllSamples(*OpenAnsflImu(WriteFile(dir + "/IMU_1.csv", text)));
  ASSERT_EQ(s.size(), 4u);  // the first row starts the series
  // Constant rates: rate * dt exactly up to rounding (1e-15).
  EXPECT_NEAR(s[0].dt_s, 0.008333, 1e-15);
  EXPECT_NEAR(s[0].dtheta_b_rad.z(), 90 * kDegToRad * s[0].dt_s, 1e-15);
  EXPECT_NEAR(s[0].dv_b_mps.z(), 9.81 * s[0].dt_s, 1e-15);  // z up, not rotated to FRD
  EXPECT_NEAR(s[0].dv_b_mps.x(), 0.1 * s[0].dt_s, 1e-15);
}

TEST(AnsflTest, ImplausibleRatesAndFieldsAreRefused) {
  const std::string dir = MakeTempDir();
  std::string text = std::string(kDotHeader) + DotRow(0.0) + "0.008333,0,0,0,0.1,0,9.81,0,-1.1e16,90\n" + DotRow(0.016666);
  const std::string path = WriteFile(dir + "/IMU_1.csv", text);
  ExpectInputError([&] { ReadAllSamples(*OpenAnsflImu(path)); }, {path, "line 3", "field 'Gyr_Y'", "implausible angular rate"});
  const std::string header =
      "SampleTimeFine,Euler_X,Euler_Y,Euler_Z,Acc_X,Acc_Y,Acc_Z,Gyr_X,Gyr_Y,Gyr_Z,Mag_X,Mag_Y,Mag_Z,\n";
  const std::string raw = WriteFile(dir + "/Xsens_DOT9.csv", header + "1000,0,0,0,0,0,9.8,0,0,30,-0.5,0.2,1e307,\n");
  ExpectInputError([&] { ReadAllSamples(*OpenAnsflDotRawMag(raw)); }, {raw, "line 2", "field 'Mag_Z'", "implausible magnetic field"});
}

TEST(AnsflTest, LostSamplePatternIsRetimed) {
  const std::string dir = MakeTempDir();
  // Rows at 0, P, 2P, then the lost-sample pattern: 4P (really 3P), 4P again, then 5P.
  const double P = 0.008333;
  std::string text = kDotHeader;
  for (double t : {0.0, P, 2 * P, 4 * P, 4 * P, 5 * P}) text += DotRow(t);
  const std::string path = WriteFile(dir + "/IMU_2.csv", text);
  const std::vector<ImuSample> s = ReadAllSamples(*OpenAnsflImu(path));
  ASSERT_EQ(s.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR(s[k].t_s, (k + 1) * P, 1e-6) << k;  // printed with 6 decimals
  }
  const FileSummary d = DescribeAnsflImu(path);
  ASSERT_FALSE(d.notes.empty());
  bool noted = false;
  for (const std::string& n : d.notes) noted |= n.find("1 rows re-timed") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST(AnsflTest, RepeatedTimeOutsideThePatternIsAnError) {
  const std::string dir = MakeTempDir();
  const double P = 0.008333;
  std::string text = kDotHeader;
  for (double t : {0.0, P, 2 * P, 2 * P, 3 * P}) text += DotRow(t);
  const std::string path = WriteFile(dir + "/IMU_3.csv", text);
  ExpectInputError([&] { ReadAllSamples(*OpenAnsflImu(path)); },
                   {path, "line 5", "field 'time'", "repeats line 4"});
  std::string back = kDotHeader;
  for (double t : {0.0, P, 2 * P, P}) back += DotRow(t);
  const std::string back_path = WriteFile(dir + "/IMU_4.csv", back);
  ExpectInputError([&] { ReadAllSamples(*OpenAnsflImu(back_path)); },
                   {"line 5", "does not increase"});
  const std::string nan = WriteFile(dir + "/nan.csv", std::string(kDotHeader) + DotRow(0) +
                                                          "0.008333,0,0,0,0.1,NaN,9.81,0,0,90\n");
  ExpectInputError([&] { ReadAllSamples(*OpenAnsflImu(nan)); },
                   {"line 3", "field 'Acc_Y'", "not a finite number"});
  const std::string missing =
      WriteFile(dir + "/missing.csv", "time,Acc_X,Acc_Y,Acc_Z,Gyr_X,Gyr_Y\n0,0,0,0,0,0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenAnsflImu(missing)); },
                   {"line 1", "missing column 'Gyr_Z'"});
  const std::string empty = WriteFile(dir + "/empty.csv", "");
  ExpectInputError([&] { ReadAllSamples(*OpenAnsflImu(empty)); }, {empty, "empty"});
}

/// A raw DOT row with the trailing comma and blank of the real files.
std::string RawRow(unsigned long long ticks, const std::string& acc_gyr) {
  return std::to_string(ticks) + ",1,2,3," + acc_gyr + ",-0.5,-0.4,-1.1, \n";
}

TEST(AnsflTest, RawDotUnwrapsTheClockSkipsZeroRowsAndDropsLostRows) {
  const std::string dir = MakeTempDir();
  const std::string header =
      "SampleTimeFine,Euler_X,Euler_Y,Euler_Z,Acc_X,Acc_Y,Acc_Z,Gyr_X,Gyr_Y,Gyr_Z,Mag_X,Mag_Y,"
      "Mag_Z,\n";
  const std::string data = "0,0,9.8,0,0,30";
  const unsigned long long start = 4294967296ULL - 3 * 8333;  // wraps after three periods
  std::string text = header + RawRow(start, "0,0,0,0,0,0");   // all-zero first row
  for (int k = 1; k <= 6; ++k) {
    const unsigned long long t = (start + 8333ULL * k) % 4294967296ULL;
    if (k == 4) continue;  // lost sample...
    text += RawRow(t, data);
    if (k == 5) text += RawRow(t, "NaN,NaN,NaN,Infinity,Infinity,Infinity");  // ...marked so
  }
  const std::string path = WriteFile(dir + "/Xsens_DOT9.csv", text);
  const std::vector<ImuSample> s = ReadAllSamples(*OpenAnsflDotRawImu(path));
  // Rows: zero (skipped), 1, 2, 3, 5 (re-timed to 4), 5 (NaN, dropped), 6: five rate
  // samples -> four increments, at 2..6 periods after the start.
  ASSERT_EQ(s.size(), 4u);
  const double t0 = start * 1e-6;
  const double expected[] = {2, 3, 4, 6};
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(s[k].t_s - t0, expected[k] * 8333e-6, 1e-9) << k;  // us ticks in double
  }
  EXPECT_NEAR(s[3].dtheta_b_rad.z(), 30 * kDegToRad * 2 * 8333e-6, 1e-12);  // bridged gap
  const std::vector<MagSample> m = ReadAllSamples(*OpenAnsflDotRawMag(path));
  ASSERT_EQ(m.size(), 7u);  // every row has a finite magnetometer
  EXPECT_NEAR(m[0].m_b_uT.x(), -0.5 * kXsensDotMagUtPerUnit, 1e-12);
  const FileSummary d = DescribeAnsflDotRaw(path);
  ASSERT_EQ(d.streams.size(), 2u);
  std::string notes;
  for (const std::string& n : d.notes) notes += n + "\n";
  EXPECT_NE(notes.find("1 leading rows with all-zero"), std::string::npos) << notes;
  EXPECT_NE(notes.find("1 lost-sample rows"), std::string::npos) << notes;
  EXPECT_NE(notes.find("(1 wraps)"), std::string::npos) << notes;
}

TEST(AnsflTest, RawDotClockJumpIsAnErrorNotAWrap) {
  const std::string dir = MakeTempDir();
  const std::string header =
      "SampleTimeFine,Euler_X,Euler_Y,Euler_Z,Acc_X,Acc_Y,Acc_Z,Gyr_X,Gyr_Y,Gyr_Z,Mag_X,Mag_Y,"
      "Mag_Z,\n";
  const std::string data = "0,0,9.8,0,0,30";
  const unsigned long long start = 500'000'000ULL;  // 500 s after power-on
  // One corrupt SampleTimeFine (line 5): near 2^32, then near 0, then back on time.
  for (const unsigned long long corrupt : {4294967000ULL, 12ULL, start + 8333ULL * 400}) {
    SCOPED_TRACE(corrupt);
    std::string text = header;
    for (int k = 0; k < 8; ++k) text += RawRow(k == 3 ? corrupt : start + 8333ULL * k, data);
    const std::string path = WriteFile(dir + "/Xsens_DOT8.csv", text);
    ExpectInputError([&] { ReadAllSamples(*OpenAnsflDotRawImu(path)); },
                     {path, "line 5", "field 'SampleTimeFine'"});
    ExpectInputError([&] { DescribeAnsflDotRaw(path); },
                     {path, "line 5", "field 'SampleTimeFine'"});
  }
  // The same at the second row, before any interval is known.
  const std::string second = WriteFile(
      dir + "/Xsens_DOT5.csv",
      header + RawRow(start, data) + RawRow(4294967000ULL, data) + RawRow(start + 8333, data));
  ExpectInputError([&] { ReadAllSamples(*OpenAnsflDotRawImu(second)); },
                   {"line 3", "field 'SampleTimeFine'"});
}

TEST(AnsflTest, RawDotNanOutsideThePatternIsAnError) {
  const std::string dir = MakeTempDir();
  const std::string header =
      "SampleTimeFine,Euler_X,Euler_Y,Euler_Z,Acc_X,Acc_Y,Acc_Z,Gyr_X,Gyr_Y,Gyr_Z,\n";
  const std::string text = header + "1000,1,2,3,0,0,9.8,0,0,30, \n9333,1,2,3,0,0,9.8,NaN,0,30, \n";
  const std::string path = WriteFile(dir + "/Xsens_DOT4.csv", text);
  ExpectInputError([&] { ReadAllSamples(*OpenAnsflDotRawImu(path)); },
                   {"line 3", "field 'Gyr_X'", "not a finite number"});
  ExpectInputError([&] { ReadAllSamples(*OpenAnsflDotRawMag(path)); }, {"missing column 'Mag_X'"});
}

std::string GtText(int rows) {
  std::string text =
      "time,distance(meters),speed(m/s), compass_heading(degrees), pitch(degrees), "
      "roll(degrees),height_above_takeoff(meters),North,East,Down\n";
  for (int k = 0; k < rows; ++k) {
    // 2 m/s north, 1 m/s west, climbing 0.5 m/s; heading 270 deg.
    text += std::to_string(0.1 * k) + ",0,0,270,-2,1,0," + std::to_string(0.2 * k) + "," +
            std::to_string(-0.1 * k) + "," + std::to_string(-0.05 * k) + "\n";
  }
  return text;
}

TEST(AnsflTest, GtWithoutExtendedUsesTheSiteOriginAndDifferencedVelocity) {
  const std::string dir = MakeTempDir();
  const std::vector<NavState> s =
      ReadAllSamples(*OpenAnsflGt(WriteFile(dir + "/GT.csv", GtText(5))));
  ASSERT_EQ(s.size(), 5u);
  EXPECT_EQ(s[0].gps_week, -1);
  // The first row (N = E = D = 0) is the site origin itself.
  EXPECT_NEAR(s[0].lat_rad, AnsflSiteOrigin().lat_rad, 1e-12);  // through ECEF and back
  EXPECT_NEAR(s[0].lon_rad, AnsflSiteOrigin().lon_rad, 1e-12);
  // -Down above the site; WGS84 curvature over 0.9 m: < 1e-6 m.
  EXPECT_NEAR(s[4].h_m, AnsflSiteOrigin().h_m + 0.2, 1e-6);
  for (const NavState& n : s) {
    // Differences of positions printed to 1e-6 m over 0.1-0.2 s: 1e-5 m/s.
    EXPECT_NEAR(n.v_n_mps.x(), 2.0, 1e-5);
    EXPECT_NEAR(n.v_n_mps.y(), -1.0, 1e-5);
    EXPECT_NEAR(n.v_n_mps.z(), -0.5, 1e-5);
  }
  const Eigen::Vector3d rpy = EulerFromQuat(s[0].q_n_b) * kRadToDeg;
  EXPECT_NEAR(rpy.x(), 1.0, 1e-9);    // roll
  EXPECT_NEAR(rpy.y(), -2.0, 1e-9);   // pitch
  EXPECT_NEAR(rpy.z(), -90.0, 1e-9);  // 270 deg heading wrapped
}

TEST(AnsflTest, GtWithExtendedTakesOriginAndSpeedsAndChecksPairing) {
  const std::string dir = MakeTempDir();
  WriteFile(dir + "/GTExtended.csv",
            "time(millisecond),latitude,longitude,altitude_above_seaLevel(meters),North,East,Down, "
            "xSpeed(m/s), ySpeed(m/s), zSpeed(m/s), roll(degrees), pitch(degrees), "
            "compass_heading(degrees)\n"
            "56100,32.8,34.9,10.0,0,0,0,2.1,-1.1,-0.4,1,-2,270\n"
            "56200,32.8,34.9,10.0,0,0,0,2.1,-1.1,-0.4,1,-2,270\n"
            "56300,32.8,34.9,10.0,0,0,0,2.2,-1.2,-0.6,1,-2,270\n");
  const std::string gt = WriteFile(dir + "/GT.csv", GtText(3));
  const std::vector<NavState> s = ReadAllSamples(*OpenAnsflGt(gt));
  ASSERT_EQ(s.size(), 3u);
  EXPECT_NEAR(s[0].lat_rad, 32.8 * kDegToRad, 1e-15);
  EXPECT_NEAR(s[0].h_m, 10.0, 1e-9);
  EXPECT_EQ(s[2].v_n_mps, Eigen::Vector3d(2.2, -1.2, -0.6));
  // The NED offset of the last row is reproduced through WGS84 to well below 1 mm.
  const wgs84::Geodetic origin{32.8 * kDegToRad, 34.9 * kDegToRad, 10.0};
  const Eigen::Vector3d ned = wgs84::GeodeticToNed({s[2].lat_rad, s[2].lon_rad, s[2].h_m}, origin);
  EXPECT_LT((ned - Eigen::Vector3d(0.4, -0.2, -0.1)).norm(), 1e-6);
  WriteFile(dir + "/GT.csv", GtText(4));  // one row more than GTExtended.csv
  ExpectInputError([&] { ReadAllSamples(*OpenAnsflGt(gt)); },
                   {"GTExtended.csv", "ends before GT.csv"});
  const std::vector<NavState> e = ReadAllSamples(*OpenAnsflGtExtended(dir + "/GTExtended.csv"));
  ASSERT_EQ(e.size(), 3u);
  EXPECT_NEAR(e[0].t_s, 56.1, 1e-12);
}

std::vector<std::string> PathFolders() {
  std::vector<std::string> v;
  for (int p = 1; p <= 4; ++p) v.push_back("StraightLine/path_" + std::to_string(p));
  for (int p = 1; p <= 27; ++p) v.push_back("Horizontal/path_" + std::to_string(p));
  return v;
}

TEST(AnsflRealDataTest, EveryPathImuLoadsAt120HzAndGtLoads) {
  const std::string root = testing::DataPath("ansfl-quadrotor");
  NAVTWIN_REQUIRE_DATA(root);
  for (const std::string& folder : PathFolders()) {
    for (int k = 1; k <= 4; ++k) {
      const std::string path = root + "/" + folder + "/IMU_" + std::to_string(k) + ".csv";
      const std::vector<ImuSample> s = ReadAllSamples(*OpenAnsflImu(path));
      ASSERT_GT(s.size(), 100u) << path;
      const double rate = static_cast<double>(s.size() - 1) / (s.back().t_s - s.front().t_s);
      EXPECT_NEAR(rate, 120.0, 1.0) << path;
    }
    const std::string gt = root + "/" + folder + "/GT.csv";
    EXPECT_EQ(ReadAllSamples(*OpenAnsflGt(gt)).size(), CountLines(gt) - 1) << gt;
  }
}

TEST(AnsflRealDataTest, StraightLinePath1ImuCountAndAxes) {
  const std::string path = testing::DataPath("ansfl-quadrotor/StraightLine/path_1/IMU_1.csv");
  NAVTWIN_REQUIRE_DATA(path);
  const std::vector<ImuSample> s = ReadAllSamples(*OpenAnsflImu(path));
  // 2881 lines = header + 2880 rate rows; the first row only starts the series.
  ASSERT_EQ(CountLines(path), 2881u);
  ASSERT_EQ(s.size(), 2879u);
  EXPECT_NEAR(s.front().t_s, 0.008333, 1e-9);
  EXPECT_NEAR(s.back().t_s, 23.990707, 1e-9);
  double dv_z = 0.0, t = 0.0;
  for (const ImuSample& x : s) {
    dv_z += x.dv_b_mps.z();
    t += x.dt_s;
  }
  // Level flight: the mean specific force on the DOT's z axis is +g (z up); +-0.8 m/s^2
  // allows for the DOT's ~5 deg tilt on the drone and the flight's accelerations.
  EXPECT_NEAR(dv_z / t, 9.8, 0.8);
}

TEST(AnsflRealDataTest, ProcessedLostSampleRowsAreRetimed) {
  const std::string path = testing::DataPath("ansfl-quadrotor/Horizontal/path_9/IMU_2.csv");
  NAVTWIN_REQUIRE_DATA(path);
  const std::vector<ImuSample> s = ReadAllSamples(*OpenAnsflImu(path));
  ASSERT_EQ(s.size(), CountLines(path) - 2);
  // Line 2251 repeats 18.757583 after a double interval from 18.740917: it becomes the
  // middle, 18.74925 (times printed to 1e-6 s).
  bool found = false;
  for (std::size_t k = 1; k < s.size(); ++k) {
    if (std::fabs(s[k].t_s - 18.74925) < 1e-6) {
      found = true;
      EXPECT_NEAR(s[k].dt_s, 0.008333, 1e-6);
      EXPECT_NEAR(s[k + 1].t_s, 18.757583, 1e-6);
    }
  }
  EXPECT_TRUE(found);
}

TEST(AnsflRealDataTest, GtAgreesWithGtExtendedOnStraightLinePaths) {
  const std::string root = testing::DataPath("ansfl-quadrotor/StraightLine");
  NAVTWIN_REQUIRE_DATA(root);
  for (int p = 1; p <= 4; ++p) {
    const std::string folder = root + "/path_" + std::to_string(p);
    const std::vector<NavState> gt = ReadAllSamples(*OpenAnsflGt(folder + "/GT.csv"));
    const std::vector<NavState> ext =
        ReadAllSamples(*OpenAnsflGtExtended(folder + "/GTExtended.csv"));
    ASSERT_EQ(gt.size(), ext.size());
    for (std::size_t k = 0; k < gt.size(); ++k) {
      const Eigen::Vector3d d = wgs84::GeodeticToNed({gt[k].lat_rad, gt[k].lon_rad, gt[k].h_m},
                                                     {ext[k].lat_rad, ext[k].lon_rad, ext[k].h_m});
      // The files' N/E/D agree with their latitude/longitude/altitude to 1.1 mm (checked
      // with a flat-Earth conversion); 3 mm leaves room for the file's 1e-7 deg rounding.
      EXPECT_LT(d.norm(), 3e-3) << folder << " row " << k;
      EXPECT_EQ(gt[k].v_n_mps, ext[k].v_n_mps);
      EXPECT_LT(AttitudeError(gt[k].q_n_b, ext[k].q_n_b).norm(), 1e-12);
    }
  }
}

TEST(AnsflRealDataTest, RawDotFilesLoad) {
  const std::string raw = testing::DataPath("ansfl-quadrotor/StraightLine/RAW");
  NAVTWIN_REQUIRE_DATA(raw);
  const char* files[] = {
      "Xsens_DOT1_D422CD003EBC_20220707_111110.csv", "Xsens_DOT1_D422CD003EBC_20220707_111438.csv",
      "Xsens_DOT2_D422CD003B0C_20220707_111109.csv", "Xsens_DOT2_D422CD003B0C_20220707_111437.csv",
      "Xsens_DOT4_D422CD003ED6_20220707_111110.csv", "Xsens_DOT4_D422CD003ED6_20220707_111438.csv",
      "Xsens_DOT7_D422CD004217_20220707_111109.csv", "Xsens_DOT7_D422CD004217_20220707_111437.csv"};
  for (const char* f : files) {
    const std::string path = raw + "/" + f;
    const std::size_t rows = CountLines(path) - 1;
    const bool dot7_late =
        std::string(f).find("DOT7_D422CD004217_20220707_111437") != std::string::npos;
    const bool dot4 = std::string(f).find("DOT4") != std::string::npos;
    const std::vector<ImuSample> s = ReadAllSamples(*OpenAnsflDotRawImu(path));
    // Minus the all-zero first row, the series start and (DOT7, 11:14:37) one lost row.
    EXPECT_EQ(s.size(), rows - 2 - (dot7_late ? 1 : 0)) << f;
    const double rate = static_cast<double>(s.size() - 1) / (s.back().t_s - s.front().t_s);
    EXPECT_NEAR(rate, 120.0, 1.0) << f;
    if (dot4) {
      ExpectInputError([&] { OpenAnsflDotRawMag(path); }, {"Mag_X"});
    } else {
      EXPECT_EQ(ReadAllSamples(*OpenAnsflDotRawMag(path)).size(), rows) << f;
    }
  }
}

}  // namespace io_ansfl_test
}  // namespace navtwin
