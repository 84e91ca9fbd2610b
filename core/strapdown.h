// Strapdown inertial mechanization in the local-level NED frame on IMU increments.
// The algorithm, its update order and the midpoint evaluation are derived in
// docs/strapdown.md; in short, for each sample k with increments (dtheta_k, dv_k) over
// (t_{k-1}, t_k]:
//   1. extrapolate position and velocity to the interval midpoint from the last step;
//   2. velocity: specific-force increment with the rotation and two-sample sculling
//      corrections, rotated to NED with the half-interval nav-frame rotation, plus the
//      gravity/Coriolis increment at the midpoint;
//   3. position: height, then latitude, then longitude with the average velocity and the
//      radii at the midpoint;
//   4. attitude: body rotation vector with the two-sample coning correction, nav-frame
//      rotation (Earth rate + transport rate) at the updated midpoint:
//        q_n_b(k) = Exp(-zeta_n) * q_n_b(k-1) * Exp(phi_b).
#pragma once

#include <optional>

#include <Eigen/Core>

#include "core/types.h"

namespace navtwin {

struct StrapdownOptions {
  /// Two-sample coning (attitude) and sculling (velocity) corrections; the rotation
  /// correction 0.5 dtheta x dv is always applied.
  bool coning_sculling = true;
  /// The free-inertial vertical channel is unstable (errors grow as exp(t / ~570 s)).
  /// When set, height is held at this value and the down velocity at 0, as a
  /// barometer-aided or horizontal-channel study would.
  std::optional<double> hold_height_m;
};

class Strapdown {
 public:
  explicit Strapdown(const NavState& initial, const StrapdownOptions& options = {});

  /// Advances the state over one IMU sample; the state's time becomes imu.t_s.
  /// Throws std::invalid_argument if imu.dt_s is not positive and finite.
  void Update(const ImuSample& imu);

  const NavState& state() const { return state_; }

  /// Replaces the state (e.g. error-state feedback) keeping the coning/sculling and
  /// midpoint-extrapolation history, which the correction does not invalidate.
  void SetState(const NavState& state) { state_ = state; }

 private:
  NavState state_;
  StrapdownOptions options_;
  // History of the previous step for the two-sample corrections and extrapolation.
  bool have_previous_ = false;
  Eigen::Vector3d prev_dtheta_b_rad_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d prev_dv_b_mps_ = Eigen::Vector3d::Zero();
  double prev_dt_s_ = 0.0;
  Eigen::Vector3d prev_delta_v_n_mps_ = Eigen::Vector3d::Zero();  // v_{k-1} - v_{k-2}
  double prev_delta_lat_rad_ = 0.0;                               // lat_{k-1} - lat_{k-2}
  double prev_delta_h_m_ = 0.0;
};

}  // namespace navtwin
