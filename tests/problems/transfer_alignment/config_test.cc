// The transfer-alignment configuration (config.h): every key is read into its member, the
// shipped preset file loads with every key, and bad files fail with the file, the line and
// the key.
#include "problems/transfer_alignment/config.h"

#include <string>

#include <gtest/gtest.h>

#include "core/io/input_error.h"

namespace navtwin::transfer {
namespace transfer_alignment_config_test {

// Values are compared exactly: each is a short decimal read by yaml-cpp into the nearest
// double, the same double the literal here gives. Every value differs from its default.
constexpr const char* kEveryKey = R"(gyro_bias_deg_h: 2.5
gyro_arw_deg_sqrt_h: 0.07
accel_bias_ug: 150
accel_vrw_m_s_sqrt_h: 0.03
gyro_scale_factor_ppm: 50
accel_scale_factor_ppm: 0
gyro_axis_misalignment_arcsec: 10
accel_axis_misalignment_arcsec: 30
initial_velocity_mps: 0.8
initial_attitude_deg: 1.5
misalignment_deg: 3
delay_s: 0.25
delay_initial_s: 0.1
master_attitude_mrad: 0.2
master_velocity_mps: 0.02
lever_arm_b_m: [1.5, -0.5, 0.25]
settle_s: 0
batch_state_interval_s: 0.2
batch_max_iterations: 12
history_window_s: 2.5
)";

TEST(TransferConfigTest, EveryKeyIsRead) {
  const TransferConfig c = ParseTransferConfig(kEveryKey, "every.yaml");
  EXPECT_EQ(c.gyro_bias_radps, 2.5 * kDegPerHour_radps);
  EXPECT_EQ(c.gyro_arw_rad_per_sqrt_s, 0.07 * kDegPerSqrtHour_radpsqrts);
  EXPECT_EQ(c.accel_bias_mps2, 150.0 * kMicroG_mps2);
  EXPECT_EQ(c.accel_vrw_mps_per_sqrt_s, 0.03 * kMpsPerSqrtHour_mpspsqrts);
  EXPECT_EQ(c.gyro_scale_factor, 50 * kPpm);
  EXPECT_EQ(c.accel_scale_factor, 0.0);
  EXPECT_EQ(c.gyro_axis_misalignment_rad, 10 * kArcsec_rad);
  EXPECT_EQ(c.accel_axis_misalignment_rad, 30 * kArcsec_rad);
  EXPECT_EQ(c.initial_velocity_mps, 0.8);
  EXPECT_EQ(c.initial_attitude_rad, 1.5 * kDegToRad);
  EXPECT_EQ(c.misalignment_rad, 3.0 * kDegToRad);
  EXPECT_EQ(c.delay_s, 0.25);
  EXPECT_EQ(c.delay_initial_s, 0.1);
  EXPECT_EQ(c.master_attitude_rad, 0.2 * kMrad_rad);
  EXPECT_EQ(c.master_velocity_mps, 0.02);
  EXPECT_EQ(c.lever_arm_b_m, Eigen::Vector3d(1.5, -0.5, 0.25));
  EXPECT_EQ(c.settle_s, 0.0);  // 0 is allowed: score from the start
  EXPECT_EQ(c.batch_state_interval_s, 0.2);
  EXPECT_EQ(c.batch_max_iterations, 12);
  EXPECT_EQ(c.history_window_s, 2.5);
}

TEST(TransferConfigTest, EmptyTextGivesTheDefaults) {
  const TransferConfig c = ParseTransferConfig("", "empty.yaml");
  const TransferConfig d;
  EXPECT_EQ(c.gyro_bias_radps, d.gyro_bias_radps);
  EXPECT_EQ(c.delay_s, d.delay_s);
  EXPECT_EQ(c.master_attitude_rad, d.master_attitude_rad);
  EXPECT_EQ(c.lever_arm_b_m, d.lever_arm_b_m);
  EXPECT_EQ(c.settle_s, d.settle_s);
  EXPECT_EQ(c.batch_max_iterations, d.batch_max_iterations);
}

TEST(TransferConfigTest, ShippedPresetFileListsEveryKeyWithTheDefaults) {
  const std::string path = std::string(NAVTWIN_SOURCE_DIR) + "/data/configs/transfer-alignment-high-maneuver.yaml";
  const TransferConfig c = LoadTransferConfig(path);
  const TransferConfig d;
  EXPECT_EQ(c.gyro_bias_radps, d.gyro_bias_radps);
  EXPECT_EQ(c.gyro_arw_rad_per_sqrt_s, d.gyro_arw_rad_per_sqrt_s);
  EXPECT_EQ(c.accel_bias_mps2, d.accel_bias_mps2);
  EXPECT_EQ(c.accel_vrw_mps_per_sqrt_s, d.accel_vrw_mps_per_sqrt_s);
  EXPECT_EQ(c.gyro_scale_factor, d.gyro_scale_factor);
  EXPECT_EQ(c.accel_scale_factor, d.accel_scale_factor);
  EXPECT_EQ(c.gyro_axis_misalignment_rad, d.gyro_axis_misalignment_rad);
  EXPECT_EQ(c.accel_axis_misalignment_rad, d.accel_axis_misalignment_rad);
  EXPECT_EQ(c.initial_velocity_mps, d.initial_velocity_mps);
  EXPECT_EQ(c.initial_attitude_rad, d.initial_attitude_rad);
  EXPECT_EQ(c.misalignment_rad, d.misalignment_rad);
  EXPECT_EQ(c.delay_s, d.delay_s);
  EXPECT_EQ(c.delay_initial_s, d.delay_initial_s);
  EXPECT_EQ(c.master_attitude_rad, d.master_attitude_rad);
  EXPECT_EQ(c.master_velocity_mps, d.master_velocity_mps);
  EXPECT_EQ(c.lever_arm_b_m, d.lever_arm_b_m);
  EXPECT_EQ(c.settle_s, d.settle_s);
  EXPECT_EQ(c.batch_state_interval_s, d.batch_state_interval_s);
  EXPECT_EQ(c.batch_max_iterations, d.batch_max_iterations);
  EXPECT_EQ(c.history_window_s, d.history_window_s);
}

/// Parses `text` expecting an InputError; returns it.
InputError ErrorOf(const std::string& text) {
  try {
    ParseTransferConfig(text, "bad.yaml");
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return InputError("", 0, "", "");
}

TEST(TransferConfigTest, UnknownKeyNamesFileLineAndKey) {
  const InputError e = ErrorOf("settle_s: 10\ndelay_initial: 0.3\n");
  EXPECT_EQ(e.file(), "bad.yaml");
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.field(), "delay_initial");
  EXPECT_NE(std::string(e.what()).find("bad.yaml:line 2"), std::string::npos) << e.what();
}

TEST(TransferConfigTest, ValuesOutOfRangeNameTheKeyAndLine) {
  struct Case {
    const char* key;
    const char* value;
  };
  // Sigmas must be > 0, settle_s >= 0, batch_state_interval_s > 0, iterations >= 1,
  // sensor noise >= 0; wrong types fail too.
  const Case cases[] = {
      {"initial_velocity_mps", "0"},  {"initial_attitude_deg", "-1"}, {"misalignment_deg", "0"},
      {"delay_s", "0"},               {"master_attitude_mrad", "0"},  {"master_velocity_mps", "-0.1"},
      {"settle_s", "-1"},             {"batch_state_interval_s", "0"}, {"batch_max_iterations", "0"},
      {"gyro_bias_deg_h", "-1"},      {"gyro_arw_deg_sqrt_h", "-0.1"}, {"accel_bias_ug", "-5"},
      {"accel_vrw_m_s_sqrt_h", "-1"}, {"delay_s", "abc"},              {"lever_arm_b_m", "[1, 2]"},
      {"batch_max_iterations", "2.5"}, {"history_window_s", "0"}, {"gyro_axis_misalignment_arcsec", "-1"}};
  for (const Case& c : cases) {
    const std::string text = std::string("delay_initial_s: 0.1\n") + c.key + ": " + c.value + "\n";
    const InputError e = ErrorOf(text);
    EXPECT_EQ(e.file(), "bad.yaml") << text;
    EXPECT_EQ(e.field(), c.key) << text;
    EXPECT_EQ(e.line(), 2) << text << e.what();
  }
}

TEST(TransferConfigTest, MissingFileIsAnInputErrorNamingIt) {
  try {
    LoadTransferConfig("/nonexistent/transfer.yaml");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/transfer.yaml");
  }
}

}  // namespace transfer_alignment_config_test
}  // namespace navtwin::transfer
