// Sample and state types shared by readers, mechanization, filters and batch problems.
// SI units inside the code, radians for angles; frames: navigation NED, body FRD.
#pragma once

#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace navtwin {

/// One IMU output: increments over the interval (t_s - dt_s, t_s], in the IMU axes.
/// dt_s comes from the time tags (real IMUs jitter; never assumed constant).
struct ImuSample {
  double t_s = 0.0;
  double dt_s = 0.0;
  Eigen::Vector3d dtheta_b_rad = Eigen::Vector3d::Zero();  ///< integral of omega_ib_b
  Eigen::Vector3d dv_b_mps = Eigen::Vector3d::Zero();      ///< integral of specific force f_b
};

/// GNSS position (and optionally velocity) solution at the antenna.
struct GnssSample {
  double t_s = 0.0;
  int gps_week = -1;  ///< GPS week of t_s where t_s is GPS seconds of week; -1 unknown
  double lat_rad = 0.0;
  double lon_rad = 0.0;
  double h_m = 0.0;  ///< height above the WGS84 ellipsoid
  Eigen::Vector3d pos_std_ned_m = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  bool has_velocity = false;
  Eigen::Vector3d v_n_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d vel_std_ned_mps = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  int quality = 0;   ///< RTKLIB Q (1 fix, 2 float, 4 DGPS, 5 single) or PX4 fix_type; 0 unknown
  int num_sats = 0;  ///< 0 unknown
};

/// Magnetometer vector in the sensor axes.
struct MagSample {
  double t_s = 0.0;
  Eigen::Vector3d m_b_uT = Eigen::Vector3d::Zero();
};

/// Barometer: pressure and/or the barometric altitude it implies. NaN where absent.
struct BaroSample {
  double t_s = 0.0;
  double pressure_pa = std::numeric_limits<double>::quiet_NaN();
  double altitude_m = std::numeric_limits<double>::quiet_NaN();
  double temperature_degC = std::numeric_limits<double>::quiet_NaN();
};

/// Navigation state: geodetic position, NED velocity, attitude q_n_b (body FRD -> NED).
struct NavState {
  double t_s = 0.0;  ///< seconds (of the GPS week where gps_week >= 0)
  int gps_week = -1; ///< -1 when the time scale has no week (simulated or relative time)
  double lat_rad = 0.0;
  double lon_rad = 0.0;
  double h_m = 0.0;
  Eigen::Vector3d v_n_mps = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_n_b = Eigen::Quaterniond::Identity();
};

}  // namespace navtwin
