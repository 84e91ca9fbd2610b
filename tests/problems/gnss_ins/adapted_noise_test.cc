// AdaptNoise (problems/gnss_ins/adapted_noise.h): each adapted group scales its own
// configuration value by its sigma scale; groups not adapted leave theirs.
#include <gtest/gtest.h>

#include "core/units.h"
#include "problems/gnss_ins/adapted_noise.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_adapted_noise_test {

ResidualStats Adapted(double scale) {
  ResidualStats r;
  r.sigma_scale = scale;
  r.adapted = true;
  return r;
}

TEST(AdaptNoise, EachGroupScalesItsValue) {
  GnssInsConfig c;
  c.imu_noise.gyro_arw_rad_per_sqrt_s = 0.5 * kDegPerSqrtHour_radpsqrts;
  c.imu_noise.accel_vrw_mps_per_sqrt_s = 0.1 * kMpsPerSqrtHour_mpspsqrts;
  c.imu_noise.gyro_bias_std_radps = 10.0 * kDegPerHour_radps;
  c.mag.noise_uT = 0.5;
  c.imu_noise.accel_scale_std = 1000.0 * kPpm;
  std::map<std::string, ResidualStats> residuals;
  residuals["imu_rotation"] = Adapted(3.0);
  residuals["imu_velocity_position"] = Adapted(2.0);
  residuals["gnss_position_v"] = Adapted(1.5);
  residuals["gnss_velocity_h"] = Adapted(0.5);
  residuals["mag"] = Adapted(0.2);
  residuals["accel_scale_process"] = Adapted(4.0);
  ResidualStats not_adapted;
  not_adapted.sigma_scale = 7.0;  // e.g. a group below the redundancy threshold: ignored
  residuals["gyro_bias_process"] = not_adapted;
  const AdaptedNoise a = AdaptNoise(c, residuals);
  EXPECT_TRUE(a.changed);
  EXPECT_EQ(a.lines.size(), 6u);
  EXPECT_DOUBLE_EQ(a.config.imu_noise.gyro_arw_rad_per_sqrt_s, 1.5 * kDegPerSqrtHour_radpsqrts);
  EXPECT_DOUBLE_EQ(a.config.imu_noise.accel_vrw_mps_per_sqrt_s, 0.2 * kMpsPerSqrtHour_mpspsqrts);
  EXPECT_DOUBLE_EQ(a.config.imu_noise.gyro_bias_std_radps, c.imu_noise.gyro_bias_std_radps);
  EXPECT_DOUBLE_EQ(a.config.gnss.pos_sigma_scale_h, 1.0);
  EXPECT_DOUBLE_EQ(a.config.gnss.pos_sigma_scale_v, 1.5);
  EXPECT_DOUBLE_EQ(a.config.gnss.vel_sigma_scale_h, 0.5);
  EXPECT_DOUBLE_EQ(a.config.mag.noise_uT, 0.1);
  EXPECT_DOUBLE_EQ(a.config.imu_noise.accel_scale_std, 4000.0 * kPpm);
  EXPECT_NE(a.lines.front().find("gyro ARW"), std::string::npos);
  EXPECT_NE(a.lines.front().find("1.5 deg/sqrt(h)"), std::string::npos) << a.lines.front();
}

TEST(AdaptNoise, NothingAdaptedLeavesTheConfiguration) {
  GnssInsConfig c;
  std::map<std::string, ResidualStats> residuals;
  residuals["imu_rotation"] = ResidualStats{};
  const AdaptedNoise a = AdaptNoise(c, residuals);
  EXPECT_FALSE(a.changed);
  EXPECT_TRUE(a.lines.empty());
  EXPECT_DOUBLE_EQ(a.config.imu_noise.gyro_arw_rad_per_sqrt_s, c.imu_noise.gyro_arw_rad_per_sqrt_s);
}

}  // namespace gnss_ins_adapted_noise_test
}  // namespace navtwin::gnss_ins
