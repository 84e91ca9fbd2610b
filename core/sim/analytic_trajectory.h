// Trajectories given by analytic attitude and velocity, and the exact IMU increments and
// truth states they imply. The simulator issue builds segment-based scenarios on this
// interface; the foundation uses it for the built-in demonstration flight.
//
// Truth kinematics (NED, body FRD, see docs/strapdown.md):
//   omega_nb_b = E(roll, pitch) * (roll', pitch', yaw')          (ZYX Euler rates)
//   omega_ib_b = omega_nb_b + R_b_n (omega_ie_n + omega_en_n)
//   f_b        = R_b_n (a_n + (2 omega_ie_n + omega_en_n) x v_n - g_n)
// The increments dtheta = integral of omega_ib_b dt and dv = integral of f_b dt over each
// sample interval are what an ideal integrating IMU outputs (core/sim/truth.h computes
// them).
#pragma once

#include <functional>

#include <Eigen/Core>

#include "core/earth.h"
#include "core/types.h"

namespace navtwin::sim {

/// Everything a trajectory says about one instant.
struct TrajectoryPoint {
  Eigen::Vector3d euler_rad;         ///< (roll, pitch, yaw) of R_n_b
  Eigen::Vector3d euler_rate_radps;  ///< their time derivatives
  Eigen::Vector3d v_n_mps;           ///< velocity over the Earth, NED
  Eigen::Vector3d a_n_mps2;          ///< its time derivative
};

class AnalyticTrajectory {
 public:
  virtual ~AnalyticTrajectory() = default;
  /// The four quantities below at once; trajectories whose four share work override it
  /// (the truth generator calls it a dozen times per sample).
  virtual TrajectoryPoint PointAt(double t_s) const {
    return {Euler_rad(t_s), EulerRate_radps(t_s), Velocity_n_mps(t_s), Acceleration_n_mps2(t_s)};
  }
  /// (roll, pitch, yaw) of R_n_b in rad and their time derivatives in rad/s.
  virtual Eigen::Vector3d Euler_rad(double t_s) const = 0;
  virtual Eigen::Vector3d EulerRate_radps(double t_s) const = 0;
  /// Velocity over the Earth in NED (m/s) and its time derivative (m/s^2).
  virtual Eigen::Vector3d Velocity_n_mps(double t_s) const = 0;
  virtual Eigen::Vector3d Acceleration_n_mps2(double t_s) const = 0;
};

/// Angular rate and specific force of the trajectory at time t for position (lat, h).
struct BodyKinematics {
  Eigen::Vector3d omega_ib_b_radps;
  Eigen::Vector3d f_b_mps2;
};
BodyKinematics BodyKinematicsAt(const AnalyticTrajectory& trajectory, double t_s, double lat_rad,
                                double h_m);
/// The same from a trajectory point already evaluated.
BodyKinematics BodyKinematicsAt(const TrajectoryPoint& point, double lat_rad, double h_m);

/// Samples the trajectory at rate_hz from t = 0 (start position `start`) for duration_s.
/// `emit` receives, for every sample k >= 1, the exact increments over (t_{k-1}, t_k]
/// and the truth state at t_k; it is first called once with the initial truth state and
/// an ImuSample with dt_s = 0 (no increment).
void SynthesizeImu(const AnalyticTrajectory& trajectory, const wgs84::Geodetic& start,
                   double rate_hz, double duration_s,
                   const std::function<void(const ImuSample&, const NavState&)>& emit);

/// The built-in demonstration flight (10 min is its natural length): a fixed-wing-like
/// cruise at 20-40 m/s with wing rock (+-11 deg roll, 60 s period), gentle pitch changes,
/// heading sweeps of +-34 deg and climbs and descents of 2 m/s.
class DemoFlight : public AnalyticTrajectory {
 public:
  Eigen::Vector3d Euler_rad(double t_s) const override;
  Eigen::Vector3d EulerRate_radps(double t_s) const override;
  Eigen::Vector3d Velocity_n_mps(double t_s) const override;
  Eigen::Vector3d Acceleration_n_mps2(double t_s) const override;
};

}  // namespace navtwin::sim
