#include "problems/inflight_alignment/filter.h"

#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/LU>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/strapdown.h"
#include "core/units.h"
#include "problems/ins/error_dynamics.h"
#include "problems/ins/ins_state.h"
#include "problems/inflight_alignment/gps_smoother.h"
#include "problems/inflight_alignment/inputs.h"

namespace navtwin::inflight {
namespace {

using Vector11 = Eigen::Matrix<double, kFilterStates, 1>;
using Matrix11 = Eigen::Matrix<double, kFilterStates, kFilterStates>;
using Gain = Eigen::Matrix<double, kFilterStates, 2>;

// Covariance propagation step: mean f_b and omega over ~0.1 s blocks. The fastest error
// dynamics are the Schuler (84 min) and Earth-rate couplings, and during the pull-up the
// specific force changes over seconds, so 0.1 s keeps the second-order transition
// matrix exact to far below the process noise while costing 10x less than per sample.
constexpr double kBlock_s = 0.1;

// The filter's states in the 15-state layout of problems/ins/ins_state.h (err::):
// dp_N, dp_E, dv_N, dv_E, phi_N, phi_E, phi_D, dbg_x, dbg_y, dba_x, dba_y.
constexpr std::array<int, kFilterStates> kIn15 = {
    ins::err::kPos + 0, ins::err::kPos + 1, ins::err::kVel + 0, ins::err::kVel + 1,
    ins::err::kAtt + 0, ins::err::kAtt + 1, ins::err::kAtt + 2, ins::err::kBg + 0,
    ins::err::kBg + 1,  ins::err::kBa + 0,  ins::err::kBa + 1};
static_assert(fstate::kPos == 0 && fstate::kVel == 2 && fstate::kLevel == 4 && fstate::kHeading == 6 &&
                  fstate::kBg == 7 && fstate::kBa == 9,
              "kIn15 follows the fstate layout");

Matrix11 Sub(const Eigen::MatrixXd& m15) {
  Matrix11 s;
  for (int i = 0; i < kFilterStates; ++i) {
    for (int j = 0; j < kFilterStates; ++j) s(i, j) = m15(kIn15[i], kIn15[j]);
  }
  return s;
}

// Sets P(i, :) = P(:, i) = 0 and P(i, i) = variance.
void ResetState(int i, double variance, Matrix11* P) {
  P->row(i).setZero();
  P->col(i).setZero();
  (*P)(i, i) = variance;
}

void RequireFilterConfig(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("RunInflightFilter: " + what);
}

void CheckConfig(const InflightConfig& c) {
  auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  auto non_negative = [](double x) { return std::isfinite(x) && x >= 0.0; };
  RequireFilterConfig(non_negative(c.sensors.gyro_bias_radps), "sensors.gyro_bias_deg_h must be >= 0");
  RequireFilterConfig(non_negative(c.sensors.gyro_arw_rad_per_sqrt_s), "sensors.gyro_arw_deg_sqrt_h must be >= 0");
  RequireFilterConfig(non_negative(c.sensors.accel_bias_mps2), "sensors.accel_bias_ug must be >= 0");
  RequireFilterConfig(non_negative(c.sensors.accel_vrw_mps_per_sqrt_s), "sensors.accel_vrw_m_s_sqrt_h must be >= 0");
  RequireFilterConfig(positive(c.initial.position_m), "initial.position_m must be > 0");
  RequireFilterConfig(positive(c.initial.velocity_mps) || c.initial.velocity_mps == 0.0, "initial.velocity_mps must be >= 0");
  RequireFilterConfig(positive(c.initial.level_rad), "initial.level_arcmin must be > 0");
  RequireFilterConfig(positive(c.initial.heading_rad), "initial.heading_arcmin must be > 0");
  RequireFilterConfig(positive(c.baro.time_constant_s), "baro.time_constant_s must be > 0");
  RequireFilterConfig(positive(c.distance.threshold_m), "distance.threshold_km must be > 0");
  RequireFilterConfig(non_negative(c.distance.recompute_every_m), "distance.recompute_every_km must be >= 0");
}

// The separation options of the distance method (filter.h, docs): Schuler rate at the
// start, the position sigma of the (raw) fixes, every term but the velocity one when the
// initial velocity is known exactly, and the sensor specification as priors.
SeparationOptions DistanceSeparationOptions(const InflightConfig& c, const NavState& initial,
                                            double position_sigma_m) {
  SeparationOptions o;
  o.schuler_rate_radps = SchulerRate(initial.lat_rad, initial.h_m);
  o.position_sigma_m = position_sigma_m;
  o.terms = {{true, c.initial.velocity_mps > 0.0, true, true}};
  const double ba_mps2 = c.sensors.accel_bias_mps2;
  const double bg_radps = c.sensors.gyro_bias_radps;
  const double level_rad = c.initial.level_rad;
  // The Earth-rate coupling of the initial heading error, Omega_ie cos L sigma_psi0, acts
  // like an east gyro bias (d phi_E / dt = Omega cos L phi_D), which drives the NORTH
  // position error: the north gyro term's prior is widened by it, the east one is not
  // (docs/inflight-alignment.md).
  const double earth_rate_heading_radps =
      wgs84::kOmegaIe_radps * std::cos(initial.lat_rad) * c.initial.heading_rad;
  o.prior_sigma[static_cast<int>(SchulerTerm::kOffset)] = c.initial.position_m;
  o.prior_sigma[static_cast<int>(SchulerTerm::kVelocity)] = c.initial.velocity_mps;
  o.prior_sigma[static_cast<int>(SchulerTerm::kTilt)] = std::hypot(ba_mps2, kStandardGravity_mps2 * level_rad);
  o.prior_sigma[static_cast<int>(SchulerTerm::kGyro)] = kStandardGravity_mps2 * bg_radps;
  o.prior_sigma_north[static_cast<int>(SchulerTerm::kGyro)] = kStandardGravity_mps2 * std::hypot(bg_radps, earth_rate_heading_radps);
  return o;
}

std::string TimeText(double t_s) {
  std::ostringstream s;
  s.precision(10);
  s << t_s;
  return s.str();
}

}  // namespace

const char* FilterMethodName(FilterMethod method) {
  switch (method) {
    case FilterMethod::kDistance:
      return "distance";
    case FilterMethod::kKalman:
      return "kalman";
  }
  return "unknown";
}

FilterRun RunInflightFilter(const InflightInputs& inputs, const InflightConfig& config, FilterMethod method) {
  const auto wall_start = std::chrono::steady_clock::now();
  ValidateInputs(inputs);
  CheckConfig(config);
  const bool distance = method == FilterMethod::kDistance;
  const NavState& initial = inputs.initial;
  const double t0_s = initial.t_s;

  FilterRun run;
  run.method = method;

  // ---- nominal state: the INS (raw IMU corrected by the bias estimates) and the estimates
  ins::InsState ins;  // nav + estimated IMU errors (body x, y biases; z and scale factors 0)
  ins.nav = initial;
  Strapdown strapdown(initial);

  // ---- process noise: white noise only; the biases are random constants whose
  // uncertainty is the specification in the initial P (no driving noise, infinite
  // correlation time).
  ins::ImuNoise noise;
  noise.gyro_arw_rad_per_sqrt_s = config.sensors.gyro_arw_rad_per_sqrt_s;
  noise.accel_vrw_mps_per_sqrt_s = config.sensors.accel_vrw_mps_per_sqrt_s;
  noise.gyro_bias_std_radps = 0.0;
  noise.accel_bias_std_mps2 = 0.0;
  noise.correlation_time_s = std::numeric_limits<double>::infinity();

  // ---- initial covariance (config.initial and the bias specification)
  Matrix11 P = Matrix11::Zero();
  const double level_rad = config.initial.level_rad;
  const double heading_rad = config.initial.heading_rad;
  const double bg_radps = config.sensors.gyro_bias_radps;
  const double ba_mps2 = config.sensors.accel_bias_mps2;
  for (int k = 0; k < 2; ++k) {
    P(fstate::kPos + k, fstate::kPos + k) = config.initial.position_m * config.initial.position_m;
    P(fstate::kVel + k, fstate::kVel + k) = config.initial.velocity_mps * config.initial.velocity_mps;
    P(fstate::kLevel + k, fstate::kLevel + k) = level_rad * level_rad;
    P(fstate::kBg + k, fstate::kBg + k) = bg_radps * bg_radps;
    P(fstate::kBa + k, fstate::kBa + k) = ba_mps2 * ba_mps2;
  }
  P(fstate::kHeading, fstate::kHeading) = heading_rad * heading_rad;

  const bool smooth_gps = distance ? config.smooth_gps_distance : config.smooth_gps_kalman;
  GpsSmoother smoother(config.smoother);
  // Raw fixes (smooth_gps false): their sigma and the chi-square gate on the 2-dof
  // innovation, whose quantile is -2 ln(1 - p).
  const double raw_sigma_m = smooth_gps ? 0.0
                             : config.sensors.gps_sigma_m > 0.0 ? config.sensors.gps_sigma_m
                                                                : EstimateGpsSigma(inputs.gnss);
  const double raw_gate_nis = config.smoother.gate_probability >= 1.0
                                  ? std::numeric_limits<double>::infinity()
                                  : -2.0 * std::log(1.0 - config.smoother.gate_probability);

  // ---- distance method: the free INS alongside and its samples at accepted fixes
  std::optional<FreeInsTrack> free_ins;
  if (distance) free_ins.emplace(initial, config.baro);
  std::vector<DistanceErrorSample> samples;
  double next_computation_m = config.distance.threshold_m;
  double heading_applied_rad = 0.0;  // sum of the corrections fed back so far

  // ---- covariance propagation over blocks of ~kBlock_s
  Eigen::Vector3d block_dtheta_rad = Eigen::Vector3d::Zero(), block_dv_mps = Eigen::Vector3d::Zero();
  double block_dt_s = 0.0;
  Eigen::MatrixXd Phi15, Qd15;
  auto propagate = [&]() {
    if (block_dt_s <= 0.0) return;
    ins.nav = strapdown.state();
    // Mean bias-corrected specific force and rate over the block, the INS state at its end.
    ins::DiscreteErrorDynamics(ins, block_dv_mps / block_dt_s, block_dtheta_rad / block_dt_s, noise,
                                    ins::err::kSize15, block_dt_s, &Phi15, &Qd15);
    // The filter's rows and columns: the vertical channel (held by the baro loop) and the
    // z biases (unobservable in level flight, negligible over minutes) are left out.
    const Matrix11 Phi = Sub(Phi15);
    P = Phi * P * Phi.transpose() + Sub(Qd15);
    P = 0.5 * (P + P.transpose()).eval();
    block_dtheta_rad.setZero();
    block_dv_mps.setZero();
    block_dt_s = 0.0;
  };

  // ---- path length of the filter INS (trapezoid of the horizontal speed)
  double path_length_m = 0.0;
  double last_speed_mps = initial.v_n_mps.head<2>().norm();
  double last_t_s = t0_s;

  auto step = [&](const ImuSample& raw) {
    const double baro_m = BaroAltitudeAt(inputs.baro, raw.t_s);
    const ImuSample corrected = ins::CorrectImu(raw, ins.imu);
    const double h_before_m = strapdown.state().h_m;
    strapdown.Update(corrected);
    NavState nav = strapdown.state();
    if (std::isfinite(baro_m)) {
      ApplyBaroLoop(baro_m, raw.dt_s, config.baro, &nav);
    } else {
      nav.h_m = h_before_m;  // no barometer: height held (as FreeInsTrack does)
      nav.v_n_mps.z() = 0.0;
    }
    strapdown.SetState(nav);
    block_dtheta_rad += corrected.dtheta_b_rad;
    block_dv_mps += corrected.dv_b_mps;
    block_dt_s += corrected.dt_s;
    if (block_dt_s >= kBlock_s - ins::kSameEpoch_s) propagate();
    const double speed_mps = nav.v_n_mps.head<2>().norm();
    path_length_m += 0.5 * (last_speed_mps + speed_mps) * (nav.t_s - last_t_s);
    last_speed_mps = speed_mps;
    last_t_s = nav.t_s;
    if (free_ins) free_ins->Update(raw, baro_m);  // same IMU, raw (no bias correction)
  };

  // Feeds a 15-state correction (true minus estimate) into the INS and the bias estimates.
  auto feed_back = [&](const Eigen::VectorXd& dx15) {
    ins.nav = strapdown.state();
    ins = ins::ApplyCorrection(ins, dx15);
    strapdown.SetState(ins.nav);
  };

  auto check_finite = [&](double t_s) {
    const NavState& n = strapdown.state();
    if (!P.allFinite() || !std::isfinite(n.lat_rad) || !std::isfinite(n.lon_rad) || !std::isfinite(n.h_m) ||
        !n.v_n_mps.allFinite() || !n.q_n_b.coeffs().allFinite() || !ins.imu.bg_radps.allFinite() ||
        !ins.imu.ba_mps2.allFinite()) {
      throw std::runtime_error("RunInflightFilter (" + std::string(FilterMethodName(method)) +
                               "): the filter diverged (non-finite state) at t = " + TimeText(t_s) + " s");
    }
  };

  std::size_t next_imu = 0;
  while (next_imu < inputs.imu.size() && inputs.imu[next_imu].t_s <= t0_s + ins::kSameEpoch_s) ++next_imu;
  const double t_end_s = inputs.imu.back().t_s;

  for (const GnssSample& fix : inputs.gnss) {
    if (fix.t_s < t0_s - ins::kSameEpoch_s) continue;  // before the alignment started
    if (fix.t_s > t_end_s + ins::kSameEpoch_s) break;  // after the IMU data
    // Step the INS to the first IMU epoch at or after the fix (at most one IMU interval
    // late; the INS position is moved back to the fix time below).
    while (strapdown.state().t_s < fix.t_s - ins::kSameEpoch_s && next_imu < inputs.imu.size()) {
      step(inputs.imu[next_imu++]);
    }
    propagate();  // P to the INS epoch (the partial block)

    FilterEpoch epoch;
    epoch.t_s = fix.t_s;
    // The GPS position of the fix and its sigma: smoothed (the seed) or raw.
    wgs84::Geodetic gps{fix.lat_rad, fix.lon_rad, fix.h_m};
    Eigen::Vector2d r_sigma_m = Eigen::Vector2d::Constant(raw_sigma_m);
    bool accepted = true;
    if (smooth_gps) {
      const SmoothedFix smoothed = smoother.Update(fix);
      accepted = !smoothed.rejected;
      gps = wgs84::Geodetic{smoothed.lat_rad, smoothed.lon_rad, smoothed.h_m};
      // R: the smoother's RAW-measurement sigma, not the smoothed fix's own (smaller)
      // sigma. Consecutive smoothed fixes share most of their raw data, so their errors
      // are strongly correlated in time; a white-noise update with the smoothed sigma would
      // count the same raw fix many times over and make the filter overconfident. With the
      // raw sigma the sequence of updates carries about the information of the raw fixes,
      // while the smoother's role is to remove the outliers and jumps.
      r_sigma_m = smoothed.measurement_sigma_ned_m.head<2>();
    }
    // Measurement: GPS minus INS position moved back to the fix time, NED metres in the
    // error-state convention (true minus estimate):
    //   z = [(lat_gps - lat_ins)(M + h), (lon_gps - lon_ins)(N + h) cos lat] = dp_NE + v.
    const NavState& nav = strapdown.state();
    const double dt_back_s = nav.t_s - fix.t_s;
    const double rm = wgs84::MeridianRadius(nav.lat_rad) + nav.h_m;
    const double rn = wgs84::PrimeVerticalRadius(nav.lat_rad) + nav.h_m;
    const double lat_ins = nav.lat_rad - nav.v_n_mps.x() * dt_back_s / rm;
    const double lon_ins = nav.lon_rad - nav.v_n_mps.y() * dt_back_s / (rn * std::cos(nav.lat_rad));
    const Eigen::Vector2d z((gps.lat_rad - lat_ins) * rm, WrapPi(gps.lon_rad - lon_ins) * rn * std::cos(nav.lat_rad));
    const Eigen::Matrix2d R = r_sigma_m.cwiseAbs2().asDiagonal();
    // H = [I2 0]: P H^T is P's first two columns.
    const Eigen::Matrix2d S = P.topLeftCorner<2, 2>() + R;
    const Eigen::Matrix2d S_inv = S.inverse();
    // Raw fixes: the filter's own gate (the smoother has gated smoothed ones).
    if (accepted && !smooth_gps) accepted = z.dot(S_inv * z) <= raw_gate_nis;
    if (!accepted) {
      ++run.gps_rejected;
    } else {
      Gain K = P.leftCols<2>() * S_inv;
      // Distance method: phi_D is a consider state (Schmidt-Kalman); its gain row is zero,
      // so the heading estimate never moves, while its variance and correlations still
      // shape the other gains. The Joseph form below keeps P right for any gain.
      if (distance) K.row(fstate::kHeading).setZero();
      const Vector11 dx = K * z;
      Matrix11 A = Matrix11::Identity();
      A.leftCols<2>() -= K;  // I - K H
      P = A * P * A.transpose() + K * R * K.transpose();
      P = 0.5 * (P + P.transpose()).eval();

      Eigen::VectorXd dx15 = Eigen::VectorXd::Zero(ins::err::kSize15);  // vertical, z biases: 0
      for (int i = 0; i < kFilterStates; ++i) dx15(kIn15[i]) = dx(i);
      feed_back(dx15);  // the error state is zero again
      epoch.innovation_ne_m = z;
      epoch.gps_used = true;

      if (distance) {
        samples.push_back(free_ins->SampleAt(fix.t_s, gps));
        if (path_length_m >= next_computation_m) {
          // Heading computation (equation 8 with the Schuler part removed) over every
          // sample since the start. A fit that cannot be made yet (no displacement gained:
          // SeparateHeadingError throws) is tried again at the next accepted fix.
          const double position_sigma_m = r_sigma_m.maxCoeff();
          bool computed = false;
          try {
            const HeadingSeparation sep =
                SeparateHeadingError(samples, DistanceSeparationOptions(config, initial, position_sigma_m));
            HeadingComputation hc;
            hc.t_s = fix.t_s;
            hc.path_length_m = path_length_m;
            hc.dh_rad = sep.dh_rad;
            hc.sigma_rad = sep.sigma_rad;
            // dH is the free INS's heading error; the filter INS (same gyros, phi_D never
            // updated) carries dH less what has been corrected already.
            hc.correction_rad = sep.dh_rad - heading_applied_rad;
            hc.separation = sep;
            // yaw -= correction: attitude error phi = (0, 0, -correction), since a
            // rotation phi_D about down adds phi_D to the yaw (distance_heading.h).
            Eigen::VectorXd dphi = Eigen::VectorXd::Zero(ins::err::kSize15);
            dphi(ins::err::kAtt + 2) = -hc.correction_rad;
            feed_back(dphi);
            heading_applied_rad = sep.dh_rad;
            // A new, independent heading estimate.
            ResetState(fstate::kHeading, sep.sigma_rad * sep.sigma_rad, &P);
            run.computations.push_back(hc);
            computed = true;
          } catch (const std::invalid_argument&) {
            // not computable yet (see above)
          }
          const double every_m = config.distance.recompute_every_m;
          if (!computed) {
            // keep next_computation_m: retry at the next fix
          } else if (every_m > 0.0) {
            while (next_computation_m <= path_length_m) next_computation_m += every_m;
          } else {
            next_computation_m = std::numeric_limits<double>::infinity();
          }
        }
      }
    }
    check_finite(fix.t_s);
    epoch.path_length_m = path_length_m;
    epoch.nav = strapdown.state();
    epoch.sigma = P.diagonal().cwiseMax(0.0).cwiseSqrt();
    epoch.yaw_sigma_rad = epoch.sigma(fstate::kHeading);
    run.epochs.push_back(epoch);
  }
  run.run_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return run;
}

}  // namespace navtwin::inflight
