// The calibration file's installation section (core/calibration_file.h: the IMU's mounting
// and time offset that `transfer-align-ansfl --calibration_out` writes and `smooth
// --calibration` applies): exact round trip with and without sigmas, every bad-input case
// naming file, line and key, and the refusal by the IMU openers of the commands that have
// no mounting to apply it to.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "core/calibration_file.h"
#include "core/io/csv_imu.h"
#include "core/io/input_error.h"
#include "tests/scratch_dir.h"

namespace navtwin {
namespace core_calibration_installation_test {

class CalibrationInstallationTest : public testing::ScratchDirTest {};

/// A DOT-like installation: 180 deg roll (z up), a few degrees, a 0.4 s clock offset.
ImuInstallation DotInstallation() {
  ImuInstallation x;
  x.mounting_rpy_rad = Eigen::Vector3d(3.1372, -0.024958, -0.016929);
  x.time_offset_s = -0.41877;
  return x;
}

TEST_F(CalibrationInstallationTest, RoundTripIsExact) {
  CalibrationFile f;
  f.created_by = "navtwin transfer-align-ansfl --data=D --path=Horizontal/path_4 --dot=1";
  ImuInstallation x = DotInstallation();
  x.mounting_sigma_rad = Eigen::Vector3d(1.4e-3, std::numeric_limits<double>::quiet_NaN(), 4e-4);
  x.time_offset_sigma_s = 1e-4;
  f.installation = x;
  ImuCalibration imu;
  imu.gyro.tail<3>() = Eigen::Vector3d(-0.014, -0.0084, -0.0077);  // the coarse gyro bias beside it
  f.imu = imu;
  const std::string path = dir_ + "/cal.yaml";
  WriteCalibrationFile(path, f);
  const CalibrationFile r = ReadCalibrationFile(path);
  ASSERT_TRUE(r.installation && r.imu);
  EXPECT_EQ(r.installation->mounting_rpy_rad, x.mounting_rpy_rad);  // bitwise: shortest round-trip form
  EXPECT_EQ(r.installation->time_offset_s, x.time_offset_s);
  ASSERT_TRUE(r.installation->mounting_sigma_rad && r.installation->time_offset_sigma_s);
  EXPECT_EQ(r.installation->mounting_sigma_rad->x(), 1.4e-3);
  EXPECT_TRUE(std::isnan(r.installation->mounting_sigma_rad->y()));  // null: not estimated
  EXPECT_EQ(r.installation->time_offset_sigma_s, 1e-4);
  EXPECT_EQ(r.imu->gyro.tail<3>(), imu.gyro.tail<3>());

  // An installation-only file, without sigmas, reads back without them and without imu.
  CalibrationFile only;
  only.installation = DotInstallation();
  WriteCalibrationFile(path, only);
  const CalibrationFile o = ReadCalibrationFile(path);
  ASSERT_TRUE(o.installation);
  EXPECT_FALSE(o.imu);
  EXPECT_FALSE(o.installation->mounting_sigma_rad);
  EXPECT_FALSE(o.installation->time_offset_sigma_s);
}

TEST_F(CalibrationInstallationTest, NonFiniteOffsetIsNotWritten) {
  CalibrationFile f;
  f.installation = DotInstallation();
  f.installation->time_offset_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(WriteCalibrationFile(dir_ + "/cal.yaml", f), std::invalid_argument);
  EXPECT_TRUE(std::filesystem::is_empty(dir_));  // the atomic file leaves nothing
}

struct BadCase {
  const char* what;
  std::string yaml;  ///< after the two header lines
  long line;
  const char* key;  ///< the key path the message must name
};

TEST_F(CalibrationInstallationTest, BadInputNamesFileLineAndKey) {
  const std::string head = "navtwin_calibration: 1\ncreated_by: test\n";
  const std::string ok_mounting = "  imu_mounting_rpy_rad: [3.1, -0.02, 0.01]\n";
  const std::string ok_offset = "  imu_time_offset_s: 0.4\n";
  const BadCase cases[] = {
      // A missing value is never taken as 0: the line is the section's first key.
      {"missing time offset", "installation:\n" + ok_mounting, 4, "installation.imu_time_offset_s"},
      {"missing mounting", "installation:\n" + ok_offset, 4, "installation.imu_mounting_rpy_rad"},
      {"empty section", "installation: {}\n", 3, "installation.imu_mounting_rpy_rad"},
      {"NaN offset", "installation:\n" + ok_mounting + "  imu_time_offset_s: .nan\n", 5,
       "installation.imu_time_offset_s"},
      {"NaN angle", "installation:\n  imu_mounting_rpy_rad: [3.1, .nan, 0]\n" + ok_offset, 4,
       "installation.imu_mounting_rpy_rad"},
      {"degrees given", "installation:\n  imu_mounting_rpy_rad: [179.7, -1.4, -0.9]\n" + ok_offset, 4,
       "installation.imu_mounting_rpy_rad"},
      {"pitch beyond 90 deg", "installation:\n  imu_mounting_rpy_rad: [0, 1.6, 0]\n" + ok_offset, 4,
       "installation.imu_mounting_rpy_rad"},
      {"two angles", "installation:\n  imu_mounting_rpy_rad: [3.1, 0]\n" + ok_offset, 4,
       "installation.imu_mounting_rpy_rad"},
      {"text offset", "installation:\n" + ok_mounting + "  imu_time_offset_s: soon\n", 5,
       "installation.imu_time_offset_s"},
      {"unknown key", "installation:\n" + ok_mounting + ok_offset + "  imu_mounting_deg: [180, 0, 0]\n", 6,
       "installation.imu_mounting_deg"},
      {"zero sigma", "installation:\n" + ok_mounting + ok_offset + "  sigma:\n    imu_time_offset_s: 0\n", 7,
       "installation.sigma.imu_time_offset_s"},
      {"negative sigma",
       "installation:\n" + ok_mounting + ok_offset + "  sigma:\n    imu_mounting_rpy_rad: [1e-3, -1e-3, 1e-3]\n", 7,
       "installation.sigma.imu_mounting_rpy_rad"},
      {"infinite sigma", "installation:\n" + ok_mounting + ok_offset + "  sigma:\n    imu_time_offset_s: .inf\n", 7,
       "installation.sigma.imu_time_offset_s"},
  };
  for (const BadCase& c : cases) {
    const std::string path = Write("bad.yaml", head + c.yaml);
    try {
      ReadCalibrationFile(path);
      ADD_FAILURE() << c.what << ": accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path) << c.what;
      EXPECT_EQ(e.line(), c.line) << c.what << ": " << e.what();
      EXPECT_EQ(e.field(), c.key) << c.what << ": " << e.what();
    }
  }
}

// ins, level, allan, inflight-align and transfer-align open the IMU through OpenImu(path,
// calibration, T): they have no mounting or clock to apply the section to, so they refuse
// it instead of dropping it.
TEST_F(CalibrationInstallationTest, ImuOpenerOfOtherCommandsRefusesTheSection) {
  const std::string imu_path = dir_ + "/imu.csv";
  {
    CsvImuWriter imu(imu_path);
    for (int k = 1; k <= 3; ++k) {
      ImuSample s;
      s.t_s = 0.01 * k;
      s.dt_s = 0.01;
      s.dv_b_mps = Eigen::Vector3d(0, 0, -0.098);
      imu.Write(s);
    }
    imu.Commit();
  }
  CalibrationFile f;
  f.imu = ImuCalibration();
  const std::string plain = dir_ + "/plain.yaml", with = dir_ + "/with.yaml";
  WriteCalibrationFile(plain, f);
  f.installation = DotInstallation();
  WriteCalibrationFile(with, f);
  EXPECT_NO_THROW(OpenImu(imu_path, plain, NAN));
  try {
    OpenImu(imu_path, with, NAN);
    ADD_FAILURE() << "an installation section was accepted by OpenImu";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), with);
    EXPECT_EQ(e.field(), "installation");
  }
}

}  // namespace core_calibration_installation_test
}  // namespace navtwin
