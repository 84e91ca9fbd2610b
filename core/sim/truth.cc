#include "core/sim/truth.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/rotation.h"

namespace navtwin::sim {
namespace {

// d(lat, lon, h)/dt for NED velocity v at (lat, h).
Eigen::Vector3d PositionRate(const wgs84::Geodetic& p, const Eigen::Vector3d& v_n) {
  return {v_n.x() / (wgs84::MeridianRadius(p.lat_rad) + p.h_m),
          v_n.y() / ((wgs84::PrimeVerticalRadius(p.lat_rad) + p.h_m) * std::cos(p.lat_rad)),
          -v_n.z()};
}

wgs84::Geodetic Add(const wgs84::Geodetic& p, const Eigen::Vector3d& d, double s) {
  return {p.lat_rad + s * d.x(), p.lon_rad + s * d.y(), p.h_m + s * d.z()};
}

// One RK4 step of the position ODE from t over h.
wgs84::Geodetic Rk4(const AnalyticTrajectory& tr, const wgs84::Geodetic& p, double t, double h) {
  const Eigen::Vector3d k1 = PositionRate(p, tr.Velocity_n_mps(t));
  const Eigen::Vector3d k2 = PositionRate(Add(p, k1, h / 2), tr.Velocity_n_mps(t + h / 2));
  const Eigen::Vector3d k3 = PositionRate(Add(p, k2, h / 2), tr.Velocity_n_mps(t + h / 2));
  const Eigen::Vector3d k4 = PositionRate(Add(p, k3, h), tr.Velocity_n_mps(t + h));
  return Add(p, k1 + 2.0 * k2 + 2.0 * k3 + k4, h / 6.0);
}

}  // namespace

TruthGenerator::TruthGenerator(const AnalyticTrajectory& trajectory, const wgs84::Geodetic& start,
                               double rate_hz)
    : trajectory_(trajectory), dt_s_(1.0 / rate_hz), position_(start) {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    throw std::invalid_argument("TruthGenerator: rate_hz must be positive and finite");
  }
  current_ = Sample(0.0, position_);
  // At the start, a one-sided difference over 1e-4 s (trajectories are defined for t >= 0).
  constexpr double kDiffStep_s = 1e-4;
  current_.alpha_ib_b_rad_s2 =
      (BodyKinematicsAt(trajectory_, kDiffStep_s, start.lat_rad, start.h_m).omega_ib_b_radps -
       current_.omega_ib_b_radps) / kDiffStep_s;
}

TruthSample TruthGenerator::Sample(double t, const wgs84::Geodetic& p) const {
  TruthSample s;
  s.t_s = t;
  s.state.t_s = t;
  s.state.lat_rad = p.lat_rad;
  s.state.lon_rad = p.lon_rad;
  s.state.h_m = p.h_m;
  const TrajectoryPoint point = trajectory_.PointAt(t);
  s.state.v_n_mps = point.v_n_mps;
  const Eigen::Vector3d& e = point.euler_rad;
  s.state.q_n_b = QuatFromEuler(e.x(), e.y(), e.z());
  const BodyKinematics k = BodyKinematicsAt(point, p.lat_rad, p.h_m);
  s.omega_ib_b_radps = k.omega_ib_b_radps;
  s.f_b_mps2 = k.f_b_mps2;
  s.a_n_mps2 = point.a_n_mps2;
  s.exact.t_s = t;
  return s;
}

const TruthSample& TruthGenerator::Next() {
  // 3-point Gauss-Legendre nodes on [0, 1] and weights.
  static const double c = std::sqrt(0.6) / 2.0;
  const double nodes[3] = {0.5 - c, 0.5, 0.5 + c};
  const double weights[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};

  const double t0 = k_ * dt_s_;
  const double t1 = (k_ + 1) * dt_s_;  // from the index: no accumulated rounding
  ImuSample inc;
  inc.t_s = t1;
  inc.dt_s = dt_s_;
  double t = t0;
  Eigen::Vector3d omega_nodes[3];
  for (int i = 0; i < 3; ++i) {
    const double tn = t0 + nodes[i] * dt_s_;
    position_ = Rk4(trajectory_, position_, t, tn - t);
    t = tn;
    const BodyKinematics kin = BodyKinematicsAt(trajectory_, tn, position_.lat_rad, position_.h_m);
    inc.dtheta_b_rad += weights[i] * dt_s_ * kin.omega_ib_b_radps;
    inc.dv_b_mps += weights[i] * dt_s_ * kin.f_b_mps2;
    omega_nodes[i] = kin.omega_ib_b_radps;
  }
  position_ = Rk4(trajectory_, position_, t, t1 - t);
  ++k_;
  current_ = Sample(t1, position_);
  current_.exact = inc;
  // Angular acceleration at t1: derivative of the quadratic through the angular rate at
  // the last two nodes and at t1 (error O(dt^2 |d3 omega/dt3|)).
  const double x0 = t0 + nodes[1] * dt_s_, x1 = t0 + nodes[2] * dt_s_, x2 = t1;
  current_.alpha_ib_b_rad_s2 = omega_nodes[1] * ((x2 - x1) / ((x0 - x1) * (x0 - x2))) +
                               omega_nodes[2] * ((x2 - x0) / ((x1 - x0) * (x1 - x2))) +
                               current_.omega_ib_b_radps * ((2 * x2 - x0 - x1) / ((x2 - x0) * (x2 - x1)));
  return current_;
}

}  // namespace navtwin::sim
