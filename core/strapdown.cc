#include "core/strapdown.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/earth.h"
#include "core/rotation.h"

namespace navtwin {
namespace {

// Coefficients of the rotation compensation for a body rotating at constant rate by
// theta over the interval: integral of Exp(alpha(t)) f dt = dv + A theta x dv +
// B theta x (theta x dv), A = (1 - cos t)/t^2, B = (1 - sin(t)/t)/t^2. Series below
// t^2 = 1e-4, where they are exact to double precision.
double RotationCompensationA(double t_sq) {
  if (t_sq < 1e-4) return 0.5 - t_sq / 24.0 + t_sq * t_sq / 720.0;
  const double t = std::sqrt(t_sq);
  return (1.0 - std::cos(t)) / t_sq;
}

double RotationCompensationB(double t_sq) {
  if (t_sq < 1e-4) return 1.0 / 6.0 - t_sq / 120.0 + t_sq * t_sq / 5040.0;
  const double t = std::sqrt(t_sq);
  return (1.0 - std::sin(t) / t) / t_sq;
}

}  // namespace

Strapdown::Strapdown(const NavState& initial, const StrapdownOptions& options)
    : state_(initial), options_(options) {
  state_.q_n_b.normalize();
  if (options_.hold_height_m) {
    state_.h_m = *options_.hold_height_m;
    state_.v_n_mps.z() = 0.0;
  }
}

void Strapdown::Update(const ImuSample& imu) {
  const double dt = imu.dt_s;
  if (!(dt > 0.0) || !std::isfinite(dt)) {
    throw std::invalid_argument("Strapdown::Update: sample at t = " + std::to_string(imu.t_s) +
                                " s has a non-positive interval dt_s = " + std::to_string(dt));
  }
  const Eigen::Vector3d& dtheta = imu.dtheta_b_rad;
  const Eigen::Vector3d& dv = imu.dv_b_mps;
  const bool two_sample = options_.coning_sculling && have_previous_;

  const double lat0 = state_.lat_rad;
  const double h0 = state_.h_m;
  const Eigen::Vector3d v0 = state_.v_n_mps;

  // 1. Midpoint extrapolation from the last step's change, scaled for a changed interval.
  const double scale = have_previous_ ? 0.5 * dt / prev_dt_s_ : 0.0;
  const double lat_mid_x = lat0 + scale * prev_delta_lat_rad_;
  const double h_mid_x = h0 + scale * prev_delta_h_m_;
  const Eigen::Vector3d v_mid_x = v0 + scale * prev_delta_v_n_mps_;
  const Eigen::Vector3d w_ie_n = wgs84::EarthRateNed(lat_mid_x);
  const Eigen::Vector3d w_en_n = wgs84::TransportRateNed(lat_mid_x, h_mid_x, v_mid_x);
  const Eigen::Vector3d zeta_x = (w_ie_n + w_en_n) * dt;

  // 2. Velocity. Specific-force increment in the body frame at t_{k-1}: rotation
  //    compensation to second order in the rotation angle (exact for constant rate and
  //    specific force over the interval, docs/strapdown.md) and the two-sample sculling
  //    correction.
  const double theta_sq = dtheta.squaredNorm();
  const Eigen::Vector3d theta_x_dv = dtheta.cross(dv);
  Eigen::Vector3d dv_sf_b = dv + RotationCompensationA(theta_sq) * theta_x_dv +
                            RotationCompensationB(theta_sq) * dtheta.cross(theta_x_dv);
  if (two_sample) {
    dv_sf_b += (prev_dtheta_b_rad_.cross(dv) + prev_dv_b_mps_.cross(dtheta)) / 12.0;
  }
  const Eigen::Vector3d dv_sf_n =
      state_.q_n_b * dv_sf_b - 0.5 * zeta_x.cross(state_.q_n_b * dv_sf_b);
  const Eigen::Vector3d g_n = wgs84::GravityNed(lat_mid_x, h_mid_x);
  const Eigen::Vector3d dv_gcor_n = (g_n - (2.0 * w_ie_n + w_en_n).cross(v_mid_x)) * dt;
  Eigen::Vector3d v1 = v0 + dv_sf_n + dv_gcor_n;
  if (options_.hold_height_m) v1.z() = 0.0;

  // 3. Position with the average velocity: height, latitude, longitude.
  const Eigen::Vector3d v_avg = 0.5 * (v0 + v1);
  const double h1 = options_.hold_height_m ? *options_.hold_height_m : h0 - v_avg.z() * dt;
  const double h_mid = 0.5 * (h0 + h1);
  const double lat1 = lat0 + v_avg.x() * dt / (wgs84::MeridianRadius(lat_mid_x) + h_mid);
  const double lat_mid = 0.5 * (lat0 + lat1);
  const double lon1 = state_.lon_rad + v_avg.y() * dt /
                                           ((wgs84::PrimeVerticalRadius(lat_mid) + h_mid) *
                                            std::cos(lat_mid));

  // 4. Attitude: body rotation with the coning correction; nav-frame rotation at the
  //    midpoint of the updated position and velocity.
  Eigen::Vector3d phi_b = dtheta;
  if (two_sample) phi_b += prev_dtheta_b_rad_.cross(dtheta) / 12.0;
  const Eigen::Vector3d zeta_n =
      (wgs84::EarthRateNed(lat_mid) + wgs84::TransportRateNed(lat_mid, h_mid, v_avg)) * dt;
  Eigen::Quaterniond q1 =
      QuatFromRotVec<double>(-zeta_n) * state_.q_n_b * QuatFromRotVec<double>(phi_b);
  q1.normalize();

  prev_delta_v_n_mps_ = v1 - v0;
  prev_delta_lat_rad_ = lat1 - lat0;
  prev_delta_h_m_ = h1 - h0;
  prev_dtheta_b_rad_ = dtheta;
  prev_dv_b_mps_ = dv;
  prev_dt_s_ = dt;
  have_previous_ = true;

  state_.t_s = imu.t_s;
  state_.lat_rad = lat1;
  state_.lon_rad = lon1;
  state_.h_m = h1;
  state_.v_n_mps = v1;
  state_.q_n_b = q1;
}

}  // namespace navtwin
