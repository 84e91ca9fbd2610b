// The free INS of the in-flight alignment (problems/inflight_alignment/free_ins.h): with
// perfect sensors its distance error against GPS is the heading's rotation of the gained
// displacement (equation 8 recovers the injected 20 arcmin), a fix between IMU epochs is
// compared at its own time, the barometric loop has the critically damped step response
// it is designed for, and the GPS sigma estimate is robust to outliers.
#include "problems/inflight_alignment/free_ins.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/sim/random.h"
#include "core/sim/scenario.h"
#include "core/units.h"
#include "problems/inflight_alignment/distance_heading.h"
#include "problems/inflight_alignment/inputs.h"

namespace navtwin::inflight {
namespace inflight_alignment_free_ins_test {


// The preset with every sensor error off (IMU, GPS, barometer exact) and only the 20 arcmin
// heading error in the initial state (no level error: its Schuler error would be 150 m
// after 545 s and hide the rotation). Simulated once per test binary.
const InflightInputs& PerfectSensors() {
  static const InflightInputs inputs = [] {
    sim::Scenario sc = sim::LoadScenario("inflight-mach07-south");
    sc.imu.errors = sim::InertialErrorConfig{};
    sc.gnss->position_sigma_ned_m.setZero();
    sc.gnss->velocity_sigma_ned_mps.setZero();
    sc.gnss->outlier_probability = 0.0;
    sc.baro->bias_fixed_m = 0.0;
    sc.baro->bias_sigma_m = 0.0;
    sc.baro->noise_m = 0.0;
    sc.init_errors = sim::InitErrorConfig{};
    sc.init_errors.attitude_phi_n_rad = Eigen::Vector3d(0.0, 0.0, 20.0 * kArcmin_rad);
    return SimulateInflightInputs(sc, /*seed=*/1);
  }();
  return inputs;
}

// Truth yaw at t (records at the IMU rate; linear between them through the wrapped step).
double TruthYaw(const std::vector<NavState>& truth, double t_s) {
  const auto it = std::upper_bound(truth.begin(), truth.end(), t_s,
                                   [](double t, const NavState& s) { return t < s.t_s; });
  const std::size_t i = it == truth.begin() ? 0 : static_cast<std::size_t>(it - truth.begin()) - 1;
  const NavState& a = truth[i];
  const NavState& b = truth[std::min(i + 1, truth.size() - 1)];
  const double w = b.t_s > a.t_s ? (t_s - a.t_s) / (b.t_s - a.t_s) : 0.0;
  return YawOf(a) + w * WrapPi(YawOf(b) - YawOf(a));
}

// ----------------------------------------------------------------- perfect sensors

TEST(InflightFreeIns, PerfectSensorsErrorIsTheRotationOfTheGainedDisplacement) {
  const InflightInputs& in = PerfectSensors();
  const std::vector<FreeInsEpoch> epochs = RunFreeIns(in, InflightConfig{});
  ASSERT_GT(epochs.size(), 500u);  // 545 s at 1 Hz
  EXPECT_DOUBLE_EQ(epochs.front().sample.t_s, epochs.front().t_s - in.initial.t_s);

  const double earth_rate_cos_lat = wgs84::kOmegaIe_radps * std::cos(in.initial.lat_rad);
  const double dh0 = -20.0 * kArcmin_rad;  // the injected error: dH = -phi_D
  const FreeInsEpoch* last_checked = nullptr;
  for (const FreeInsEpoch& e : epochs) {
    // Up to 100 s (20 km gained from rest), before the Schuler terms leave the t^3 regime
    // (their next term is (w t)^2 / 20 = 0.8 % of them at 100 s).
    if (e.sample.t_s > 100.0) break;
    const double t = e.sample.t_s;
    const double dh = WrapPi(e.yaw_free_rad - TruthYaw(in.truth, e.t_s));
    // The INS rotates the displacement it gains by dH: err = D - Rz(-dH) D exactly (D is
    // the INS's, rotated). Its local heading error dH(t) drifts from dH(0) by the
    // meridian convergence of the rotated track (the east velocity error dH v over R
    // times tan L: 0.05 arcmin by 100 s), so the current dH is the one to rotate by.
    const Eigen::Vector2d d(e.sample.dn_m, e.sample.de_m);
    const Eigen::Vector2d d_true(std::cos(dh) * d.x() + std::sin(dh) * d.y(),
                                 -std::sin(dh) * d.x() + std::cos(dh) * d.y());
    Eigen::Vector2d predicted = d - d_true;
    // The heading error also tilts the platform through the Earth rate:
    // d(phi_E)/dt = Omega cos L phi_D, d(dv_N)/dt = -g phi_E, so the INS runs ahead north
    // by err_N = g Omega cos L phi_D t^3 / 6 = -g Omega cos L dH t^3 / 6 (0.56 m at 100 s;
    // the docs' gyro-shaped term).
    predicted.x() -= kStandardGravity_mps2 * earth_rate_cos_lat * dh0 * t * t * t / 6.0;
    const Eigen::Vector2d err(e.sample.err_n_m, e.sample.err_e_m);
    // What remains are products of small errors through the pull-up and the speed-up
    // (attitude error times pitch rate, the vertical loop), a few centimetres (measured:
    // 4 cm north, 1.3 cm east at 100 s), and the files' rounding: 0.1 m, i.e. 5e-6 of
    // the 20 km gained.
    EXPECT_LT((err - predicted).norm(), 0.1) << "t " << t << " s, D " << d.norm() << " m";
    last_checked = &e;
  }
  ASSERT_NE(last_checked, nullptr);
  const double dh_true = WrapPi(last_checked->yaw_free_rad - TruthYaw(in.truth, last_checked->t_s));
  EXPECT_NEAR(dh_true, dh0, 0.1 * kArcmin_rad);  // the meridian-convergence drift above
  // Equation 8 on the last sample recovers it: the cross-track remainder (< 0.1 m) over
  // the 19 km gained is 0.02 arcmin; the along-track terms enter through dE err_N / D^2
  // (0.1 km x 0.6 m / (19 km)^2 = 6e-4 arcmin).
  const DistanceErrorSample& s = last_checked->sample;
  ASSERT_GT(std::hypot(s.dn_m, s.de_m), 19e3);
  const double dh_eq8 = DistanceHeadingError(s.dn_m, s.de_m, s.err_n_m, s.err_e_m);
  EXPECT_NEAR(dh_eq8, dh_true, 0.02 * kArcmin_rad) << "gained " << std::hypot(s.dn_m, s.de_m) << " m";
}

TEST(InflightFreeIns, FixBetweenImuEpochsIsComparedAtItsOwnTime) {
  const InflightInputs& in = PerfectSensors();
  // The same flight with every fix 5 ms later (half an IMU interval) and, the GPS being
  // exact, moved along the true velocity (1.2 m at 238 m/s): the samples must agree with
  // those of the original fixes, the INS being moved back by v dt to each fix.
  InflightInputs shifted = in;
  constexpr double kShift_s = 0.005;
  for (GnssSample& g : shifted.gnss) {
    const auto it = std::lower_bound(in.truth.begin(), in.truth.end(), g.t_s,
                                     [](const NavState& s, double t) { return s.t_s < t - 1e-9; });
    ASSERT_NE(it, in.truth.end());
    const double rm = wgs84::MeridianRadius(g.lat_rad) + g.h_m;
    const double rn = wgs84::PrimeVerticalRadius(g.lat_rad) + g.h_m;
    g.t_s += kShift_s;
    g.lat_rad += it->v_n_mps.x() * kShift_s / rm;
    g.lon_rad += it->v_n_mps.y() * kShift_s / (rn * std::cos(g.lat_rad));
    g.h_m -= it->v_n_mps.z() * kShift_s;
  }
  const std::vector<FreeInsEpoch> a = RunFreeIns(in, InflightConfig{});
  const std::vector<FreeInsEpoch> b = RunFreeIns(shifted, InflightConfig{});
  // The last shifted fix may fall past the IMU data.
  ASSERT_GE(b.size() + 1, a.size());
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    // The INS error grows by at most its rate times 5 ms (under 1 m/s: 5 mm) and the
    // acceleration of up to 7 m/s^2 (pull-up, speed-up) makes the first-order moves differ
    // by a dt^2 / 2 < 0.1 mm; 1 cm covers both. The gained displacement moves by
    // (v - v0) 5 ms, at most 0.7 m, and must be the original's plus that.
    EXPECT_NEAR(b[i].sample.err_n_m, a[i].sample.err_n_m, 0.01) << "fix " << i;
    EXPECT_NEAR(b[i].sample.err_e_m, a[i].sample.err_e_m, 0.01) << "fix " << i;
    EXPECT_NEAR(b[i].sample.t_s, a[i].sample.t_s + kShift_s, 1e-9);
    const auto it = std::lower_bound(in.truth.begin(), in.truth.end(), a[i].t_s,
                                     [](const NavState& s, double t) { return s.t_s < t - 1e-9; });
    ASSERT_NE(it, in.truth.end());
    const Eigen::Vector2d gained_move = (it->v_n_mps - in.initial.v_n_mps).head<2>() * kShift_s;
    EXPECT_NEAR(b[i].sample.dn_m - a[i].sample.dn_m, gained_move.x(), 0.01) << "fix " << i;
    EXPECT_NEAR(b[i].sample.de_m - a[i].sample.de_m, gained_move.y(), 0.01) << "fix " << i;
  }
}

// ----------------------------------------------------------------- barometric loop

TEST(InflightFreeIns, BaroLoopHasTheCriticallyDampedStepResponse) {
  // A stationary INS (level, facing north; the IMU reads -gravity and the Earth rate) that
  // starts 10 m above the barometric altitude. The loop's error equation is
  // (s + 1/tau)^2 dh = 0 with dh(0) = 10 m, dh'(0) = -2 dh(0) / tau (the loop's gain on
  // the height), so dh(t) = dh(0) (1 - t / tau) exp(-t / tau): through zero at tau, the
  // one undershoot of exp(-2) dh(0) at 2 tau, no oscillation.
  constexpr double kLat = 36.5 * kDegToRad, kH = 1000.0, kStep = 10.0, kDt = 0.01;
  BaroLoopOptions loop;
  loop.time_constant_s = 20.0;
  NavState start;
  start.lat_rad = kLat;
  start.lon_rad = 127.0 * kDegToRad;
  start.h_m = kH + kStep;
  FreeInsTrack track(start, loop);
  ImuSample imu;
  imu.dt_s = kDt;
  imu.dv_b_mps = Eigen::Vector3d(0.0, 0.0, -wgs84::NormalGravity(kLat, kH)) * kDt;
  imu.dtheta_b_rad = wgs84::EarthRateNed(kLat) * kDt;
  double min_dh = kStep;
  for (int k = 1; k <= 20000; ++k) {  // 10 time constants
    imu.t_s = k * kDt;
    track.Update(imu, kH);
    const double t = imu.t_s, tau = loop.time_constant_s;
    const double dh = track.state().h_m - kH;
    const double expected = kStep * (1.0 - t / tau) * std::exp(-t / tau);
    // Neglected: the free-inertial term 2 g / R dh (1/(565 s)^2, 0.13 % of 1/tau^2) and the
    // Euler step of the loop (dt / tau = 5e-4): 0.5 % of the step covers both.
    ASSERT_NEAR(dh, expected, 0.05) << "t " << t << " s";
    min_dh = std::min(min_dh, dh);
  }
  EXPECT_NEAR(min_dh, -kStep * std::exp(-2.0), 0.05);
  EXPECT_NEAR(track.state().h_m, kH, 0.01);  // 10 tau: 10 m * 9 e^-10 = 4 mm
  EXPECT_NEAR(track.state().v_n_mps.z(), 0.0, 1e-3);
}

TEST(InflightFreeIns, BaroLoopRejectsABadTimeConstant) {
  NavState nav;
  BaroLoopOptions loop;
  loop.time_constant_s = 0.0;
  EXPECT_THROW(ApplyBaroLoop(100.0, 0.01, loop, &nav), std::invalid_argument);
}

// ----------------------------------------------------------------- GPS sigma

TEST(InflightFreeIns, GpsSigmaIsRobustToOutliers) {
  // 5000 fixes at 1 Hz of a flight south at 238 m/s speeding up by 0.5 m/s^2 (third
  // differences cancel it), 17 m white noise per axis and 1 % outliers of 200 m in a
  // random direction.
  sim::Rng rng(7);
  constexpr double kSigma = 17.0;
  const double lat0 = 36.5 * kDegToRad, rm = wgs84::MeridianRadius(lat0) + 1000.0;
  const double rn = (wgs84::PrimeVerticalRadius(lat0) + 1000.0) * std::cos(lat0);
  std::vector<GnssSample> fixes;
  for (int k = 0; k < 5000; ++k) {
    const double t = k;
    Eigen::Vector3d p(-238.0 * t - 0.25 * t * t, 0.0, 0.0);
    for (int a = 0; a < 3; ++a) p(a) += kSigma * rng.Normal();
    if (rng.Uniform() < 0.01) {
      const Eigen::Vector3d dir(rng.Normal(), rng.Normal(), rng.Normal());
      p += 200.0 * dir.normalized();
    }
    GnssSample g;
    g.t_s = t;
    g.lat_rad = lat0 + p.x() / rm;
    g.lon_rad = 127.0 * kDegToRad + p.y() / rn;
    g.h_m = 1000.0 - p.z();
    fixes.push_back(g);
  }
  // Each outlier spoils 4 differences (4 % of them, all above the median): the median of
  // |d| moves from the 50 % to the 52 % point of the clean distribution, +4.8 %; the
  // sampling spread of a median of 5000 is 1.7 % (3 sigma 5 %); 10 % covers both.
  EXPECT_NEAR(EstimateGpsSigma(fixes), kSigma, 0.1 * kSigma);
  std::vector<GnssSample> first(fixes.begin(), fixes.begin() + 7);
  EXPECT_THROW(EstimateGpsSigma(first), std::invalid_argument);  // fewer than 8 fixes
}

TEST(InflightFreeIns, GpsSigmaSkipsGapsInsteadOfCountingTheMotion) {
  // A 1 Hz flight at 238 m/s with a 10 s gap every 20 fixes and no noise at all: a third
  // difference across a gap would see the motion (metres); skipped, the estimate is 0.
  std::vector<GnssSample> fixes;
  const double lat0 = 36.5 * kDegToRad, rm = wgs84::MeridianRadius(lat0) + 1000.0;
  double t = 0.0;
  for (int k = 0; k < 200; ++k) {
    t += (k % 20 == 0 && k > 0) ? 10.0 : 1.0;
    GnssSample g;
    g.t_s = t;
    g.lat_rad = lat0 - 238.0 * t / rm;
    g.lon_rad = 127.0 * kDegToRad;
    g.h_m = 1000.0;
    fixes.push_back(g);
  }
  // Rounding of lat * R (6.4e6 m * 1e-16) through four terms: below 1 micrometre.
  EXPECT_LT(EstimateGpsSigma(fixes), 1e-6);
}

}  // namespace inflight_alignment_free_ins_test
}  // namespace navtwin::inflight
