#include "problems/ins/alignment.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/units.h"

namespace navtwin::ins {
namespace ins_alignment_test {


// Exact increments of an IMU at rest on the Earth at latitude lat, height 0, attitude R:
// omega_b = R^T omega_ie_n, f_b = -R^T g_n (specific force points up, f_z ~ -g when
// level); 100 Hz with a little jitter in dt.
std::vector<ImuSample> StaticSamples(const Eigen::Matrix3d& R_n_b, double lat_rad, double duration_s) {
  std::vector<ImuSample> out;
  double t = 0.0;
  for (int k = 0; t < duration_s; ++k) {
    ImuSample s;
    s.dt_s = 0.01 * (1.0 + 0.05 * std::sin(0.7 * k));
    t += s.dt_s;
    s.t_s = t;
    s.dtheta_b_rad = R_n_b.transpose() * wgs84::EarthRateNed(lat_rad) * s.dt_s;
    s.dv_b_mps = -R_n_b.transpose() * wgs84::GravityNed(lat_rad, 0.0) * s.dt_s;
    out.push_back(s);
  }
  return out;
}

// Magnetic field in NED with declination D (east of north) and inclination I (down), uT.
Eigen::Vector3d FieldNed(double declination_rad, double inclination_rad) {
  const double B = 48.0;
  return B * Eigen::Vector3d(std::cos(inclination_rad) * std::cos(declination_rad),
                             std::cos(inclination_rad) * std::sin(declination_rad),
                             std::sin(inclination_rad));
}

struct Attitude { double roll, pitch, yaw; };

// Attitudes in every quadrant of roll and yaw, both pitch signs, up to 170 deg roll.
const Attitude kAttitudes[] = {
    {0.0, 0.0, 0.0},           {5 * kDegToRad, -3 * kDegToRad, 30 * kDegToRad},  {-20 * kDegToRad, 10 * kDegToRad, -120 * kDegToRad},
    {100 * kDegToRad, 40 * kDegToRad, 175 * kDegToRad}, {-170 * kDegToRad, -60 * kDegToRad, -60 * kDegToRad}, {45 * kDegToRad, 80 * kDegToRad, 91 * kDegToRad},
};

// The Euler angles of the result vs the truth; the comparison through the rotation
// (|Log(R_true R_est^T)|) avoids angle wrapping. Exact data: only rounding remains, ~1e-15
// in roll/pitch; the gyrocompass heading is a ratio of Earth-rate components of 5e-5 rad/s
// computed from sums of 1000 samples, still ~1e-12. Tolerance 1e-9 as required.
TEST(StaticCoarseAlignment, GyrocompassingRecoversKnownAttitudes) {
  const double lat = 47.0 * kDegToRad;
  for (const Attitude& a : kAttitudes) {
    const Eigen::Matrix3d R = DcmFromEuler(a.roll, a.pitch, a.yaw);
    const Eigen::Quaterniond q = StaticCoarseAlignment(StaticSamples(R, lat, 10.0), lat, std::nullopt, 0.0);
    const Eigen::Vector3d e = EulerFromQuat(q);
    EXPECT_NEAR(e.x(), a.roll, 1e-9) << a.roll / kDegToRad << " " << a.pitch / kDegToRad << " " << a.yaw / kDegToRad;
    EXPECT_NEAR(e.y(), a.pitch, 1e-9);
    EXPECT_LT(AttitudeError(QuatFromEuler(a.roll, a.pitch, a.yaw), q).norm(), 1e-9);
  }
}

TEST(StaticCoarseAlignment, MagnetometerHeadingWithDeclination) {
  const double lat = -33.0 * kDegToRad, declination = -11.0 * kDegToRad;
  for (double inclination : {-55.0 * kDegToRad, 65.0 * kDegToRad}) {
    for (const Attitude& a : kAttitudes) {
      const Eigen::Matrix3d R = DcmFromEuler(a.roll, a.pitch, a.yaw);
      const Eigen::Vector3d m_b = R.transpose() * FieldNed(declination, inclination);
      const Eigen::Quaterniond q = StaticCoarseAlignment(StaticSamples(R, lat, 2.0), lat, m_b, declination);
      EXPECT_LT(AttitudeError(QuatFromEuler(a.roll, a.pitch, a.yaw), q).norm(), 1e-9)
          << a.roll / kDegToRad << " " << a.pitch / kDegToRad << " " << a.yaw / kDegToRad;
    }
  }
  // Without the declination the heading is off by exactly the declination.
  const Eigen::Matrix3d R = DcmFromEuler(0.1, -0.05, 1.0);
  const Eigen::Vector3d m_b = R.transpose() * FieldNed(declination, 60 * kDegToRad);
  const Eigen::Quaterniond q = StaticCoarseAlignment(StaticSamples(R, lat, 1.0), lat, m_b, 0.0);
  EXPECT_NEAR(EulerFromQuat(q).z(), 1.0 - declination, 1e-12);
}

TEST(StaticCoarseAlignment, SignsOfLevelingFromSpecificForce) {
  // Nose up 10 deg: the accelerometer x axis senses +g sin(10 deg) (f_b ~ -g_b at rest).
  const double lat = 0.5;
  const auto samples = StaticSamples(DcmFromEuler(0.0, 10 * kDegToRad, 0.0), lat, 1.0);
  EXPECT_GT(samples[0].dv_b_mps.x(), 0.0);
  EXPECT_NEAR(EulerFromQuat(StaticCoarseAlignment(samples, lat, std::nullopt, 0.0)).y(), 10 * kDegToRad, 1e-12);
  // Right wing down 10 deg: f_y = -g cos(p) sin(r) < 0 and the result is roll = +10 deg.
  const auto rolled = StaticSamples(DcmFromEuler(10 * kDegToRad, 0.0, 0.0), lat, 1.0);
  EXPECT_LT(rolled[0].dv_b_mps.y(), 0.0);
  EXPECT_NEAR(EulerFromQuat(StaticCoarseAlignment(rolled, lat, std::nullopt, 0.0)).x(), 10 * kDegToRad, 1e-12);
}

TEST(StaticCoarseAlignment, RejectsEmptyAndMovingData) {
  EXPECT_THROW(StaticCoarseAlignment({}, 0.5, std::nullopt, 0.0), std::invalid_argument);
  auto accelerating = StaticSamples(Eigen::Matrix3d::Identity(), 0.5, 1.0);
  // 6 m/s^2 forward: |f| = 11.5 m/s^2. (A smaller steady acceleration cannot be told
  // from a tilt by a static alignment.)
  for (ImuSample& s : accelerating) s.dv_b_mps.x() += 6.0 * s.dt_s;
  EXPECT_THROW(StaticCoarseAlignment(accelerating, 0.5, std::nullopt, 0.0), std::invalid_argument);
  auto turning = StaticSamples(Eigen::Matrix3d::Identity(), 0.5, 1.0);
  for (ImuSample& s : turning) s.dtheta_b_rad.z() += 0.2 * s.dt_s;  // 11 deg/s
  EXPECT_THROW(StaticCoarseAlignment(turning, 0.5, std::nullopt, 0.0), std::invalid_argument);
  auto zero_dt = StaticSamples(Eigen::Matrix3d::Identity(), 0.5, 0.05);
  for (ImuSample& s : zero_dt) s.dt_s = 0.0;
  EXPECT_THROW(StaticCoarseAlignment(zero_dt, 0.5, std::nullopt, 0.0), std::invalid_argument);
}

TEST(AttitudeFromGnssVelocity, LevelWithVelocityHeading) {
  const Eigen::Vector3d e = EulerFromQuat(AttitudeFromGnssVelocity(Eigen::Vector3d(-3.0, -4.0, 1.0)));
  EXPECT_NEAR(e.x(), 0.0, 1e-15);
  EXPECT_NEAR(e.y(), 0.0, 1e-15);
  EXPECT_NEAR(e.z(), std::atan2(-4.0, -3.0), 1e-15);
  // East: heading +90 deg.
  EXPECT_NEAR(EulerFromQuat(AttitudeFromGnssVelocity(Eigen::Vector3d(0.0, 5.0, 0.0))).z(), 90 * kDegToRad, 1e-15);
  EXPECT_THROW(AttitudeFromGnssVelocity(Eigen::Vector3d(0.0, 0.0, 3.0)), std::invalid_argument);
}

}  // namespace ins_alignment_test
}  // namespace navtwin::ins
