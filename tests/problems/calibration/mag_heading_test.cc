// The attitude helpers and the heading-error score of calibrate-mag
// (problems/calibration/mag_heading.h) and the record interpolation they use (NavAt).
#include "problems/calibration/mag_heading.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "problems/ins/nav_error.h"

namespace navtwin::calibration {
namespace calibration_mag_heading_test {

NavState StateAt(double t_s, double yaw_rad) {
  NavState s;
  s.t_s = t_s;
  s.q_n_b = QuatFromEuler(0.1, -0.2, yaw_rad);
  return s;
}

TEST(MagHeadingTest, NavAtInterpolatesInsideAndRefusesOutside) {
  const std::vector<NavState> nav = {StateAt(0.0, 0.0), StateAt(1.0, 0.4)};
  ASSERT_FALSE(NavAt(nav, -0.1).has_value());
  ASSERT_FALSE(NavAt(nav, 1.1).has_value());
  ASSERT_TRUE(NavAt(nav, 1.0 + 1e-10, 1e-9).has_value());  // the end, within the tolerance
  // Halfway between two attitudes that differ only in yaw: the yaw is halfway (slerp about
  // one axis is linear in the angle); 1e-12 rad is rounding.
  const std::optional<Eigen::Vector3d> euler = EulerAt(nav, 0.5);
  ASSERT_TRUE(euler.has_value());
  EXPECT_NEAR((*euler)[0], 0.1, 1e-12);
  EXPECT_NEAR((*euler)[1], -0.2, 1e-12);
  EXPECT_NEAR((*euler)[2], 0.2, 1e-12);
  EXPECT_NEAR((*EulerAt(nav, 1.0))[2], 0.4, 1e-12);
}

TEST(MagHeadingTest, AccelerometerLevelsTheMeanSpecificForce) {
  // A static IMU at roll 0.1, pitch -0.2: f_b = R_b_n (0, 0, -g).
  const Eigen::Vector3d euler(0.1, -0.2, 0.7);
  const Eigen::Vector3d f_b = DcmFromEuler(euler(0), euler(1), euler(2)).transpose() * Eigen::Vector3d(0.0, 0.0, -9.81);
  std::vector<ImuSample> imu;
  for (int k = 1; k <= 100; ++k) {
    ImuSample s;
    s.t_s = 0.01 * k;
    s.dt_s = 0.01;
    s.dv_b_mps = f_b * s.dt_s;
    imu.push_back(s);
  }
  const AccelerometerLevel level(imu, 0.05);
  const std::optional<Eigen::Vector2d> rp = level.At(0.5);
  ASSERT_TRUE(rp.has_value());
  EXPECT_NEAR((*rp)(0), 0.1, 1e-12);  // exact data: rounding only
  EXPECT_NEAR((*rp)(1), -0.2, 1e-12);
  EXPECT_FALSE(level.At(2.0).has_value());
}

TEST(MagHeadingTest, HeadingErrorsBeforeAndAfterAHardIronCorrection) {
  // Level samples all round the compass, a field of 20 uT north horizontal plus 40 uT down,
  // hard iron (8, -5, 0) uT. With the calibration the heading is exact; without it is not.
  const Eigen::Vector3d m_n(20.0, 0.0, 40.0), h(8.0, -5.0, 0.0);
  std::vector<MagSample> mag;
  std::vector<std::optional<Eigen::Vector3d>> euler;
  for (int k = 0; k < 36; ++k) {
    const Eigen::Vector3d e(0.0, 0.0, WrapPi(k * 10.0 * kDegToRad));
    MagSample s;
    s.t_s = k;
    s.m_b_uT = DcmFromEuler(e(0), e(1), e(2)).transpose() * m_n + h;
    mag.push_back(s);
    euler.push_back(e);
  }
  euler[3].reset();  // a sample without reference attitude is not scored
  MagCalibration c;
  c.hard_iron_uT = h;
  c.method = "ellipsoid";
  const HeadingErrors e = MagHeadingErrors(mag, euler, c, false, 0.0);
  EXPECT_EQ(e.samples, 35);
  EXPECT_LT(e.after_deg, 1e-9);    // exact data
  EXPECT_GT(e.before_deg, 10.0);   // 9.4 uT of hard iron against 20 uT horizontal
  EXPECT_DOUBLE_EQ(MedianInterval_s(mag), 1.0);
}

TEST(MagHeadingTest, SampleAttitudesFromNavAccelerometerOrLevel) {
  std::vector<MagSample> mag(3);
  for (int i = 0; i < 3; ++i) mag[i].t_s = 0.5 * i;  // 0, 0.5, 1.0 s
  mag[2].t_s = 3.0;                                   // outside both records below

  const std::vector<NavState> nav = {StateAt(0.0, 0.0), StateAt(1.0, 0.4)};
  const MagSampleAttitudes from_nav = AttitudesFromNav(mag, nav);
  EXPECT_EQ(from_nav.source, "truth");
  ASSERT_EQ(from_nav.euler_rad.size(), 3u);
  ASSERT_TRUE(from_nav.euler_rad[1].has_value());
  EXPECT_NEAR((*from_nav.euler_rad[1])[2], 0.2, 1e-12);
  EXPECT_NEAR((*from_nav.roll_pitch_rad[1])[0], 0.1, 1e-12);
  EXPECT_NEAR((*from_nav.roll_pitch_rad[1])[1], -0.2, 1e-12);
  EXPECT_FALSE(from_nav.euler_rad[2].has_value());
  EXPECT_FALSE(from_nav.roll_pitch_rad[2].has_value());

  const Eigen::Vector3d f_b = DcmFromEuler(0.1, -0.2, 0.0).transpose() * Eigen::Vector3d(0.0, 0.0, -9.81);
  std::vector<ImuSample> imu;
  for (int k = 1; k <= 100; ++k) {
    ImuSample s;
    s.t_s = 0.01 * k;
    s.dt_s = 0.01;
    s.dv_b_mps = f_b * s.dt_s;
    imu.push_back(s);
  }
  const MagSampleAttitudes from_imu = AttitudesFromAccelerometer(mag, imu);
  EXPECT_EQ(from_imu.source, "imu accelerometer");
  ASSERT_EQ(from_imu.euler_rad.size(), 3u);
  EXPECT_FALSE(from_imu.euler_rad[1].has_value());  // no yaw from an accelerometer
  ASSERT_TRUE(from_imu.roll_pitch_rad[1].has_value());
  EXPECT_NEAR((*from_imu.roll_pitch_rad[1])[0], 0.1, 1e-12);
  EXPECT_NEAR((*from_imu.roll_pitch_rad[1])[1], -0.2, 1e-12);
  EXPECT_FALSE(from_imu.roll_pitch_rad[2].has_value());

  const MagSampleAttitudes level = LevelAttitudes(mag);
  EXPECT_EQ(level.source, "level (assumed)");
  ASSERT_EQ(level.roll_pitch_rad.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_FALSE(level.euler_rad[i].has_value());
    ASSERT_TRUE(level.roll_pitch_rad[i].has_value());
    EXPECT_EQ(level.roll_pitch_rad[i]->norm(), 0.0);
  }
}

}  // namespace calibration_mag_heading_test
}  // namespace navtwin::calibration
