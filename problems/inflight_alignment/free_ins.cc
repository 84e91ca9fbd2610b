#include "problems/inflight_alignment/free_ins.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/earth.h"
#include "core/rotation.h"
#include "problems/inflight_alignment/gps_smoother.h"
#include "problems/ins/ins_state.h"

namespace navtwin::inflight {
namespace {

// median |d| = 0.6745 sigma_d for a normal d: 1.4826 = 1 / 0.6745 turns it into sigma_d.
constexpr double kMadToSigma = 1.4826;
// Consecutive fix intervals within this fraction of each other count as equally spaced
// (a third difference cancels constant-acceleration motion only on an even grid).
constexpr double kEvenSpacingTolerance = 1e-3;

// A position moved along the velocity v_n_mps by dt_s (NED, small dt: first order in the
// radii, which is exact to (v dt)^2 / R, 1e-9 m for 10 ms at 238 m/s).
wgs84::Geodetic MoveAlong(const NavState& nav, double dt_s) {
  const double rm = wgs84::MeridianRadius(nav.lat_rad) + nav.h_m;
  const double rn = wgs84::PrimeVerticalRadius(nav.lat_rad) + nav.h_m;
  wgs84::Geodetic p;
  p.lat_rad = nav.lat_rad + nav.v_n_mps.x() * dt_s / rm;
  p.lon_rad = nav.lon_rad + nav.v_n_mps.y() * dt_s / (rn * std::cos(nav.lat_rad));
  p.h_m = nav.h_m - nav.v_n_mps.z() * dt_s;
  return p;
}

// Median of the absolute values (the vector is reordered).
double MedianAbs(std::vector<double>* values) {
  for (double& v : *values) v = std::abs(v);
  const std::size_t mid = values->size() / 2;
  std::nth_element(values->begin(), values->begin() + static_cast<std::ptrdiff_t>(mid), values->end());
  double m = (*values)[mid];
  if (values->size() % 2 == 0) {
    // Even count: the mean of the two middle values (the lower one is the largest of the
    // lower half, which nth_element left unsorted before mid).
    m = 0.5 * (m + *std::max_element(values->begin(), values->begin() + static_cast<std::ptrdiff_t>(mid)));
  }
  return m;
}

}  // namespace

void ApplyBaroLoop(double baro_altitude_m, double dt_s, const BaroLoopOptions& options, NavState* nav) {
  const double tau = options.time_constant_s;
  if (!(tau > 0.0) || !std::isfinite(tau)) {
    throw std::invalid_argument("BaroLoopOptions.time_constant_s = " + std::to_string(tau) +
                                " must be finite and > 0");
  }
  if (!std::isfinite(baro_altitude_m) || !(dt_s >= 0.0)) {
    throw std::invalid_argument("ApplyBaroLoop: altitude " + std::to_string(baro_altitude_m) +
                                " m or interval " + std::to_string(dt_s) + " s is not valid");
  }
  // Height error dh = h_ins - h_true, up-velocity error du: with this loop
  //   dh' = du - 2 dh / tau,   du' = -dh / tau^2   =>  s^2 + 2 s / tau + 1 / tau^2 = (s + 1/tau)^2,
  // a double pole at -1/tau (critically damped); the free-inertial 2 g / R dh term
  // (1 / (565 s)^2) is small against 1 / tau^2 for tau of tens of seconds.
  const double e = baro_altitude_m - nav->h_m;
  nav->h_m += 2.0 * e * dt_s / tau;
  nav->v_n_mps.z() -= e * dt_s / (tau * tau);  // down velocity: an up-velocity gain of e / tau^2
}

double YawOf(const NavState& nav) { return EulerFromQuat(nav.q_n_b.normalized()).z(); }

// ----------------------------------------------------------------- FreeInsTrack

FreeInsTrack::FreeInsTrack(const NavState& initial, const BaroLoopOptions& baro)
    : ins_(initial), baro_(baro) {
  start_.lat_rad = initial.lat_rad;
  start_.lon_rad = initial.lon_rad;
  start_.h_m = initial.h_m;
  v0_n_mps_ = initial.v_n_mps;
  // D(initial.t_s) = 0. The distance's clock is the absolute time, so that
  // gained_.start_time_s() is initial.t_s and sample times count from it.
  gained_.Add(initial.t_s, Eigen::Vector3d::Zero());
  last_t_s_ = initial.t_s;
  last_v_ne_mps_ = initial.v_n_mps.head<2>();
}

void FreeInsTrack::Update(const ImuSample& imu, double baro_altitude_m) {
  const NavState before = ins_.state();
  ins_.Update(imu);
  NavState nav = ins_.state();
  if (std::isfinite(baro_altitude_m)) {
    ApplyBaroLoop(baro_altitude_m, imu.dt_s, baro_, &nav);
  } else {
    // No barometer: the height is held (the free-inertial vertical channel diverges).
    nav.h_m = before.h_m;
    nav.v_n_mps.z() = 0.0;
  }
  ins_.SetState(nav);
  const Eigen::Vector2d v_ne = nav.v_n_mps.head<2>();
  // Path length: trapezoid of the horizontal speed.
  path_length_m_ += 0.5 * (last_v_ne_mps_.norm() + v_ne.norm()) * (nav.t_s - last_t_s_);
  // Gained displacement: the velocity form of DistanceFlown fed v - v0 (header).
  gained_.Add(nav.t_s, nav.v_n_mps - v0_n_mps_);
  last_t_s_ = nav.t_s;
  last_v_ne_mps_ = v_ne;
}

DistanceErrorSample FreeInsTrack::SampleAt(double t_fix_s, const wgs84::Geodetic& gps_position) const {
  const NavState& nav = ins_.state();
  // Move the INS back from its epoch to the fix with the current velocity:
  // p(t_fix) = p(t_ins) - v (t_ins - t_fix), D(t_fix) = D(t_ins) - (v - v0)_NE (t_ins - t_fix).
  const double dt_back_s = nav.t_s - t_fix_s;
  const wgs84::Geodetic ins_at_fix = MoveAlong(nav, -dt_back_s);
  const Eigen::Vector2d gained_ne_m =
      gained_.north_east_m() - (nav.v_n_mps - v0_n_mps_).head<2>() * dt_back_s;
  const Eigen::Vector2d err_ne_m =
      NorthEastFromStart(start_, ins_at_fix) - NorthEastFromStart(start_, gps_position);
  DistanceErrorSample s;
  s.t_s = t_fix_s - gained_.start_time_s();
  s.dn_m = gained_ne_m.x();
  s.de_m = gained_ne_m.y();
  s.err_n_m = err_ne_m.x();
  s.err_e_m = err_ne_m.y();
  return s;
}

const NavState& FreeInsTrack::state() const { return ins_.state(); }

// ----------------------------------------------------------------- RunFreeIns

std::vector<FreeInsEpoch> RunFreeIns(const InflightInputs& inputs, const InflightConfig& config) {
  ValidateInputs(inputs);
  const double t0_s = inputs.initial.t_s;
  FreeInsTrack track(inputs.initial, config.baro);
  // IMU samples after the initial state (their interval ends after initial.t_s).
  std::size_t next_imu = 0;
  while (next_imu < inputs.imu.size() && inputs.imu[next_imu].t_s <= t0_s + ins::kSameEpoch_s) ++next_imu;
  const double t_end_s = inputs.imu.back().t_s;

  std::vector<FreeInsEpoch> epochs;
  for (const GnssSample& fix : inputs.gnss) {
    if (fix.t_s < t0_s - ins::kSameEpoch_s) continue;   // before the alignment started
    if (fix.t_s > t_end_s + ins::kSameEpoch_s) break;   // after the IMU data
    // Step to the first IMU epoch at or after the fix.
    while (track.state().t_s < fix.t_s - ins::kSameEpoch_s && next_imu < inputs.imu.size()) {
      const ImuSample& imu = inputs.imu[next_imu++];
      track.Update(imu, BaroAltitudeAt(inputs.baro, imu.t_s));
    }
    FreeInsEpoch e;
    e.sample = track.SampleAt(fix.t_s, wgs84::Geodetic{fix.lat_rad, fix.lon_rad, fix.h_m});
    e.t_s = fix.t_s;
    e.path_length_m = track.path_length_m();
    e.yaw_free_rad = YawOf(track.state());
    epochs.push_back(e);
  }
  return epochs;
}

// ----------------------------------------------------------------- EstimateGpsSigma

double EstimateGpsSigma(const std::vector<GnssSample>& gnss) {
  if (gnss.size() < 8) {
    throw std::invalid_argument("EstimateGpsSigma: " + std::to_string(gnss.size()) +
                                " GNSS fixes; at least 8 are needed");
  }
  const wgs84::Geodetic origin{gnss.front().lat_rad, gnss.front().lon_rad, gnss.front().h_m};
  std::vector<Eigen::Vector2d> ne(gnss.size());
  for (std::size_t k = 0; k < gnss.size(); ++k) {
    ne[k] = NorthEastFromStart(origin, wgs84::Geodetic{gnss[k].lat_rad, gnss[k].lon_rad, gnss[k].h_m});
  }
  std::vector<double> dn, de;
  for (std::size_t k = 3; k < gnss.size(); ++k) {
    const double dt1 = gnss[k].t_s - gnss[k - 1].t_s;
    const double dt2 = gnss[k - 1].t_s - gnss[k - 2].t_s;
    const double dt3 = gnss[k - 2].t_s - gnss[k - 3].t_s;
    if (!(dt1 > 0.0) || std::abs(dt2 - dt1) > kEvenSpacingTolerance * dt1 ||
        std::abs(dt3 - dt1) > kEvenSpacingTolerance * dt1) {
      continue;  // a gap: the difference would not cancel the motion
    }
    const Eigen::Vector2d d = ne[k] - 3.0 * ne[k - 1] + 3.0 * ne[k - 2] - ne[k - 3];
    dn.push_back(d.x());
    de.push_back(d.y());
  }
  if (dn.empty()) {
    throw std::invalid_argument("EstimateGpsSigma: no four consecutive, equally spaced GNSS fixes");
  }
  // A robust scale: the median of |d| is blind to the few differences an outlier spoils
  // (each outlier enters four of them).
  const double sigma_n = kMadToSigma * MedianAbs(&dn) / kThirdDifferenceGain;
  const double sigma_e = kMadToSigma * MedianAbs(&de) / kThirdDifferenceGain;
  return std::max(sigma_n, sigma_e);
}

}  // namespace navtwin::inflight
