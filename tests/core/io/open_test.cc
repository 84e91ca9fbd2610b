// Format detection, dispatch by kind (including ULog) and file summaries.
#include "core/io/open.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "tests/core/io/io_test_util.h"
#include "tests/test_data.h"

namespace navtwin {
namespace io_open_test {

using testing::ExpectInputError;
using testing::MakeTempDir;
using testing::WriteFile;

TEST(OpenTest, DetectsEveryTextKindFromItsFirstLines) {
  const std::string d = MakeTempDir();
  struct Case {
    const char* name;
    const char* text;
    FileFormat format;
  };
  const Case cases[] = {
      {"imu.txt", "388000.005 1e-5 -2e-5 3e-6 0.001 0.002 -0.049\n", FileFormat::kKfginsImu},
      {"gnss.txt", "388000 30.5 114.3 20.1 0.01 0.01 0.02\n", FileFormat::kKfginsGnss},
      {"gnss13.txt", "388000 30.5 114.3 20.1 0.01 0.01 0.02 1 2 3 .1 .1 .1\n",
       FileFormat::kKfginsGnss},
      {"nav.txt", "2381 388000 30.5 114.3 20.1 0 0 0 1 2 3\n", FileFormat::kKfginsNav},
      {"sf.csv", "1756402240.9610000,-0.017,-0.007,1.01,0.0006,-0.0028,0.0027,0,0,0,0\n",
       FileFormat::kRtklibWalkImuSf},
      {"sol.pos", "% program : RTKLIB\n", FileFormat::kRtklibPos},
      {"imu.csv", "# note\nt_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps\n",
       FileFormat::kCsvImu},
      {"rates.csv", "t_ms,gyro_x_dps,gyro_y_dps,gyro_z_dps,acc_x_g,acc_y_g,acc_z_g\n",
       FileFormat::kCsvImu},
      {"IMU_1.csv", "time,Euler_X,Euler_Y,Euler_Z,Acc_X,Acc_Y,Acc_Z,Gyr_X,Gyr_Y,Gyr_Z\n",
       FileFormat::kAnsflImu},
      {"dot.csv", "SampleTimeFine,Euler_X,Euler_Y,Euler_Z,Acc_X,Acc_Y,Acc_Z,Gyr_X,Gyr_Y,Gyr_Z,\n",
       FileFormat::kAnsflDotRaw},
      {"GT.csv",
       "time,distance(meters),speed(m/s), compass_heading(degrees), pitch(degrees), "
       "roll(degrees),height_above_takeoff(meters),North,East,Down\n",
       FileFormat::kAnsflGt},
      {"GTExtended.csv",
       "time(millisecond),latitude,longitude,altitude_above_seaLevel(meters),North,East,Down, "
       "xSpeed(m/s), ySpeed(m/s), zSpeed(m/s), roll(degrees), pitch(degrees), "
       "compass_heading(degrees)\n",
       FileFormat::kAnsflGtExtended},
      {"five.txt", "1 2 3 4 5\n", FileFormat::kUnknown},
      {"other.csv", "a,b,c\n", FileFormat::kUnknown},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(DetectFormat(WriteFile(d + "/" + c.name, c.text)), c.format) << c.name;
  }
  const std::string raw = WriteFile(d + "/imu_walk.csv", "0.01,-0.02,1.0,0.5,-0.25,9.0,1000\n");
  WriteFile(d + "/imu_walk.csv.tag", "TIMETAG RTKLIB");
  EXPECT_EQ(DetectFormat(raw), FileFormat::kRtklibWalkImu);
  EXPECT_EQ(DetectFormat(WriteFile(d + "/log.ulg", "not really")), FileFormat::kULog);
}

TEST(OpenTest, FormatNamesAreDistinct) {
  std::set<std::string> names;
  for (int f = 0; f <= static_cast<int>(FileFormat::kUnknown); ++f) {
    names.insert(FormatName(static_cast<FileFormat>(f)));
  }
  EXPECT_EQ(names.size(), static_cast<std::size_t>(FileFormat::kUnknown) + 1);
  EXPECT_EQ(FormatName(FileFormat::kRtklibPos), "rtklib-pos");
}

TEST(OpenTest, RefusesStreamsAKindDoesNotHold) {
  const std::string d = MakeTempDir();
  const std::string imu =
      WriteFile(d + "/imu.txt", "1.000 0 0 0 0 0 -0.049\n1.005 0 0 0 0 0 -0.049\n");
  ImuSample s;
  EXPECT_TRUE(OpenImu(imu)->Next(&s));
  ExpectInputError([&] { OpenGnss(imu); },
                   {imu, "cannot read GNSS samples from a file of kind kfgins-imu"});
  ExpectInputError([&] { OpenNav(imu); }, {"cannot read navigation states"});
  ExpectInputError([&] { OpenMag(imu); }, {"cannot read magnetometer samples"});
  ExpectInputError([&] { OpenBaro(imu); }, {"cannot read barometer samples"});
  const std::string unknown = WriteFile(d + "/five.txt", "1 2 3 4 5\n");
  ExpectInputError([&] { OpenImu(unknown); }, {unknown, "line 1", "5 numbers", "7 (KF-GINS IMU or GNSS)"});
  ExpectInputError([&] { DescribeFile(unknown); }, {"not a recognised format"});
  const std::string empty = WriteFile(d + "/empty.txt", "");
  ExpectInputError([&] { OpenImu(empty); }, {empty, "empty"});
}

// Detection does not rest on the first line alone: a corrupt first data line leaves the
// kind to the next lines (and the reader then names the bad line and field); a kind that
// stays unknown names the line and the field; 7 columns near (0 deg, 0 deg) are told apart
// by the sigmas, the height and the time step.
TEST(OpenTest, DetectionSurvivesACorruptFirstLineAndExplainsUnknownKinds) {
  const std::string d = MakeTempDir();
  const std::string corrupt = WriteFile(d + "/corrupt.txt",
                                        "1.000 0 0 0x 0 0 -0.049\n1.005 0 0 0 0 0 -0.049\n1.010 0 0 0 0 0 -0.049\n");
  EXPECT_EQ(DetectFormat(corrupt), FileFormat::kKfginsImu);
  ImuSample s;
  ExpectInputError([&] { OpenImu(corrupt)->Next(&s); }, {corrupt, "line 1", "0x"});
  const std::string text = WriteFile(d + "/text.txt", "1.000 0 zero 0 0 0 -0.049\n");
  ExpectInputError([&] { OpenImu(text); }, {text, "line 1", "field 3", "zero"});
  const std::string header = WriteFile(d + "/header.csv", "# made by hand\ntime,ax,ay,az\n0,1,2,3\n");
  ExpectInputError([&] { OpenImu(header); }, {header, "line 2", "header", "not a format navtwin reads"});
  const std::string gnss = WriteFile(d + "/gnss_at_origin.txt",
                                     "388000 0.10 0.20 20.1 0.01 0.01 0.02\n388001 0.10 0.20 20.1 0.01 0.01 0.02\n");
  EXPECT_EQ(DetectFormat(gnss), FileFormat::kKfginsGnss);
  const std::string imu = WriteFile(d + "/imu_200hz.txt", "1.000 0.1 0.2 0 0 0 -0.049\n1.005 0.1 0.2 0 0 0 -0.049\n");
  EXPECT_EQ(DetectFormat(imu), FileFormat::kKfginsImu);
  // A 20 Hz IMU whose dv happen to be positive (upside down) is still an IMU: no height.
  const std::string slow = WriteFile(d + "/imu_20hz.txt", "1.00 0.01 0.02 0.001 0.01 0.02 0.49\n1.05 0.01 0.02 0.001 0.01 0.02 0.49\n");
  EXPECT_EQ(DetectFormat(slow), FileFormat::kKfginsImu);
  // A GNSS fix at sea level near (0, 0) at 1 Hz: the time step.
  const std::string sea = WriteFile(d + "/gnss_sea_level.txt", "100 0.1 0.2 0.3 0.01 0.01 0.02\n101 0.1 0.2 0.3 0.01 0.01 0.02\n");
  EXPECT_EQ(DetectFormat(sea), FileFormat::kKfginsGnss);
}

TEST(OpenTest, DescribesATextFile) {
  const std::string d = MakeTempDir();
  const std::string imu =
      WriteFile(d + "/imu.csv",
                "t_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps\n"
                "1.00,0,0,0,0,0,0\n1.01,0,0,0,0,0,0\n1.02,0,0,0,0,0,0\n1.05,0,0,0,0,0,0\n");
  const FileSummary f = DescribeFile(imu);
  EXPECT_EQ(f.kind, "csv-imu");
  ASSERT_EQ(f.streams.size(), 1u);
  EXPECT_EQ(f.streams[0].count, 4u);
  EXPECT_NEAR(f.streams[0].rate_hz, 100.0, 1e-3);  // median of 0.01, 0.01, 0.03 (float dt)
  EXPECT_EQ(f.streams[0].gaps, 1u);                // 0.03 s > 2 x the median
  ASSERT_EQ(f.streams[0].fields.size(), 7u);
  EXPECT_EQ(f.streams[0].fields[4], "dv_x_mps");
}

TEST(OpenRealDataTest, DetectsAndDescribesTheRealFiles) {
  const std::string root = testing::DataPath("");
  NAVTWIN_REQUIRE_DATA(testing::DataPath("rtklib-walk/imu_1730.csv"));
  NAVTWIN_REQUIRE_DATA(testing::DataPath("ansfl-quadrotor/StraightLine/path_1/GT.csv"));
  const struct {
    const char* path;
    FileFormat format;
  } cases[] = {
      {"rtklib-walk/gnss_1730_sf.pos", FileFormat::kRtklibPos},
      {"rtklib-walk/imu_1730.csv", FileFormat::kRtklibWalkImu},
      {"rtklib-walk/imu_1730_sf.csv", FileFormat::kRtklibWalkImuSf},
      {"ansfl-quadrotor/StraightLine/path_1/IMU_1.csv", FileFormat::kAnsflImu},
      {"ansfl-quadrotor/StraightLine/path_1/GT.csv", FileFormat::kAnsflGt},
      {"ansfl-quadrotor/StraightLine/path_1/GTExtended.csv", FileFormat::kAnsflGtExtended},
      {"ansfl-quadrotor/StraightLine/RAW/Xsens_DOT1_D422CD003EBC_20220707_111110.csv",
       FileFormat::kAnsflDotRaw},
      {"ansfl-quadrotor/StraightLine/RAW/Jul-7th-2022-11-10AM-Flight-Airdata.csv",
       FileFormat::kUnknown},
      {"px4-ulog/sample.ulg", FileFormat::kULog},
  };
  for (const auto& c : cases) EXPECT_EQ(DetectFormat(root + c.path), c.format) << c.path;
  const FileSummary walk = DescribeFile(root + "rtklib-walk/imu_1730.csv");
  ASSERT_EQ(walk.streams.size(), 1u);
  EXPECT_EQ(walk.streams[0].count, 20454u);
  const FileSummary pos = DescribeFile(root + "rtklib-walk/gnss_1730_sf.pos");
  EXPECT_EQ(pos.streams[0].count, 536u);
  EXPECT_NEAR(pos.streams[0].rate_hz, 4.0, 1e-3);  // 0.25 s intervals stored as float
  const FileSummary gt = DescribeFile(root + "ansfl-quadrotor/StraightLine/path_1/GT.csv");
  EXPECT_EQ(gt.streams[0].count, 239u);
  NavState n;
  EXPECT_TRUE(OpenNav(root + "ansfl-quadrotor/StraightLine/path_1/GTExtended.csv")->Next(&n));
  MagSample m;
  EXPECT_TRUE(OpenMag(root + "ansfl-quadrotor/StraightLine/RAW/"
                             "Xsens_DOT1_D422CD003EBC_20220707_111110.csv")
                  ->Next(&m));
}

// ULog dispatch goes to core/io/ulog.h (tested in ulog_test.cc); here only that each
// stream reaches it.
TEST(OpenRealDataTest, DispatchesULogStreams) {
  const std::string sample = testing::DataPath("px4-ulog/sample.ulg");
  const std::string ekf = testing::DataPath("px4-ulog/ekf_failure.ulg");
  NAVTWIN_REQUIRE_DATA(sample);
  NAVTWIN_REQUIRE_DATA(ekf);
  ImuSample imu;
  EXPECT_TRUE(OpenImu(sample)->Next(&imu));
  MagSample mag;
  EXPECT_TRUE(OpenMag(sample)->Next(&mag));
  GnssSample gnss;
  EXPECT_TRUE(OpenGnss(ekf)->Next(&gnss));
  BaroSample baro;
  EXPECT_TRUE(OpenBaro(ekf)->Next(&baro));
  NavState nav;  // a ULog's navigation stream is PX4's own estimate
  EXPECT_TRUE(OpenNav(ekf)->Next(&nav));
  EXPECT_EQ(nav.gps_week, 2353);
  EXPECT_EQ(DescribeFile(sample).kind, "ulog");
}

}  // namespace io_open_test
}  // namespace navtwin
