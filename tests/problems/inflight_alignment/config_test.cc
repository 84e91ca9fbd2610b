// The in-flight alignment configuration (config.h): every key is read into its field, the
// shipped preset file loads, and bad files fail with the file, the line and the key path.
#include "problems/inflight_alignment/config.h"

#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "core/io/input_error.h"

namespace navtwin::inflight {
namespace inflight_alignment_config_test {

// Values are compared exactly: each is a short decimal read by yaml-cpp into the nearest
// double, the same double the literal here gives.
constexpr const char* kEveryKey = R"(sensors:
  gyro_bias_deg_h: 0.02
  gyro_arw_deg_sqrt_h: 0.006
  accel_bias_ug: 50
  accel_vrw_m_s_sqrt_h: 0.001
  gps_sigma_m: 12
initial:
  position_m: 5
  velocity_mps: 0.2
  level_arcmin: 0.5
  heading_arcmin: 60
baro:
  time_constant_s: 30
smoother:
  use_in_distance: false
  use_in_kalman: true
  quiet_accel_noise_mps2_sqrt_hz: 0.2
  maneuver_accel_noise_mps2_sqrt_hz: 20
  maneuver_mean_interval_s: 5000
  maneuver_mean_duration_s: 15
  initial_position_sigma_ned_m: [11, 12, 13]
  initial_speed_sigma_mps: 250
  noise_window_fixes: 100
  noise_min_fixes: 25
  min_position_sigma_m: 0.7
  max_position_sigma_m: 90
  gate_probability: 0.999
  reset_after_rejections: 4
distance:
  threshold_km: 8
  recompute_every_km: 5
batch:
  loss: huber
  loss_scale_sigma: 2.5
  max_iterations: 80
  tilt_segment_s: 45
)";

TEST(InflightConfigTest, EveryKeyIsRead) {
  const InflightConfig c = ParseInflightConfig(kEveryKey, "every.yaml");
  EXPECT_EQ(c.sensors.gyro_bias_radps, 0.02 * kDegPerHour_radps);
  EXPECT_EQ(c.sensors.gyro_arw_rad_per_sqrt_s, 0.006 * kDegPerSqrtHour_radpsqrts);
  EXPECT_EQ(c.sensors.accel_bias_mps2, 50.0 * kMicroG_mps2);
  EXPECT_EQ(c.sensors.accel_vrw_mps_per_sqrt_s, 0.001 * kMpsPerSqrtHour_mpspsqrts);
  EXPECT_EQ(c.sensors.gps_sigma_m, 12.0);
  EXPECT_EQ(c.initial.position_m, 5.0);
  EXPECT_EQ(c.initial.velocity_mps, 0.2);
  EXPECT_EQ(c.initial.level_rad, 0.5 * kArcmin_rad);
  EXPECT_EQ(c.initial.heading_rad, 60.0 * kArcmin_rad);
  EXPECT_EQ(c.baro.time_constant_s, 30.0);
  // Both opposite to the defaults (distance smooths, kalman does not).
  EXPECT_FALSE(c.smooth_gps_distance);
  EXPECT_TRUE(c.smooth_gps_kalman);
  const GpsSmootherOptions& s = c.smoother;
  EXPECT_EQ(s.quiet_accel_noise_mps2_sqrt_hz, 0.2);
  EXPECT_EQ(s.maneuver_accel_noise_mps2_sqrt_hz, 20.0);
  EXPECT_EQ(s.maneuver_mean_interval_s, 5000.0);
  EXPECT_EQ(s.maneuver_mean_duration_s, 15.0);
  EXPECT_EQ(s.initial_position_sigma_ned_m, Eigen::Vector3d(11.0, 12.0, 13.0));
  EXPECT_EQ(s.initial_speed_sigma_mps, 250.0);
  EXPECT_EQ(s.noise_window_fixes, 100);
  EXPECT_EQ(s.noise_min_fixes, 25);
  EXPECT_EQ(s.min_position_sigma_m, 0.7);
  EXPECT_EQ(s.max_position_sigma_m, 90.0);
  EXPECT_EQ(s.gate_probability, 0.999);
  EXPECT_EQ(s.reset_after_rejections, 4);
  EXPECT_EQ(c.distance.threshold_m, 8e3);
  EXPECT_EQ(c.distance.recompute_every_m, 5e3);
  EXPECT_EQ(c.batch.loss, RobustLoss::kHuber);
  EXPECT_EQ(c.batch.loss_scale_sigma, 2.5);
  EXPECT_EQ(c.batch.max_iterations, 80);
  EXPECT_EQ(c.batch.tilt_segment_s, 45.0);
}

TEST(InflightConfigTest, EmptyTextGivesTheDefaults) {
  const InflightConfig c = ParseInflightConfig("", "empty.yaml");
  const InflightConfig d;
  EXPECT_EQ(c.sensors.gps_sigma_m, d.sensors.gps_sigma_m);
  EXPECT_EQ(c.initial.heading_rad, d.initial.heading_rad);
  EXPECT_EQ(c.distance.threshold_m, d.distance.threshold_m);
  EXPECT_EQ(c.batch.loss, d.batch.loss);
  EXPECT_EQ(c.smoother.noise_window_fixes, d.smoother.noise_window_fixes);
}

TEST(InflightConfigTest, ShippedPresetFileHoldsTheDefaultsAndTheGpsSigma) {
  // data/configs/inflight-mach07-south.yaml lists every key: the defaults of config.h and
  // gps_sigma_m 17, the preset's GPS noise.
  const InflightConfig c =
      LoadInflightConfig(std::string(NAVTWIN_SOURCE_DIR) + "/data/configs/inflight-mach07-south.yaml");
  const InflightConfig d;
  EXPECT_EQ(c.sensors.gps_sigma_m, 17.0);
  EXPECT_EQ(c.sensors.gyro_bias_radps, d.sensors.gyro_bias_radps);
  EXPECT_EQ(c.sensors.gyro_arw_rad_per_sqrt_s, d.sensors.gyro_arw_rad_per_sqrt_s);
  EXPECT_EQ(c.sensors.accel_bias_mps2, d.sensors.accel_bias_mps2);
  EXPECT_EQ(c.sensors.accel_vrw_mps_per_sqrt_s, d.sensors.accel_vrw_mps_per_sqrt_s);
  EXPECT_EQ(c.initial.position_m, d.initial.position_m);
  EXPECT_EQ(c.initial.velocity_mps, d.initial.velocity_mps);
  EXPECT_EQ(c.initial.level_rad, d.initial.level_rad);
  EXPECT_EQ(c.initial.heading_rad, d.initial.heading_rad);
  EXPECT_EQ(c.baro.time_constant_s, d.baro.time_constant_s);
  EXPECT_EQ(c.smooth_gps_distance, d.smooth_gps_distance);
  EXPECT_EQ(c.smooth_gps_kalman, d.smooth_gps_kalman);
  EXPECT_EQ(c.smoother.quiet_accel_noise_mps2_sqrt_hz, d.smoother.quiet_accel_noise_mps2_sqrt_hz);
  EXPECT_EQ(c.smoother.maneuver_accel_noise_mps2_sqrt_hz, d.smoother.maneuver_accel_noise_mps2_sqrt_hz);
  EXPECT_EQ(c.smoother.maneuver_mean_interval_s, d.smoother.maneuver_mean_interval_s);
  EXPECT_EQ(c.smoother.maneuver_mean_duration_s, d.smoother.maneuver_mean_duration_s);
  EXPECT_EQ(c.smoother.initial_position_sigma_ned_m, d.smoother.initial_position_sigma_ned_m);
  EXPECT_EQ(c.smoother.initial_speed_sigma_mps, d.smoother.initial_speed_sigma_mps);
  EXPECT_EQ(c.smoother.noise_window_fixes, d.smoother.noise_window_fixes);
  EXPECT_EQ(c.smoother.noise_min_fixes, d.smoother.noise_min_fixes);
  EXPECT_EQ(c.smoother.min_position_sigma_m, d.smoother.min_position_sigma_m);
  EXPECT_EQ(c.smoother.max_position_sigma_m, d.smoother.max_position_sigma_m);
  EXPECT_EQ(c.smoother.gate_probability, d.smoother.gate_probability);
  EXPECT_EQ(c.smoother.reset_after_rejections, d.smoother.reset_after_rejections);
  EXPECT_EQ(c.distance.threshold_m, d.distance.threshold_m);
  EXPECT_EQ(c.distance.recompute_every_m, d.distance.recompute_every_m);
  EXPECT_EQ(c.batch.loss, d.batch.loss);
  EXPECT_EQ(c.batch.loss_scale_sigma, d.batch.loss_scale_sigma);
  EXPECT_EQ(c.batch.max_iterations, d.batch.max_iterations);
  EXPECT_EQ(c.batch.tilt_segment_s, d.batch.tilt_segment_s);
}

TEST(InflightConfigTest, ZeroIsAcceptedWhereItMeansNoneOrEstimate) {
  const InflightConfig c = ParseInflightConfig(
      "sensors: {gps_sigma_m: 0, gyro_bias_deg_h: 0, accel_bias_ug: 0, gyro_arw_deg_sqrt_h: 0}\n"
      "distance: {recompute_every_km: 0}\n"
      "smoother: {initial_position_sigma_ned_m: 8}\n"
      "batch: {tilt_segment_s: 0}\n",
      "zero.yaml");
  EXPECT_EQ(c.sensors.gps_sigma_m, 0.0);
  EXPECT_EQ(c.sensors.gyro_bias_radps, 0.0);
  EXPECT_EQ(c.distance.recompute_every_m, 0.0);
  EXPECT_EQ(c.batch.tilt_segment_s, 0.0);  // no level random walk in the batch
  EXPECT_EQ(c.smoother.initial_position_sigma_ned_m, Eigen::Vector3d::Constant(8.0));  // scalar: every axis
}

/// Parses `text` expecting an InputError; returns it.
InputError ErrorOf(const std::string& text) {
  try {
    ParseInflightConfig(text, "bad.yaml");
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return InputError("", 0, "", "");
}

TEST(InflightConfigTest, UnknownKeysNameFileLineAndKeyPath) {
  InputError e = ErrorOf("sensors:\n  gyro_bias_deg_h: 0.01\n  gyro_bais_deg_h: 1\n");
  EXPECT_EQ(e.file(), "bad.yaml");
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.field(), "sensors.gyro_bais_deg_h");
  EXPECT_NE(std::string(e.what()).find("bad.yaml:line 3"), std::string::npos) << e.what();

  e = ErrorOf("distance:\n  threshold_km: 10\nfilter:\n  x: 1\n");
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.field(), "filter");

  e = ErrorOf("smoother:\n  gate_probability: 0.99\n  gate: 1\n");
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.field(), "smoother.gate");
}

TEST(InflightConfigTest, ValuesOutOfRangeNameTheKey) {
  struct Case {
    const char* text;
    const char* field;
  };
  const Case cases[] = {
      {"initial:\n  heading_arcmin: 0\n", "initial.heading_arcmin"},
      {"initial:\n  position_m: -1\n", "initial.position_m"},
      {"initial:\n  level_arcmin: 0\n", "initial.level_arcmin"},
      {"sensors:\n  gps_sigma_m: -1\n", "sensors.gps_sigma_m"},
      {"sensors:\n  gyro_bias_deg_h: -0.01\n", "sensors.gyro_bias_deg_h"},
      {"sensors:\n  accel_bias_ug: -100\n", "sensors.accel_bias_ug"},
      {"distance:\n  threshold_km: 0\n", "distance.threshold_km"},
      {"distance:\n  recompute_every_km: -5\n", "distance.recompute_every_km"},
      {"baro:\n  time_constant_s: 0\n", "baro.time_constant_s"},
      {"batch:\n  loss_scale_sigma: 0\n", "batch.loss_scale_sigma"},
      {"batch:\n  loss: l2\n", "batch.loss"},
      {"batch:\n  max_iterations: 0\n", "batch.max_iterations"},
      {"batch:\n  tilt_segment_s: -30\n", "batch.tilt_segment_s"},
      {"smoother:\n  gate_probability: 1.5\n", "smoother.gate_probability"},
      {"smoother:\n  noise_min_fixes: 200\n", "smoother.noise_min_fixes"},  // > window 120
      {"smoother:\n  max_position_sigma_m: 0.1\n", "smoother.max_position_sigma_m"},  // < min 0.5
      {"smoother:\n  initial_position_sigma_ned_m: [1, 0, 1]\n", "smoother.initial_position_sigma_ned_m"},
      {"distance:\n  threshold_km: ten\n", "distance.threshold_km"},  // wrong type
  };
  for (const Case& c : cases) {
    const InputError e = ErrorOf(c.text);
    EXPECT_EQ(e.field(), c.field) << c.text << e.what();
    EXPECT_EQ(e.line(), 2) << c.text;  // every case puts the key on line 2
    EXPECT_EQ(e.file(), "bad.yaml");
  }
}

TEST(InflightConfigTest, MissingFileNamesIt) {
  const std::string path = ::testing::TempDir() + "no_such_inflight_config.yaml";
  try {
    LoadInflightConfig(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
  }
}

TEST(InflightConfigTest, RobustLossNames) {
  EXPECT_STREQ(RobustLossName(RobustLoss::kNone), "none");
  EXPECT_STREQ(RobustLossName(RobustLoss::kHuber), "huber");
  EXPECT_STREQ(RobustLossName(RobustLoss::kCauchy), "cauchy");
  EXPECT_EQ(ParseInflightConfig("batch: {loss: none}\n", "x.yaml").batch.loss, RobustLoss::kNone);
}

}  // namespace inflight_alignment_config_test
}  // namespace navtwin::inflight
