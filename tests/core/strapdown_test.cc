#include "core/strapdown.h"

#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/rotation.h"

namespace navtwin {
namespace core_strapdown_test {

// Exact increments of an IMU at rest on the Earth at (lat, h) with attitude R_n_b:
// the body turns with the Earth (omega_ib_b = R_b_n omega_ie_n, constant in body axes)
// and senses f_b = -R_b_n g_n, so dtheta = omega dt and dv = f dt are exact.
ImuSample StationarySample(const Eigen::Matrix3d& R_n_b, double lat_rad, double h_m, double t_s,
                           double dt_s) {
  ImuSample s;
  s.t_s = t_s;
  s.dt_s = dt_s;
  s.dtheta_b_rad = R_n_b.transpose() * wgs84::EarthRateNed(lat_rad) * dt_s;
  s.dv_b_mps = -R_n_b.transpose() * wgs84::GravityNed(lat_rad, h_m) * dt_s;
  return s;
}

NavState StateAt(double lat_rad, double lon_rad, double h_m, const Eigen::Quaterniond& q_n_b) {
  NavState s;
  s.lat_rad = lat_rad;
  s.lon_rad = lon_rad;
  s.h_m = h_m;
  s.q_n_b = q_n_b;
  return s;
}

TEST(Strapdown, StationaryExactIncrementsStayPutForOneHour) {
  const double lat = 45.0 * kDegToRad, lon = 10.0 * kDegToRad, h = 100.0;
  const Eigen::Quaterniond q_n_b = QuatFromEuler(0.02, -0.01, 1.2);
  const Eigen::Matrix3d R_n_b = DcmFromQuat(q_n_b);
  Strapdown ins(StateAt(lat, lon, h, q_n_b));
  const double dt = 1.0 / 200.0;
  const int n = 3600 * 200;
  for (int k = 1; k <= n; ++k) ins.Update(StationarySample(R_n_b, lat, h, k * dt, dt));
  const NavState& s = ins.state();
  const Eigen::Vector3d dp = wgs84::GeodeticToNed({s.lat_rad, s.lon_rad, s.h_m}, {lat, lon, h});
  // The bound: 1 cm and 1e-5 deg after 1 h.
  EXPECT_LT(dp.norm(), 0.01) << dp.transpose();
  EXPECT_LT(AttitudeError(q_n_b, s.q_n_b).norm() * kRadToDeg, 1e-5);
  EXPECT_NEAR(s.t_s, 3600.0, 1e-9);
}

// Upward zero crossings of a sampled signal, linearly interpolated.
std::vector<double> UpwardCrossings(const std::vector<double>& t, const std::vector<double>& x) {
  std::vector<double> out;
  for (size_t i = 1; i < x.size(); ++i) {
    if (x[i - 1] < 0.0 && x[i] >= 0.0) {
      out.push_back(t[i - 1] + (t[i] - t[i - 1]) * (-x[i - 1]) / (x[i] - x[i - 1]));
    }
  }
  return out;
}

TEST(Strapdown, InitialTiltGivesSchulerOscillation) {
  const double lat = 45.0 * kDegToRad, h = 0.0;
  const Eigen::Quaterniond q_true = Eigen::Quaterniond::Identity();
  // 1 mrad roll error: the estimated attitude is Exp(phi) R_true with phi along north.
  const Eigen::Quaterniond q_est = ApplyAttitudeError(Eigen::Vector3d(1e-3, 0.0, 0.0), q_true);
  StrapdownOptions opt;
  opt.hold_height_m = h;  // free-inertial height would diverge over 3 h
  Strapdown ins(StateAt(lat, 0.0, h, q_est), opt);
  const double dt = 0.1;
  std::vector<double> t, v_e;
  for (int k = 1; k <= 3 * 3600 * 10; ++k) {
    ins.Update(StationarySample(DcmFromQuat(q_true), lat, h, k * dt, dt));
    t.push_back(k * dt);
    v_e.push_back(ins.state().v_n_mps.y());
  }
  const std::vector<double> up = UpwardCrossings(t, v_e);
  ASSERT_GE(up.size(), 2u);
  const double period_min = (up.back() - up.front()) / (up.size() - 1) / 60.0;
  // The bound: 84.4 +- 0.5 min (2 pi sqrt(R/g) at 45 deg).
  EXPECT_NEAR(period_min, 84.4, 0.5);
  // The tilt error g * 1 mrad integrates to a Schuler velocity amplitude of about
  // g phi / omega_s = 9.8e-3 / 1.24e-3 = 7.9 m/s; check the order of magnitude.
  double vmax = 0.0;
  for (double v : v_e) vmax = std::max(vmax, std::abs(v));
  EXPECT_NEAR(vmax, 7.9, 1.0);
}

// Classic coning: the rotation vector of R_n_b(t) has constant length beta and an axis
// turning at Omega in the body y-z plane, relative to a NED frame at rest on the Earth
// (the Earth rate is added to the increments below). The body rate over NED is
//   omega(t) = (-2 Omega sin^2(beta/2), -Omega sin(beta) sin(Omega t), Omega sin(beta) cos(Omega t)),
// and its exact increments are integrated in closed form. An algorithm without the
// coning term drifts about x at (1/2) Omega sin^2(beta) (1 - sin(Omega h) / (Omega h)).
struct Coning {
  double beta, omega;
  Eigen::Matrix3d R(double t) const {
    return ExpSO3(Eigen::Vector3d(0.0, beta * std::cos(omega * t), beta * std::sin(omega * t)));
  }
  Eigen::Vector3d Increment(double t0, double t1) const {
    const double wx = -2.0 * omega * std::pow(std::sin(beta / 2), 2);
    return Eigen::Vector3d(wx * (t1 - t0),
                           std::sin(beta) * (std::cos(omega * t1) - std::cos(omega * t0)),
                           std::sin(beta) * (std::sin(omega * t1) - std::sin(omega * t0)));
  }
};

double ConingDriftRate(bool coning_sculling, const Coning& c, double h_s, double duration_s) {
  // The IMU sits at 45 deg latitude: the Earth rate is added to the body increments so
  // that the mechanization's Earth-rate removal leaves exactly the coning motion.
  const double lat = M_PI / 4;
  StrapdownOptions opt;
  opt.coning_sculling = coning_sculling;
  opt.hold_height_m = 0.0;
  Strapdown ins(StateAt(lat, 0.0, 0.0, QuatFromDcm(c.R(0.0))), opt);
  const int n = static_cast<int>(duration_s / h_s);
  const Eigen::Vector3d w_ie_n = wgs84::EarthRateNed(lat);
  const Eigen::Vector3d g_n = wgs84::GravityNed(lat, 0.0);
  for (int k = 1; k <= n; ++k) {
    const double t0 = (k - 1) * h_s, t1 = k * h_s;
    ImuSample s;
    s.t_s = t1;
    s.dt_s = h_s;
    // The Earth-rate part changes direction in body axes with the coning; its first-order
    // increment at the midpoint is exact enough (its product with the coning is 1e-9 smaller).
    const Eigen::Matrix3d R_mid = c.R(0.5 * (t0 + t1));
    s.dtheta_b_rad = c.Increment(t0, t1) + R_mid.transpose() * w_ie_n * h_s;
    s.dv_b_mps = -R_mid.transpose() * g_n * h_s;
    ins.Update(s);
  }
  const Eigen::Vector3d err_b =
      c.R(n * h_s).transpose() * AttitudeError(QuatFromDcm(c.R(n * h_s)), ins.state().q_n_b);
  return err_b.norm() / (n * h_s);
}

TEST(Strapdown, ConingCorrectionRemovesPredictedDrift) {
  const Coning c{0.05, 2.0 * M_PI * 5.0};  // 0.05 rad half-cone at 5 Hz
  const double h = 0.01;                   // 100 Hz
  const double predicted = 0.5 * c.omega * std::pow(std::sin(c.beta), 2) *
                           (1.0 - std::sin(c.omega * h) / (c.omega * h));
  const double without = ConingDriftRate(false, c, h, 20.0);
  const double with = ConingDriftRate(true, c, h, 20.0);
  // The uncorrected drift follows the analytic prediction (5 %: the prediction is the
  // leading term of a series in beta); the two-sample correction removes at least 95 %.
  EXPECT_NEAR(without / predicted, 1.0, 0.05) << "without " << without << " predicted " << predicted;
  EXPECT_LT(with, 0.05 * predicted) << "with " << with;
  // What remains is the two-sample algorithm's own error, fourth order in the interval:
  // halving it divides the drift by 16 in theory; 12 leaves room for the next term.
  const double with_half = ConingDriftRate(true, c, h / 2, 20.0);
  EXPECT_GT(with / with_half, 12.0) << with << " vs " << with_half;
}

TEST(Strapdown, RejectsNonPositiveInterval) {
  Strapdown ins(StateAt(0.5, 0.0, 0.0, Eigen::Quaterniond::Identity()));
  ImuSample s;
  s.t_s = 1.0;
  s.dt_s = 0.0;
  EXPECT_THROW(ins.Update(s), std::invalid_argument);
}

}  // namespace core_strapdown_test
}  // namespace navtwin
