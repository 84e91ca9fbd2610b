// Support of the navigation filter (problems/gnss_ins/filter.h): initial state per
// InitConfig::Source (and the static alignment's heading, a search in heading_search.cc),
// initial standard deviations, magnetometer calibration, measurement
// sigmas and ZUPT stillness detection. The main loop is in filter.cc.
#include "problems/gnss_ins/filter.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/earth.h"
#include "core/io/input_error.h"
#include "core/rotation.h"
#include "problems/gnss_ins/alignment.h"
#include "problems/gnss_ins/error_dynamics.h"
#include "problems/gnss_ins/heading_search.h"

namespace navtwin::gnss_ins {
namespace {

constexpr double kTimeEps_s = 1e-6;

std::string Seconds(double t_s) {
  std::ostringstream s;
  s.precision(12);
  s << t_s << " s";
  return s.str();
}

/// Zero entries of `given` replaced by `fallback`.
Eigen::Vector3d OrDefault(const Eigen::Vector3d& given, double fallback) {
  Eigen::Vector3d out = given;
  for (int i = 0; i < 3; ++i) {
    if (out[i] == 0.0) out[i] = fallback;
  }
  return out;
}

/// The IMU reference point from an antenna fix: p_imu = p_ant - R_n_b l_b (exact, ECEF).
void ImuPositionFromAntenna(const GnssSample& fix, const Eigen::Quaterniond& q_n_b,
                            const Eigen::Vector3d& lever_arm_b_m, NavState* nav) {
  const wgs84::Geodetic p =
      wgs84::NedToGeodetic(-(q_n_b * lever_arm_b_m), {fix.lat_rad, fix.lon_rad, fix.h_m});
  nav->lat_rad = p.lat_rad;
  nav->lon_rad = p.lon_rad;
  nav->h_m = p.h_m;
}

bool AnyNonZero(const ImuErrors& e) {
  return !e.bg_radps.isZero(0.0) || !e.ba_mps2.isZero(0.0) || !e.sg.isZero(0.0) || !e.sa.isZero(0.0);
}

FilterStart GivenStart(const Inputs& inputs, const GnssInsConfig& config) {
  if (!config.init.state) {
    throw std::invalid_argument("RunFilter: init.source given needs init.state");
  }
  FilterStart start;
  start.state = *config.init.state;
  if (AnyNonZero(config.init.imu_errors)) start.state.imu = config.init.imu_errors;
  const double imu_begin_s = inputs.imu.front().t_s - inputs.imu.front().dt_s;
  // A start before the IMU record is taken at its beginning (as KF-GINS does with a
  // starttime before the first IMU sample).
  if (start.state.nav.t_s < imu_begin_s) start.state.nav.t_s = imu_begin_s;
  start.use_measurements_at_start = true;
  return start;
}

FilterStart StaticAlignmentStart(const Inputs& inputs, const GnssInsConfig& config, std::ostream* progress) {
  const InitConfig& init = config.init;
  const double begin_s = inputs.imu.front().t_s - inputs.imu.front().dt_s;
  const double end_s = begin_s + init.static_duration_s;
  std::vector<ImuSample> samples;
  for (const ImuSample& s : inputs.imu) {
    if (s.t_s > end_s + kTimeEps_s) break;
    samples.push_back(CorrectImu(s, init.imu_errors));
  }
  if (inputs.gnss.empty()) {
    throw InputError(inputs.paths.gnss, 0, "position",
                     "static alignment takes the position from the first GNSS fix, and the GNSS "
                     "record is empty");
  }
  const GnssSample& fix = inputs.gnss.front();
  // The heading reference: the magnetometer (kMagnetometer, or kAuto with one), else the
  // mean angular rate (gyrocompassing; for kSearch only roll and pitch are kept).
  const InitConfig::Heading heading = init.heading;
  const bool mag_on = config.mag.mode != MagConfig::Mode::kOff;
  if (heading == InitConfig::Heading::kMagnetometer && !mag_on) {
    throw std::invalid_argument("RunFilter: init.heading magnetometer needs mag.mode other than off");
  }
  std::optional<Eigen::Vector3d> m_b_uT;
  if (heading == InitConfig::Heading::kMagnetometer || (heading == InitConfig::Heading::kAuto && mag_on)) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (const MagSample& m : inputs.mag) {
      if (m.t_s < begin_s - kTimeEps_s) continue;
      if (m.t_s > samples.back().t_s + kTimeEps_s) break;
      sum += CalibrateMag(m.m_b_uT, config.mag);
      ++count;
    }
    if (count > 0) m_b_uT = sum / count;
    if (count == 0 && heading == InitConfig::Heading::kMagnetometer) {
      throw InputError(inputs.paths.mag, 0, "heading",
                       "no magnetometer sample in the static alignment window (the first " +
                           Seconds(init.static_duration_s) + " of IMU data)");
    }
  }
  FilterStart start;
  start.state.imu = init.imu_errors;
  NavState& nav = start.state.nav;
  try {
    nav.q_n_b = StaticCoarseAlignment(samples, fix.lat_rad, m_b_uT, config.mag.declination_rad);
  } catch (const std::invalid_argument& e) {
    throw InputError(inputs.paths.imu, 0, "static alignment",
                     std::string(e.what()) + " (the first " + Seconds(init.static_duration_s) +
                         " of IMU data)");
  }
  ImuPositionFromAntenna(fix, nav.q_n_b, config.installation.antenna_lever_arm_b_m, &nav);
  nav.v_n_mps.setZero();
  nav.t_s = samples.back().t_s;
  nav.gps_week = fix.gps_week;
  start.use_measurements_at_start = false;
  if (heading == InitConfig::Heading::kSearch) {
    // Roll and pitch from the alignment, the heading from the search; the IMU position
    // follows the heading through the lever arm.
    const Eigen::Vector3d rpy = EulerFromQuat<double>(nav.q_n_b);
    const InsState levelled = start.state;
    const auto state_for_yaw = [&](double yaw_rad) {
      InsState s = levelled;
      s.nav.q_n_b = QuatFromEuler<double>(rpy[0], rpy[1], yaw_rad);
      ImuPositionFromAntenna(fix, s.nav.q_n_b, config.installation.antenna_lever_arm_b_m, &s.nav);
      return s;
    };
    const HeadingSearchResult search = SearchHeading(inputs, config, state_for_yaw, progress);
    start.state = state_for_yaw(search.hypotheses[search.best].yaw_rad);
  }
  return start;
}

FilterStart GnssVelocityStart(const Inputs& inputs, const GnssInsConfig& config) {
  const double imu_begin_s = inputs.imu.front().t_s - inputs.imu.front().dt_s;
  const double imu_end_s = inputs.imu.back().t_s;
  for (const GnssSample& fix : inputs.gnss) {
    if (fix.t_s < imu_begin_s || fix.t_s >= imu_end_s) continue;
    if (!fix.has_velocity || fix.v_n_mps.head<2>().norm() < config.init.min_speed_mps) continue;
    FilterStart start;
    start.state.imu = config.init.imu_errors;
    NavState& nav = start.state.nav;
    nav.q_n_b = AttitudeFromGnssVelocity(fix.v_n_mps);
    ImuPositionFromAntenna(fix, nav.q_n_b, config.installation.antenna_lever_arm_b_m, &nav);
    nav.v_n_mps = fix.v_n_mps;
    nav.t_s = fix.t_s;
    nav.gps_week = fix.gps_week;
    start.use_measurements_at_start = false;  // the fix at the start made the state
    return start;
  }
  std::ostringstream reason;
  reason << "no GNSS fix with velocity and a horizontal speed of at least " << config.init.min_speed_mps
         << " m/s inside the IMU record: cannot take the heading from the GNSS velocity";
  throw InputError(inputs.paths.gnss, 0, "velocity", reason.str());
}

/// x * y for small fixed-size matrices, coefficient-based (Eigen would otherwise take its
/// blocked GEMM path, slow at 9 x 9).
template <typename X, typename Y>
auto Mul(const Eigen::MatrixBase<X>& x, const Eigen::MatrixBase<Y>& y) {
  return x.lazyProduct(y).eval();
}

/// PropagateCovariance for S IMU-error states (6 or 12); see filter.h for the block form.
template <int S>
void PropagateBlocks(const Eigen::MatrixXd& F, const Eigen::MatrixXd& G, const Eigen::VectorXd& qc,
                     double dt, Eigen::MatrixXd* P, Eigen::MatrixXd* phi_acc) {
  constexpr int N = 9;  // navigation states: dp, dv, phi
  using MatNN = Eigen::Matrix<double, N, N>;
  using MatNS = Eigen::Matrix<double, N, S>;
  using MatSS = Eigen::Matrix<double, S, S>;
  // F dt = [[a, b], [0, c]]  =>  (F dt)^2 = [[a^2, a b + b c], [0, c^2]] and
  // Phi = [[A, B], [0, D]] = I + F dt + (F dt)^2 / 2.
  const MatNN a = F.topLeftCorner<N, N>() * dt;
  const MatNS b = F.topRightCorner<N, S>() * dt;
  const MatSS c = F.bottomRightCorner<S, S>() * dt;
  MatNN A = a + 0.5 * Mul(a, a);
  A.diagonal().array() += 1.0;
  const MatNS B = b + 0.5 * (Mul(a, b) + Mul(b, c));
  MatSS D = c + 0.5 * Mul(c, c);
  D.diagonal().array() += 1.0;
  // G Qc G^T = blockdiag(Qn, diag(qs)).
  const Eigen::Matrix<double, N, 6> Gn = G.topLeftCorner<N, 6>();
  const Eigen::Matrix<double, N, 6> Gq = Gn * qc.head<6>().asDiagonal();
  const MatNN Qn = Mul(Gq, Gn.transpose());
  // G maps the IMU-error driving noises w[6 .. 6 + S) onto the IMU-error rows (identity).
  const Eigen::Matrix<double, S, 1> qs = qc.segment<S>(6);
  // Phi P Phi^T with P = [[Pnn, Pns], [Pns^T, Pss]].
  const MatNN Pnn = P->topLeftCorner<N, N>();
  const MatNS Pns = P->topRightCorner<N, S>();
  const MatSS Pss = P->bottomRightCorner<S, S>();
  const MatNN M1 = Mul(A, Pnn) + Mul(B, Pns.transpose());
  const MatNS M2 = Mul(A, Pns) + Mul(B, Pss);
  MatNN Nnn = Mul(M1, A.transpose()) + Mul(M2, B.transpose());
  MatNS Nns = Mul(M2, D.transpose());
  MatSS Nss = Mul(Mul(D, Pss), D.transpose());
  // + Qd = dt/2 (Phi GQG Phi^T + GQG), Phi GQG Phi^T = [[A Qn A^T + B Qs B^T, B Qs D^T], [., D Qs D^T]].
  const MatNS Bq = B * qs.asDiagonal();
  Nnn += (0.5 * dt) * (Mul(Mul(A, Qn), A.transpose()) + Mul(Bq, B.transpose()) + Qn);
  Nns += (0.5 * dt) * Mul(Bq, D.transpose());
  const MatSS Dq = D * qs.asDiagonal();
  MatSS Qss = Mul(Dq, D.transpose());
  Qss.diagonal() += qs;
  Nss += (0.5 * dt) * Qss;
  P->topLeftCorner<N, N>() = 0.5 * (Nnn + Nnn.transpose());
  P->topRightCorner<N, S>() = Nns;
  P->bottomLeftCorner<S, N>() = Nns.transpose();
  P->bottomRightCorner<S, S>() = 0.5 * (Nss + Nss.transpose());
  if (phi_acc != nullptr) {
    // [[A, B], [0, D]] [[Xnn, Xns], [0, Xss]] = [[A Xnn, A Xns + B Xss], [0, D Xss]].
    const MatNN Xnn = phi_acc->topLeftCorner<N, N>();
    const MatNS Xns = phi_acc->topRightCorner<N, S>();
    const MatSS Xss = phi_acc->bottomRightCorner<S, S>();
    phi_acc->topLeftCorner<N, N>() = Mul(A, Xnn);
    phi_acc->topRightCorner<N, S>() = Mul(A, Xns) + Mul(B, Xss);
    phi_acc->bottomRightCorner<S, S>() = Mul(D, Xss);
  }
}

}  // namespace

void PropagateCovariance(const InsState& x, const Eigen::Vector3d& f_b_mps2,
                         const Eigen::Vector3d& omega_ib_b_radps, const ImuNoise& noise, double dt_s,
                         Eigen::MatrixXd* P, Eigen::MatrixXd* phi_acc) {
  const int n = static_cast<int>(P->rows());
  if ((n != err::kSize15 && n != err::kSize21) || P->cols() != n ||
      (phi_acc != nullptr && (phi_acc->rows() != n || phi_acc->cols() != n))) {
    throw std::invalid_argument("PropagateCovariance: P (and phi_acc) must be 15 x 15 or 21 x 21");
  }
  if (!(dt_s >= 0.0) || !std::isfinite(dt_s)) {
    throw std::invalid_argument("PropagateCovariance: dt_s must be finite and non-negative");
  }
  const Eigen::MatrixXd F = ErrorDynamicsF(x, f_b_mps2, omega_ib_b_radps, noise, n);
  const Eigen::MatrixXd G = ErrorDynamicsG(x, n);
  const Eigen::VectorXd qc = ErrorDynamicsQc(noise, n);
  if (n == err::kSize15) {
    PropagateBlocks<6>(F, G, qc, dt_s, P, phi_acc);
  } else {
    PropagateBlocks<12>(F, G, qc, dt_s, P, phi_acc);
  }
}

Eigen::VectorXd InitialStdVector(const GnssInsConfig& config, int n) {
  if (n != err::kSize15 && n != err::kSize21) {
    throw std::invalid_argument("InitialStdVector: n must be 15 or 21");
  }
  const InitialStd& s = config.init.std;
  const ImuNoise& noise = config.imu_noise;
  Eigen::VectorXd std(n);
  std.segment<3>(err::kPos) = s.pos_ned_m;
  std.segment<3>(err::kVel) = s.vel_ned_mps;
  std.segment<3>(err::kAtt) = s.att_rad;
  if (config.init.source == InitConfig::Source::kStaticAlignment &&
      config.init.heading == InitConfig::Heading::kSearch) {
    std[err::kAtt + 2] = HeadingSearchYawStd(config.init.heading_hypotheses);
  }
  std.segment<3>(err::kBg) = OrDefault(s.bg_radps, noise.gyro_bias_std_radps);
  std.segment<3>(err::kBa) = OrDefault(s.ba_mps2, noise.accel_bias_std_mps2);
  if (n == err::kSize21) {
    std.segment<3>(err::kSg) = OrDefault(s.sg, noise.gyro_scale_std);
    std.segment<3>(err::kSa) = OrDefault(s.sa, noise.accel_scale_std);
  }
  if (!std.allFinite() || (std.array() < 0.0).any()) {
    throw std::invalid_argument("InitialStdVector: initial standard deviations must be finite and >= 0");
  }
  return std;
}

Eigen::Vector3d CalibrateMag(const Eigen::Vector3d& m_raw_uT, const MagConfig& mag) {
  const Eigen::Matrix3d I_plus_S = Eigen::Matrix3d::Identity() + mag.soft_iron;
  return I_plus_S.partialPivLu().solve(m_raw_uT - mag.hard_iron_uT);
}

Eigen::Vector3d MeasurementSigma(const Eigen::Vector3d& file_sigma, double floor, double fallback) {
  Eigen::Vector3d s;
  for (int i = 0; i < 3; ++i) {
    s[i] = std::isfinite(file_sigma[i]) ? std::max(file_sigma[i], floor) : std::max(fallback, floor);
  }
  return s;
}

void StillnessDetector::Add(const ImuSample& s) {
  Entry e;
  e.begin_s = s.t_s - s.dt_s;
  e.moving = s.dtheta_b_rad.norm() / s.dt_s > config_.gyro_threshold_radps;
  e.f_mps2 = s.dv_b_mps.norm() / s.dt_s - 9.8;
  window_.push_back(e);
  moving_ += e.moving;
  sum_ += e.f_mps2;
  sum_sq_ += e.f_mps2 * e.f_mps2;
  // Drop the oldest samples while the rest still cover the window.
  const double window_begin_s = s.t_s - config_.window_s;
  while (window_.size() > 1 && window_[1].begin_s <= window_begin_s + kTimeEps_s) {
    const Entry& old = window_.front();
    moving_ -= old.moving;
    sum_ -= old.f_mps2;
    sum_sq_ -= old.f_mps2 * old.f_mps2;
    window_.pop_front();
  }
  full_ = window_.front().begin_s <= window_begin_s + kTimeEps_s;
}

bool StillnessDetector::Still() const {
  if (!full_ || moving_ > 0) return false;
  const double n = static_cast<double>(window_.size());
  const double mean = sum_ / n;
  const double var = std::max(0.0, sum_sq_ / n - mean * mean);
  return std::sqrt(var) <= config_.accel_std_threshold_mps2;
}

FilterStart InitialFilterState(const Inputs& inputs, const GnssInsConfig& config, std::ostream* progress) {
  if (inputs.imu.empty()) throw InputError(inputs.paths.imu, 0, "", "no IMU samples");
  switch (config.init.source) {
    case InitConfig::Source::kGiven:
      return GivenStart(inputs, config);
    case InitConfig::Source::kStaticAlignment:
      return StaticAlignmentStart(inputs, config, progress);
    case InitConfig::Source::kGnssVelocity:
      return GnssVelocityStart(inputs, config);
  }
  throw std::invalid_argument("RunFilter: unknown init.source");
}

}  // namespace navtwin::gnss_ins
