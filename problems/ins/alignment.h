// Initial attitude for the GNSS/INS estimators: static coarse alignment (leveling from
// gravity, heading from gyrocompassing or a magnetometer) and a level attitude from the
// GNSS velocity direction. Frames: NED, body FRD, q_n_b maps body to NED.
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/types.h"

namespace navtwin::ins {

/// Static coarse alignment from body-axes IMU samples over a still interval: roll and
/// pitch from the mean specific force, heading from the mean angular rate (gyrocompassing;
/// only meaningful for gyros well below Earth rate noise) or, when m_b_uT is given
/// (calibrated, body axes), from the magnetometer with declination. Returns q_n_b.
/// At rest f_b = -R_b_n g_n = -g (-sin p, sin r cos p, cos r cos p), so
///   roll = atan2(-f_y, -f_z),  pitch = atan2(f_x, sqrt(f_y^2 + f_z^2)).
/// Heading: with the body vector v levelled by roll and pitch, h = R_y(p) R_x(r) v
/// (= R_z(yaw)^T v_n), a reference pointing north or at the declination gives
///   magnetometer: yaw = atan2(-h_y, h_x) + declination,
///   gyrocompass:  yaw = atan2(-h_y, h_x) (Earth rate points north, horizontally).
/// Throws std::invalid_argument when the samples are empty, have non-positive total
/// duration, or are clearly not static (|mean f| differs from normal gravity at lat_rad by
/// more than 1 m/s^2 or |mean omega| exceeds 0.05 rad/s), or the heading reference has no
/// horizontal component.
Eigen::Quaterniond StaticCoarseAlignment(const std::vector<ImuSample>& samples, double lat_rad,
                                         const std::optional<Eigen::Vector3d>& m_b_uT,
                                         double declination_rad);

/// Level attitude (roll = pitch = 0) with the heading of the horizontal velocity,
/// yaw = atan2(v_E, v_N). Throws std::invalid_argument when the horizontal speed is zero
/// or not finite.
Eigen::Quaterniond AttitudeFromGnssVelocity(const Eigen::Vector3d& v_n_mps);

/// The IMU reference point from an antenna fix: p_imu = p_ant - R_n_b l_b (exact, through
/// the local NED frame of the fix); sets nav's lat_rad, lon_rad, h_m.
void ImuPositionFromAntenna(const GnssSample& fix, const Eigen::Quaterniond& q_n_b,
                            const Eigen::Vector3d& lever_arm_b_m, NavState* nav);

}  // namespace navtwin::ins
