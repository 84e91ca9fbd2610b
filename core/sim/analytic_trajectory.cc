#include "core/sim/analytic_trajectory.h"

#include <cmath>
#include <stdexcept>

#include "core/rotation.h"
#include "core/sim/truth.h"
#include "core/units.h"

namespace navtwin::sim {
BodyKinematics BodyKinematicsAt(const TrajectoryPoint& p, double lat_rad, double h_m) {
  const Eigen::Vector3d& e = p.euler_rad;
  const Eigen::Vector3d& de = p.euler_rate_radps;
  const double sr = std::sin(e.x()), cr = std::cos(e.x());
  const double sp = std::sin(e.y()), cp = std::cos(e.y());
  const Eigen::Vector3d omega_nb_b(de.x() - de.z() * sp, de.y() * cr + de.z() * sr * cp,
                                   -de.y() * sr + de.z() * cr * cp);
  const double sy = std::sin(e.z()), cy = std::cos(e.z());
  Eigen::Matrix3d R_b_n;  // DcmFromEuler(e)^T, reusing the sines and cosines above
  R_b_n << cy * cp, sy * cp, -sp,
           cy * sp * sr - sy * cr, sy * sp * sr + cy * cr, cp * sr,
           cy * sp * cr + sy * sr, sy * sp * cr - cy * sr, cp * cr;
  const Eigen::Vector3d w_ie = wgs84::EarthRateNed(lat_rad);
  const Eigen::Vector3d w_en = wgs84::TransportRateNed(lat_rad, h_m, p.v_n_mps);
  BodyKinematics k;
  k.omega_ib_b_radps = omega_nb_b + R_b_n * (w_ie + w_en);
  k.f_b_mps2 = R_b_n * (p.a_n_mps2 + (2.0 * w_ie + w_en).cross(p.v_n_mps) -
                        wgs84::GravityNed(lat_rad, h_m));
  return k;
}

BodyKinematics BodyKinematicsAt(const AnalyticTrajectory& tr, double t, double lat_rad, double h_m) {
  return BodyKinematicsAt(tr.PointAt(t), lat_rad, h_m);
}

void SynthesizeImu(const AnalyticTrajectory& tr, const wgs84::Geodetic& start, double rate_hz,
                   double duration_s,
                   const std::function<void(const ImuSample&, const NavState&)>& emit) {
  if (!(rate_hz > 0.0) || !(duration_s > 0.0)) {
    throw std::invalid_argument("SynthesizeImu: rate_hz and duration_s must be positive");
  }
  TruthGenerator truth(tr, start, rate_hz);
  emit(ImuSample(), truth.current().state);
  const long n = std::lround(duration_s * rate_hz);
  for (long k = 1; k <= n; ++k) {
    const TruthSample& s = truth.Next();
    emit(s.exact, s.state);
  }
}

namespace {
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

Eigen::Vector3d DemoFlight::EulerRate_radps(double t) const {
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
  const double dyaw = EulerRate_radps(t).z();
  return {dspeed * std::cos(yaw) - speed * dyaw * std::sin(yaw),
          dspeed * std::sin(yaw) + speed * dyaw * std::cos(yaw),
          -kClimbAmp * kTwoPi / kClimbPeriod * std::cos(kTwoPi * t / kClimbPeriod)};
}

}  // namespace navtwin::sim
