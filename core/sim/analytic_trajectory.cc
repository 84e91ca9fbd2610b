#include "core/sim/analytic_trajectory.h"

#include <cmath>
#include <stdexcept>

#include "core/rotation.h"

namespace navtwin::sim {
namespace {

struct GeoPoint {
  double lat_rad, lon_rad, h_m;
};

// d(lat, lon, h)/dt for NED velocity v at (lat, h).
GeoPoint PositionRate(const GeoPoint& p, const Eigen::Vector3d& v_n) {
  return {v_n.x() / (wgs84::MeridianRadius(p.lat_rad) + p.h_m),
          v_n.y() / ((wgs84::PrimeVerticalRadius(p.lat_rad) + p.h_m) * std::cos(p.lat_rad)),
          -v_n.z()};
}

GeoPoint Add(const GeoPoint& p, const GeoPoint& d, double s) {
  return {p.lat_rad + s * d.lat_rad, p.lon_rad + s * d.lon_rad, p.h_m + s * d.h_m};
}

// One RK4 step of the position ODE from t over h.
GeoPoint Rk4(const AnalyticTrajectory& tr, const GeoPoint& p, double t, double h) {
  const GeoPoint k1 = PositionRate(p, tr.Velocity_n_mps(t));
  const GeoPoint k2 = PositionRate(Add(p, k1, h / 2), tr.Velocity_n_mps(t + h / 2));
  const GeoPoint k3 = PositionRate(Add(p, k2, h / 2), tr.Velocity_n_mps(t + h / 2));
  const GeoPoint k4 = PositionRate(Add(p, k3, h), tr.Velocity_n_mps(t + h));
  return {p.lat_rad + h / 6 * (k1.lat_rad + 2 * k2.lat_rad + 2 * k3.lat_rad + k4.lat_rad),
          p.lon_rad + h / 6 * (k1.lon_rad + 2 * k2.lon_rad + 2 * k3.lon_rad + k4.lon_rad),
          p.h_m + h / 6 * (k1.h_m + 2 * k2.h_m + 2 * k3.h_m + k4.h_m)};
}

NavState TruthState(const AnalyticTrajectory& tr, double t, const GeoPoint& p) {
  NavState s;
  s.t_s = t;
  s.lat_rad = p.lat_rad;
  s.lon_rad = p.lon_rad;
  s.h_m = p.h_m;
  s.v_n_mps = tr.Velocity_n_mps(t);
  const Eigen::Vector3d e = tr.Euler_rad(t);
  s.q_n_b = QuatFromEuler(e.x(), e.y(), e.z());
  return s;
}

}  // namespace

BodyKinematics BodyKinematicsAt(const AnalyticTrajectory& tr, double t, double lat_rad, double h_m) {
  const Eigen::Vector3d e = tr.Euler_rad(t);
  const Eigen::Vector3d de = tr.EulerRate_rad_s(t);
  const double sr = std::sin(e.x()), cr = std::cos(e.x());
  const double sp = std::sin(e.y()), cp = std::cos(e.y());
  const Eigen::Vector3d omega_nb_b(de.x() - de.z() * sp, de.y() * cr + de.z() * sr * cp,
                                   -de.y() * sr + de.z() * cr * cp);
  const Eigen::Matrix3d R_b_n = DcmFromEuler(e.x(), e.y(), e.z()).transpose();
  const Eigen::Vector3d v_n = tr.Velocity_n_mps(t);
  const Eigen::Vector3d w_ie = wgs84::EarthRateNed(lat_rad);
  const Eigen::Vector3d w_en = wgs84::TransportRateNed(lat_rad, h_m, v_n);
  BodyKinematics k;
  k.omega_ib_b_rad_s = omega_nb_b + R_b_n * (w_ie + w_en);
  k.f_b_mps2 = R_b_n * (tr.Acceleration_n_mps2(t) + (2.0 * w_ie + w_en).cross(v_n) -
                        wgs84::GravityNed(lat_rad, h_m));
  return k;
}

void SynthesizeImu(const AnalyticTrajectory& tr, const wgs84::Geodetic& start, double rate_hz,
                   double duration_s,
                   const std::function<void(const ImuSample&, const NavState&)>& emit) {
  if (!(rate_hz > 0.0) || !(duration_s > 0.0)) {
    throw std::invalid_argument("SynthesizeImu: rate_hz and duration_s must be positive");
  }
  // 3-point Gauss-Legendre nodes on [0, 1] and weights.
  const double c = std::sqrt(0.6) / 2.0;
  const double nodes[3] = {0.5 - c, 0.5, 0.5 + c};
  const double weights[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};

  const double dt = 1.0 / rate_hz;
  const long n = std::lround(duration_s * rate_hz);
  GeoPoint p{start.lat_rad, start.lon_rad, start.h_m};
  ImuSample none;
  emit(none, TruthState(tr, 0.0, p));
  for (long k = 1; k <= n; ++k) {
    const double t0 = (k - 1) * dt;
    ImuSample s;
    s.t_s = k * dt;
    s.dt_s = dt;
    double t = t0;
    for (int i = 0; i < 3; ++i) {
      const double tn = t0 + nodes[i] * dt;
      p = Rk4(tr, p, t, tn - t);
      t = tn;
      const BodyKinematics kin = BodyKinematicsAt(tr, tn, p.lat_rad, p.h_m);
      s.dtheta_b_rad += weights[i] * dt * kin.omega_ib_b_rad_s;
      s.dv_b_mps += weights[i] * dt * kin.f_b_mps2;
    }
    p = Rk4(tr, p, t, s.t_s - t);
    emit(s, TruthState(tr, s.t_s, p));
  }
}

namespace {
constexpr double kTwoPi = 2.0 * M_PI;
// Demo-flight shape: amplitude (rad or m/s) and period (s) of each sinusoid.
constexpr double kRollAmp = 0.2, kRollPeriod = 60.0;
constexpr double kPitchMean = 0.02, kPitchAmp = 0.05, kPitchPeriod = 120.0;
constexpr double kYawMean = 0.5, kYawAmp = 0.6, kYawPeriod = 200.0;
constexpr double kSpeedMean = 30.0, kSpeedAmp = 10.0, kSpeedPeriod = 300.0;
constexpr double kClimbAmp = 2.0, kClimbPeriod = 150.0;
}  // namespace

Eigen::Vector3d DemoFlight::Euler_rad(double t) const {
  return {kRollAmp * std::sin(kTwoPi * t / kRollPeriod),
          kPitchMean + kPitchAmp * std::sin(kTwoPi * t / kPitchPeriod),
          kYawMean + kYawAmp * std::sin(kTwoPi * t / kYawPeriod)};
}

Eigen::Vector3d DemoFlight::EulerRate_rad_s(double t) const {
  return {kRollAmp * kTwoPi / kRollPeriod * std::cos(kTwoPi * t / kRollPeriod),
          kPitchAmp * kTwoPi / kPitchPeriod * std::cos(kTwoPi * t / kPitchPeriod),
          kYawAmp * kTwoPi / kYawPeriod * std::cos(kTwoPi * t / kYawPeriod)};
}

Eigen::Vector3d DemoFlight::Velocity_n_mps(double t) const {
  const double speed = kSpeedMean - kSpeedAmp * std::cos(kTwoPi * t / kSpeedPeriod);
  const double yaw = Euler_rad(t).z();
  return {speed * std::cos(yaw), speed * std::sin(yaw),
          -kClimbAmp * std::sin(kTwoPi * t / kClimbPeriod)};
}

Eigen::Vector3d DemoFlight::Acceleration_n_mps2(double t) const {
  const double speed = kSpeedMean - kSpeedAmp * std::cos(kTwoPi * t / kSpeedPeriod);
  const double dspeed = kSpeedAmp * kTwoPi / kSpeedPeriod * std::sin(kTwoPi * t / kSpeedPeriod);
  const double yaw = Euler_rad(t).z();
  const double dyaw = EulerRate_rad_s(t).z();
  return {dspeed * std::cos(yaw) - speed * dyaw * std::sin(yaw),
          dspeed * std::sin(yaw) + speed * dyaw * std::cos(yaw),
          -kClimbAmp * kTwoPi / kClimbPeriod * std::cos(kTwoPi * t / kClimbPeriod)};
}

}  // namespace navtwin::sim
