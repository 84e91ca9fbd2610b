#include "problems/ins/alignment.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/earth.h"
#include "core/leveling_model.h"
#include "core/rotation.h"

namespace navtwin::ins {
namespace {

// Limits for "clearly not static": the mean specific force must be gravity to within
// kMaxGravityDeviation (covers normal gravity's variation with latitude and height,
// ~0.06 m/s^2 below 10 km, plus large MEMS accelerometer biases), and the mean rate below
// kMaxRate = 2.9 deg/s (above the bias of any usable MEMS gyro).
constexpr double kMaxGravityDeviation_mps2 = 1.0;
constexpr double kMaxRate_radps = 0.05;

// Yaw of a body vector v whose levelled horizontal part, h = Ry(pitch) Rx(roll) v, is
// R_z(yaw)^T times a horizontal reference pointing north (Earth rate) or at the
// declination (magnetic field): yaw = atan2(-h_y, h_x) (docs in alignment.h).
double YawOfLevelledVector(const Eigen::Vector3d& v_b, double roll, double pitch, const char* what) {
  const Eigen::Matrix3d level = DcmFromEuler<double>(roll, pitch, 0.0);  // Ry(pitch) Rx(roll)
  const Eigen::Vector3d h = level * v_b;
  if (!(std::hypot(h.x(), h.y()) > 0.0)) {
    throw std::invalid_argument(std::string("StaticCoarseAlignment: the ") + what +
                                " has no horizontal component; heading undefined");
  }
  return std::atan2(-h.y(), h.x());
}

}  // namespace

Eigen::Quaterniond StaticCoarseAlignment(const std::vector<ImuSample>& samples, double lat_rad,
                                         const std::optional<Eigen::Vector3d>& m_b_uT,
                                         double declination_rad) {
  if (samples.empty()) throw std::invalid_argument("StaticCoarseAlignment: no IMU samples");
  Eigen::Vector3d sum_dtheta = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_dv = Eigen::Vector3d::Zero();
  double sum_dt = 0.0;
  for (const ImuSample& s : samples) {
    sum_dtheta += s.dtheta_b_rad;
    sum_dv += s.dv_b_mps;
    sum_dt += s.dt_s;
  }
  if (!(sum_dt > 0.0) || !std::isfinite(sum_dt) || !sum_dtheta.allFinite() || !sum_dv.allFinite()) {
    throw std::invalid_argument("StaticCoarseAlignment: the samples' total interval is not positive "
                                "or their increments are not finite");
  }
  const Eigen::Vector3d f = sum_dv / sum_dt;          // mean specific force, body
  const Eigen::Vector3d omega = sum_dtheta / sum_dt;  // mean angular rate, body
  const double g = wgs84::NormalGravity(lat_rad, 0.0);
  if (std::abs(f.norm() - g) > kMaxGravityDeviation_mps2 || omega.norm() > kMaxRate_radps) {
    throw std::invalid_argument(
        "StaticCoarseAlignment: the interval is not static (mean |f| = " + std::to_string(f.norm()) +
        " m/s^2, gravity " + std::to_string(g) + " m/s^2; mean |omega| = " +
        std::to_string(omega.norm()) + " rad/s)");
  }
  // At rest f_b = -R_b_n g_n = g (sin p, -cos p sin r, -cos p cos r).
  const leveling::RollPitch level = leveling::LevelFromSpecificForce(f);
  const double roll = level.roll_rad;
  const double pitch = level.pitch_rad;
  double yaw = 0.0;
  if (m_b_uT) {
    yaw = YawOfLevelledVector(*m_b_uT, roll, pitch, "magnetic field") + declination_rad;
  } else {
    // Gyrocompassing: only the direction of the Earth rate's horizontal part (north,
    // magnitude Omega cos lat) matters.
    yaw = YawOfLevelledVector(omega, roll, pitch, "mean angular rate");
  }
  return QuatFromEuler<double>(roll, pitch, WrapPi(yaw));
}

Eigen::Quaterniond AttitudeFromGnssVelocity(const Eigen::Vector3d& v_n_mps) {
  const double speed = std::hypot(v_n_mps.x(), v_n_mps.y());
  if (!(speed > 0.0) || !std::isfinite(speed)) {
    throw std::invalid_argument("AttitudeFromGnssVelocity: horizontal speed " +
                                std::to_string(speed) + " m/s gives no heading");
  }
  return QuatFromEuler<double>(0.0, 0.0, std::atan2(v_n_mps.y(), v_n_mps.x()));
}

void ImuPositionFromAntenna(const GnssSample& fix, const Eigen::Quaterniond& q_n_b,
                            const Eigen::Vector3d& lever_arm_b_m, NavState* nav) {
  const wgs84::Geodetic p =
      wgs84::NedToGeodetic(-(q_n_b * lever_arm_b_m), {fix.lat_rad, fix.lon_rad, fix.h_m});
  nav->lat_rad = p.lat_rad;
  nav->lon_rad = p.lon_rad;
  nav->h_m = p.h_m;
}

}  // namespace navtwin::ins
