// End-to-end checks of `navtwin level`: text and JSON output on a simulated record of the
// seed-000 scenario, flag misuse (exit 2), bad input with its documented fallback (exit 1
// or a warning), and the motors-off segment of a real PX4 log.
#include <cmath>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "tests/apps/cli_util.h"
#include "tests/test_data.h"

#include "core/io/csv_imu.h"

namespace navtwin {
namespace apps_level_cli_test {

using namespace cli_test;  // RunResult, Navtwin, MakeTempDir, JsonNumberAfter

constexpr double kG = 9.80665;
const char* const kMethods[] = {"plain_mean", "period_average", "filter", "batch"};

/// A temporary folder per test, removed at its end.
class LevelCliTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = MakeTempDir("level"); }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }

  /// 10 s of the seed's experiment (600 Hz, level, body-x vibration 22-24 Hz of N(0, 1 g),
  /// 50 mg noise) simulated with a fixed seed; returns the IMU file.
  std::string SimulateSeedScenario() {
    const RunResult r = Navtwin("simulate --scenario leveling-600hz-vibration --seed 3 --out " + dir_ + "/sim");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return dir_ + "/sim/imu.txt";
  }

  /// 2 s at 200 Hz of gravity at roll 1 deg, with `rate_z_rad_s` of yaw rate and the
  /// x axis set to +16 g on samples 100..102 (saturated for a 16 g accelerometer).
  std::string WriteRecord(const std::string& name, double rate_z_rad_s, bool saturate) {
    const std::string path = dir_ + "/" + name;
    CsvImuWriter writer(path);
    const double roll = 1.0 * M_PI / 180.0, dt = 0.005;
    for (int k = 0; k < 400; ++k) {
      ImuSample s;
      s.t_s = k * dt;
      s.dt_s = dt;
      Eigen::Vector3d f(0.0, -kG * std::sin(roll), -kG * std::cos(roll));
      if (saturate && k >= 100 && k <= 102) f.x() = 16.0 * kG;
      s.dv_b_mps = f * dt;
      s.dtheta_b_rad = Eigen::Vector3d(0.0, 0.0, rate_z_rad_s) * dt;
      writer.Write(s);
    }
    writer.Commit();
    return path;
  }

  std::string dir_;
};

TEST_F(LevelCliTest, TextOutputListsEveryMethodWithSigmaAndPeriod) {
  const std::string imu = SimulateSeedScenario();
  const RunResult r = Navtwin("level --imu " + imu);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("120 samples at 600.00 Hz"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("checks: ok"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("roll_deg"), std::string::npos) << r.out;
  for (const char* m : kMethods) EXPECT_NE(r.out.find(std::string("\n") + m + " "), std::string::npos) << m;
}

TEST_F(LevelCliTest, JsonOnTheSeedScenarioLevelsNearTheTruth) {
  const std::string imu = SimulateSeedScenario();
  const RunResult r = Navtwin("level --imu " + imu + " --start_s 2 --format=json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string& j = r.out;
  EXPECT_EQ(JsonNumberAfter(j, "{", "samples"), 120);
  EXPECT_NEAR(JsonNumberAfter(j, "{", "rate_hz"), 600.0, 1e-6);
  EXPECT_EQ(JsonNumberAfter(j, "{", "start_s"), 2.0);
  EXPECT_EQ(JsonNumberAfter(j, "\"checks\"", "saturated_samples"), 0);
  EXPECT_NE(j.find("\"moving\":false"), std::string::npos) << j;
  for (const char* m : kMethods) {
    const std::string anchor = std::string("\"") + m + "\":{";
    ASSERT_NE(j.find(anchor), std::string::npos) << m;
    for (const char* key : {"roll_deg", "pitch_deg", "roll_sigma_deg", "pitch_sigma_deg", "period_samples"}) {
      EXPECT_TRUE(std::isfinite(JsonNumberAfter(j, anchor, key))) << m << " " << key;
    }
  }
  // 22-24 Hz at 600 Hz: 25.0-27.3 samples, rounded by the seed's method.
  const double period = JsonNumberAfter(j, "\"period_average\":{", "period_samples");
  EXPECT_GE(period, 25.0);
  EXPECT_LE(period, 27.0);
  // The truth is level. The seed method's pitch error stays within about +-3 deg (spec,
  // published experiment); the batch's 1 sigma floor is 0.26 deg, so 1 deg is ~4 sigma.
  EXPECT_LT(std::abs(JsonNumberAfter(j, "\"period_average\":{", "pitch_deg")), 3.0);
  EXPECT_LT(std::abs(JsonNumberAfter(j, "\"batch\":{", "pitch_deg")), 1.0);
  EXPECT_LT(std::abs(JsonNumberAfter(j, "\"batch\":{", "roll_deg")), 1.0);
}

TEST_F(LevelCliTest, BadFlagsExitWithUsage) {
  const std::string imu = WriteRecord("still.csv", 0.0, false);
  for (const std::string& flags : {std::string(), "--imu " + imu + " --window_s 0", "--imu " + imu + " --window_s -1",
                                  "--imu " + imu + " --start_s -2", "--imu " + imu + " --vib_axes w",
                                  "--imu " + imu + " --vib_tones 0", "--imu " + imu + " --noise_mg -5",
                                  "--imu " + imu + " extra_argument", "--imu " + imu + " --runs 5"}) {
    const RunResult r = Navtwin("level " + flags);
    EXPECT_EQ(r.exit_code, 2) << flags;
    EXPECT_NE(r.err.find("usage: navtwin level"), std::string::npos) << flags << ": " << r.err;
  }
}

TEST_F(LevelCliTest, AWindowPastTheEndOrAMissingFileExitsOne) {
  const std::string imu = WriteRecord("still.csv", 0.0, false);
  const RunResult late = Navtwin("level --imu " + imu + " --start_s 1.9 --window_s 0.2");
  EXPECT_EQ(late.exit_code, 1);
  EXPECT_NE(late.err.find("beyond the end of the record, which is 1.9950 s long"), std::string::npos) << late.err;
  EXPECT_EQ(late.out, "");
  const RunResult missing = Navtwin("level --imu " + dir_ + "/nothing.csv");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("nothing.csv"), std::string::npos) << missing.err;
}

TEST_F(LevelCliTest, MotionIsRefusedUnlessAllowed) {
  const std::string imu = WriteRecord("turning.csv", 0.2, false);
  const RunResult refused = Navtwin("level --imu " + imu);
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("mean angular rate 0.2000 rad/s"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("--allow_motion"), std::string::npos) << refused.err;
  EXPECT_EQ(refused.out, "");
  const RunResult allowed = Navtwin("level --imu " + imu + " --allow_motion --format=json");
  EXPECT_EQ(allowed.exit_code, 0) << allowed.err;
  EXPECT_NE(allowed.err.find("warning: moving"), std::string::npos) << allowed.err;
  EXPECT_NE(allowed.out.find("\"moving\":true"), std::string::npos) << allowed.out;
  // Noise-free gravity at roll 1 deg: every method gives it to rounding (the rotation
  // about z does not change the specific force).
  for (const char* m : kMethods) {
    EXPECT_NEAR(JsonNumberAfter(allowed.out, std::string("\"") + m + "\":{", "roll_deg"), 1.0, 1e-6) << m;
  }
}

TEST_F(LevelCliTest, SaturatedSamplesAreReportedOnStderr) {
  const std::string imu = WriteRecord("saturated.csv", 0.0, true);
  const RunResult r = Navtwin("level --imu " + imu + " --start_s 0.4 --window_s 0.2 --format=json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: 3 of 40 samples saturated on axis x between t = 0.5000 and 0.5100 s"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(JsonNumberAfter(r.out, "\"checks\"", "saturated_samples"), 3);
}

// battery_brownout.ulg (Pixhawk 6C, 221.7 Hz IMU): disarmed at 75.03 s after the first IMU
// sample ("Disarmed by landing", PWM 1000 from 75.1 s) and on the ground until the log ends
// at 76.03 s. Short windows of that motors-off segment must level like the whole of it.
TEST_F(LevelCliTest, RealMotorsOffWindowsAgreeWithTheWholeSegment) {
  const std::string ulog = testing::DataPath("px4-ulog/battery_brownout.ulg");
  NAVTWIN_REQUIRE_DATA(ulog);
  const RunResult whole = Navtwin("level --imu " + ulog + " --start_s 75.1 --window_s 0.9 --format=json");
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  const double roll_ref = JsonNumberAfter(whole.out, "\"plain_mean\":{", "roll_deg");
  const double pitch_ref = JsonNumberAfter(whole.out, "\"plain_mean\":{", "pitch_deg");
  // The landing spot tilts the vehicle about -1.4 deg in roll (measured: -1.375, -0.022).
  EXPECT_NEAR(roll_ref, -1.37, 0.1);
  EXPECT_NEAR(pitch_ref, -0.02, 0.1);
  for (const char* start : {"75.1", "75.3", "75.5", "75.7"}) {
    const RunResult r = Navtwin("level --imu " + ulog + " --start_s " + start + " --format=json");
    ASSERT_EQ(r.exit_code, 0) << start << ": " << r.err;
    for (const char* m : kMethods) {
      const std::string anchor = std::string("\"") + m + "\":{";
      // Motors off, the accelerometers still show 0.15-0.2 m/s^2 (x, y) of noise and a
      // 50.5 Hz tone: over 44 samples the mean keeps ~0.03 m/s^2 = 0.18 deg, 1 sigma;
      // 0.5 deg is nearly 3 sigma.
      EXPECT_NEAR(JsonNumberAfter(r.out, anchor, "roll_deg"), roll_ref, 0.5) << start << " " << m;
      EXPECT_NEAR(JsonNumberAfter(r.out, anchor, "pitch_deg"), pitch_ref, 0.5) << start << " " << m;
    }
  }
}

}  // namespace apps_level_cli_test
}  // namespace navtwin
