// `--calibration FILE` on a command that reads an IMU (`navtwin ins`): a file whose imu
// section undoes the simulated biases and scale factors changes the output (here: removes
// the drift), and a missing or bad file exits non-zero naming the file.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/apps/cli_util.h"

namespace navtwin {
namespace apps_calibration_flag_test {

using namespace cli_test;  // RunResult, Navtwin, MakeTempDir, JsonNumberAfter

class CalibrationFlagTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = MakeTempDir("calibration_flag"); }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  std::string dir_;
};

TEST_F(CalibrationFlagTest, InsAppliesTheImuSectionAndRejectsBadFiles) {
  // 60 s at rest with constant gyro and accelerometer biases and scale factors only.
  std::ofstream(dir_ + "/static.yaml")
      << "name: static-biased\nduration_s: 60\nstart: {lat_deg: 45, lon_deg: 7, h_m: 100}\n"
         "trajectory:\n  segments:\n    - {kind: static, duration_s: 60}\n"
         "imu:\n  rate_hz: 100\n  errors:\n"
         "    gyro: {bias_fixed_deg_h: [20, -10, 5], scale_factor_fixed_ppm: [300, -200, 100]}\n"
         "    accel: {bias_fixed_ug: [2000, -1000, 500], scale_factor_fixed_ppm: [1000, -500, 800]}\n";
  ASSERT_EQ(Navtwin("simulate --scenario " + dir_ + "/static.yaml --seed 1 --out " + dir_).exit_code, 0);
  // The same errors in the calibration file's SI units.
  const double deg_h = M_PI / 180.0 / 3600.0, ug = 9.80665e-6;
  std::ofstream cal(dir_ + "/cal.yaml");
  cal.precision(17);
  cal << "navtwin_calibration: 1\ncreated_by: test\nimu:\n  gyro:\n"
      << "    scale_factor: [300e-6, -200e-6, 100e-6]\n"
      << "    bias_rad_per_s: [" << 20 * deg_h << ", " << -10 * deg_h << ", " << 5 * deg_h << "]\n"
      << "  accel:\n    scale_factor: [1000e-6, -500e-6, 800e-6]\n"
      << "    bias_mps2: [" << 2000 * ug << ", " << -1000 * ug << ", " << 500 * ug << "]\n";
  cal.close();

  const std::string ins = "ins --imu " + dir_ + "/imu.txt --init_from " + dir_ + "/truth.nav --truth " + dir_ +
                          "/truth.nav --format=json --out " + dir_;
  const RunResult raw = Navtwin(ins + "/raw");
  ASSERT_EQ(raw.exit_code, 0) << raw.err;
  const RunResult calibrated = Navtwin(ins + "/cal --calibration " + dir_ + "/cal.yaml");
  ASSERT_EQ(calibrated.exit_code, 0) << calibrated.err;
  // 2 mg for 60 s drifts ~35 m; compensated, the record is the perfect one, which the
  // simulator's round trip navigates to within a centimetre.
  EXPECT_GT(JsonNumberAfter(raw.out, "\"horizontal_m\"", "max"), 10.0) << raw.out;
  EXPECT_LT(JsonNumberAfter(calibrated.out, "\"horizontal_m\"", "max"), 0.01) << calibrated.out;
  // The temperature flag needs the file.
  EXPECT_EQ(Navtwin(ins + "/t --imu_temperature_degC 30").exit_code, 2);

  const RunResult missing = Navtwin(ins + "/m --calibration " + dir_ + "/nothere.yaml");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find(dir_ + "/nothere.yaml"), std::string::npos) << missing.err;
  std::ofstream(dir_ + "/bad.yaml") << "navtwin_calibration: 1\nimu:\n  accel:\n    bias_mps2: [0, 0]\n";
  const RunResult bad = Navtwin(ins + "/b --calibration " + dir_ + "/bad.yaml");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find(dir_ + "/bad.yaml:line 4"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("imu.accel.bias_mps2"), std::string::npos) << bad.err;
  // A magnetometer-only file cannot calibrate an IMU.
  std::ofstream(dir_ + "/mag.yaml") << "navtwin_calibration: 1\nmag: {hard_iron_uT: [1, 2, 3]}\n";
  const RunResult mag_only = Navtwin(ins + "/g --calibration " + dir_ + "/mag.yaml");
  EXPECT_EQ(mag_only.exit_code, 1);
  EXPECT_NE(mag_only.err.find("no imu section"), std::string::npos) << mag_only.err;
}

}  // namespace apps_calibration_flag_test
}  // namespace navtwin
