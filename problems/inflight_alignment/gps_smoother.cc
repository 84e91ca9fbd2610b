#include "problems/inflight_alignment/gps_smoother.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

#include "core/rotation.h"
#include "solvers/eskf.h"

namespace navtwin::inflight {
namespace {

constexpr int kQuiet = 0;
constexpr int kManeuver = 1;
// Consecutive intervals within this fraction of each other count as equally spaced.
constexpr double kEvenIntervalTolerance = 0.01;

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

void Require(bool ok, const char* option, const std::string& rule) {
  if (!ok) throw std::invalid_argument(std::string("GpsSmootherOptions.") + option + " " + rule);
}

bool PositiveFinite(double x) { return std::isfinite(x) && x > 0.0; }

void ValidateOptions(const GpsSmootherOptions& o) {
  Require(PositiveFinite(o.quiet_accel_noise_mps2_sqrt_hz), "quiet_accel_noise_mps2_sqrt_hz",
          "must be finite and > 0");
  Require(PositiveFinite(o.maneuver_accel_noise_mps2_sqrt_hz), "maneuver_accel_noise_mps2_sqrt_hz",
          "must be finite and > 0");
  Require(PositiveFinite(o.maneuver_mean_interval_s), "maneuver_mean_interval_s", "must be finite and > 0");
  Require(PositiveFinite(o.maneuver_mean_duration_s), "maneuver_mean_duration_s", "must be finite and > 0");
  Require(o.initial_position_sigma_ned_m.allFinite() && (o.initial_position_sigma_ned_m.array() > 0.0).all(),
          "initial_position_sigma_ned_m", "must be finite and > 0 on every axis");
  Require(PositiveFinite(o.initial_speed_sigma_mps), "initial_speed_sigma_mps", "must be finite and > 0");
  Require(o.noise_window_fixes >= 1, "noise_window_fixes", "must be >= 1");
  Require(o.noise_min_fixes >= 1 && o.noise_min_fixes <= o.noise_window_fixes, "noise_min_fixes",
          "must be in [1, noise_window_fixes]");
  Require(PositiveFinite(o.min_position_sigma_m), "min_position_sigma_m", "must be finite and > 0");
  Require(std::isfinite(o.max_position_sigma_m) && o.max_position_sigma_m >= o.min_position_sigma_m,
          "max_position_sigma_m", "must be finite and >= min_position_sigma_m");
  Require(o.gate_probability > 0.0 && o.gate_probability <= 1.0, "gate_probability", "must be in (0, 1]");
  Require(o.reset_after_rejections >= 1, "reset_after_rejections", "must be >= 1");
}

std::string Number(double x) {
  std::ostringstream s;
  s.precision(17);
  s << x;
  return s.str();
}

void RequireFinite(double value, const char* field) {
  if (!std::isfinite(value)) {
    throw std::invalid_argument(std::string("GpsSmoother::Update: GnssSample.") + field +
                                " is not finite (" + Number(value) + ")");
  }
}

// Constant-velocity transition over dt for [pos; vel] (3 axes each).
Matrix6d Transition(double dt_s) {
  Matrix6d F = Matrix6d::Identity();
  F.topRightCorner<3, 3>().diagonal().setConstant(dt_s);
  return F;
}

// Discrete process noise of white acceleration with PSD q (m^2/s^3) over dt, per axis:
// q [dt^3/3, dt^2/2; dt^2/2, dt].
Matrix6d ProcessNoise(double q, double dt_s) {
  Matrix6d Q = Matrix6d::Zero();
  Q.topLeftCorner<3, 3>().diagonal().setConstant(q * dt_s * dt_s * dt_s / 3.0);
  Q.topRightCorner<3, 3>().diagonal().setConstant(q * dt_s * dt_s / 2.0);
  Q.bottomLeftCorner<3, 3>().diagonal().setConstant(q * dt_s * dt_s / 2.0);
  Q.bottomRightCorner<3, 3>().diagonal().setConstant(q * dt_s);
  return Q;
}

// One mode's prediction and its innovation for position measurement z with covariance R.
struct ModeInnovation {
  Vector6d x;
  Matrix6d P;
  Eigen::Vector3d nu;
  Eigen::Matrix3d S;
  double nis = 0.0;
  double log_det_s = 0.0;
};

ModeInnovation Innovate(const Vector6d& x_pred, const Matrix6d& P_pred, const Eigen::Vector3d& z,
                        const Eigen::Matrix3d& R) {
  ModeInnovation m;
  m.x = x_pred;
  m.P = P_pred;
  m.nu = z - x_pred.head<3>();
  m.S = P_pred.topLeftCorner<3, 3>() + R;
  const Eigen::LLT<Eigen::Matrix3d> llt(m.S);
  if (llt.info() != Eigen::Success) throw std::runtime_error("GpsSmoother: innovation covariance not positive definite");
  m.nis = m.nu.dot(llt.solve(m.nu));
  m.log_det_s = 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
  return m;
}

// The combined estimate of the modes: the probability-weighted mean and covariance
// (spread of the means included).
void Combine(const std::array<GpsSmoother::ModeState, 2>& modes, Vector6d* x, Matrix6d* P) {
  x->setZero();
  for (const auto& m : modes) *x += m.probability * m.x;
  P->setZero();
  for (const auto& m : modes) {
    const Vector6d dx = m.x - *x;
    *P += m.probability * (m.P + dx * dx.transpose());
  }
}

// IMM mixing and prediction over dt: each mode starts from the probability-weighted
// mix of the modes (pi(i, j) = P(mode j now | mode i before)) and is predicted with its
// own process noise; *c receives the predicted mode probabilities.
std::array<ModeInnovation, 2> MixAndPredict(const std::array<GpsSmoother::ModeState, 2>& modes,
                                            const GpsSmootherOptions& o, double dt_s, const Eigen::Vector3d& z,
                                            const Eigen::Matrix3d& R, Eigen::Vector2d* c) {
  const double stay_quiet = std::exp(-dt_s / o.maneuver_mean_interval_s);
  const double stay_maneuver = std::exp(-dt_s / o.maneuver_mean_duration_s);
  Eigen::Matrix2d pi;
  pi << stay_quiet, 1.0 - stay_quiet, 1.0 - stay_maneuver, stay_maneuver;
  const Eigen::Vector2d mu(modes[kQuiet].probability, modes[kManeuver].probability);
  *c = pi.transpose() * mu;
  const Matrix6d F = Transition(dt_s);
  const double accel[2] = {o.quiet_accel_noise_mps2_sqrt_hz, o.maneuver_accel_noise_mps2_sqrt_hz};
  std::array<ModeInnovation, 2> pred;
  for (int j = 0; j < 2; ++j) {
    Vector6d x0 = Vector6d::Zero();
    for (int i = 0; i < 2; ++i) x0 += pi(i, j) * mu(i) / (*c)(j) * modes[i].x;
    Matrix6d P0 = Matrix6d::Zero();
    for (int i = 0; i < 2; ++i) {
      const Vector6d dx = modes[i].x - x0;
      P0 += pi(i, j) * mu(i) / (*c)(j) * (modes[i].P + dx * dx.transpose());
    }
    pred[j] = Innovate(F * x0, F * P0 * F.transpose() + ProcessNoise(accel[j] * accel[j], dt_s), z, R);
  }
  return pred;
}

// The gated NIS: the combined estimate predicted with the manoeuvre mode's process noise,
// i.e. reject only what a manoeuvre starting now could not explain. Gating under each
// mode's own prediction would let the manoeuvre mode, which follows the raw fixes, accept
// outliers; gating under the mixture would reject the first fixes of every manoeuvre.
double GateNis(const std::array<GpsSmoother::ModeState, 2>& modes, const GpsSmootherOptions& o, double dt_s,
               const Eigen::Vector3d& z, const Eigen::Matrix3d& R) {
  Vector6d x;
  Matrix6d P;
  Combine(modes, &x, &P);
  const Matrix6d F = Transition(dt_s);
  const double q = o.maneuver_accel_noise_mps2_sqrt_hz * o.maneuver_accel_noise_mps2_sqrt_hz;
  return Innovate(F * x, F * P * F.transpose() + ProcessNoise(q, dt_s), z, R).nis;
}

// Kalman update of one mode with H = [I 0], Joseph form.
void Correct(ModeInnovation& m, const Eigen::Matrix3d& R) {
  const Eigen::Matrix<double, 6, 3> K = m.P.leftCols<3>() * m.S.inverse();
  m.x += K * m.nu;
  Matrix6d IKH = Matrix6d::Identity();
  IKH.leftCols<3>() -= K;
  m.P = IKH * m.P * IKH.transpose() + K * R * K.transpose();
  m.P = 0.5 * (m.P + m.P.transpose()).eval();
}


// Kalman update of both modes and the new mode probabilities: predicted probability
// times the Gaussian likelihood of each mode's innovation (in the log domain).
void CorrectModes(const Eigen::Matrix3d& R, const Eigen::Vector2d& c, std::array<ModeInnovation, 2>* pred,
                  std::array<GpsSmoother::ModeState, 2>* modes) {
  Eigen::Vector2d log_likelihood;
  for (int j = 0; j < 2; ++j) {
    ModeInnovation& m = (*pred)[j];
    log_likelihood(j) = -0.5 * (m.nis + m.log_det_s);
    Correct(m, R);
    (*modes)[j].x = m.x;
    (*modes)[j].P = m.P;
  }
  const Eigen::Vector2d w = c.cwiseProduct((log_likelihood.array() - log_likelihood.maxCoeff()).exp().matrix());
  for (int j = 0; j < 2; ++j) (*modes)[j].probability = w(j) / w.sum();
}

}  // namespace

GpsSmoother::GpsSmoother(const GpsSmootherOptions& options) : options_(options) {
  ValidateOptions(options_);
  gate_nis_ = options_.gate_probability >= 1.0 ? std::numeric_limits<double>::infinity()
                                               : ChiSquareQuantile(options_.gate_probability, 3);
}

void GpsSmoother::Validate(const GnssSample& fix) const {
  RequireFinite(fix.t_s, "t_s");
  RequireFinite(fix.lat_rad, "lat_rad");
  RequireFinite(fix.lon_rad, "lon_rad");
  RequireFinite(fix.h_m, "h_m");
  if (!(std::abs(fix.lat_rad) < 0.5 * M_PI)) {
    throw std::invalid_argument("GpsSmoother::Update: GnssSample.lat_rad " + Number(fix.lat_rad) +
                                " is at or beyond a pole (|lat| must be < pi/2)");
  }
  if (started_ && !(fix.t_s > last_t_s_)) {
    throw std::invalid_argument("GpsSmoother::Update: GnssSample.t_s " + Number(fix.t_s) +
                                " s is not after the previous fix's " + Number(last_t_s_) + " s");
  }
}

Eigen::Vector3d GpsSmoother::ToLocal(const GnssSample& fix) const {
  const double dlon = WrapPi(fix.lon_rad - origin_.lon_rad);
  return Eigen::Vector3d((fix.lat_rad - origin_.lat_rad) * rad_to_north_m_, dlon * rad_to_east_m_,
                         origin_.h_m - fix.h_m);
}

wgs84::Geodetic GpsSmoother::ToGeodetic(const Eigen::Vector3d& pos_ned_m) const {
  wgs84::Geodetic g;
  g.lat_rad = origin_.lat_rad + pos_ned_m.x() / rad_to_north_m_;
  g.lon_rad = WrapPi(origin_.lon_rad + pos_ned_m.y() / rad_to_east_m_);
  g.h_m = origin_.h_m - pos_ned_m.z();
  return g;
}

void GpsSmoother::Initialise(const Eigen::Vector3d& z_ned_m, const Eigen::Vector3d& sigma_ned_m) {
  const double v2 = options_.initial_speed_sigma_mps * options_.initial_speed_sigma_mps;
  // The stationary distribution of the mode chain: the fraction of time in manoeuvres.
  const double p_maneuver = options_.maneuver_mean_duration_s /
                            (options_.maneuver_mean_interval_s + options_.maneuver_mean_duration_s);
  for (ModeState& mode : modes_) {
    mode.x << z_ned_m, Eigen::Vector3d::Zero();
    mode.P.setZero();
    mode.P.diagonal() << sigma_ned_m.cwiseAbs2(), Eigen::Vector3d::Constant(v2);
  }
  modes_[kQuiet].probability = 1.0 - p_maneuver;
  modes_[kManeuver].probability = p_maneuver;
  rejection_run_ = 0;
}

void GpsSmoother::PushNoiseSample(double t_s, const Eigen::Vector3d& z_ned_m) {
  recent_.emplace_back(t_s, z_ned_m);
  if (recent_.size() > 4) recent_.pop_front();
  if (recent_.size() < 4) return;
  const double d1 = recent_[1].first - recent_[0].first;
  const double d2 = recent_[2].first - recent_[1].first;
  const double d3 = recent_[3].first - recent_[2].first;
  if (std::max(std::abs(d2 - d1), std::abs(d3 - d1)) > kEvenIntervalTolerance * d1) return;
  third_diff_sq_m2_.push_back(
      (recent_[3].second - 3.0 * recent_[2].second + 3.0 * recent_[1].second - recent_[0].second).cwiseAbs2());
  if (third_diff_sq_m2_.size() > static_cast<std::size_t>(options_.noise_window_fixes)) {
    third_diff_sq_m2_.pop_front();
  }
}

Eigen::Vector3d GpsSmoother::MeasurementSigma() const {
  if (third_diff_sq_m2_.size() < static_cast<std::size_t>(options_.noise_min_fixes)) {
    return options_.initial_position_sigma_ned_m;
  }
  Eigen::Vector3d mean_sq = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& d2 : third_diff_sq_m2_) mean_sq += d2;
  mean_sq /= static_cast<double>(third_diff_sq_m2_.size());
  Eigen::Vector3d sigma;
  for (int a = 0; a < 3; ++a) {
    sigma(a) = std::clamp(std::sqrt(mean_sq(a)) / kThirdDifferenceGain, options_.min_position_sigma_m,
                          options_.max_position_sigma_m);
  }
  return sigma;
}

SmoothedFix GpsSmoother::Update(const GnssSample& fix) {
  Validate(fix);
  if (!started_) {
    origin_ = {fix.lat_rad, fix.lon_rad, fix.h_m};
    rad_to_north_m_ = wgs84::MeridianRadius(fix.lat_rad) + fix.h_m;
    rad_to_east_m_ = (wgs84::PrimeVerticalRadius(fix.lat_rad) + fix.h_m) * std::cos(fix.lat_rad);
    started_ = true;
  }
  const Eigen::Vector3d z = ToLocal(fix);
  // The noise estimate from the fixes before this one; this fix joins its window only if
  // the gate accepts it (or it starts the track), so outliers stay out of it.
  const Eigen::Vector3d sigma = MeasurementSigma();
  ++fixes_;
  if (fixes_ == 1) {
    PushNoiseSample(fix.t_s, z);
    Initialise(z, sigma);
    last_t_s_ = fix.t_s;
    SmoothedFix out = Output(fix.t_s, sigma);
    out.reset = true;
    return out;
  }
  const double dt = fix.t_s - last_t_s_;
  last_t_s_ = fix.t_s;
  const Eigen::Matrix3d R = sigma.cwiseAbs2().asDiagonal();
  Eigen::Vector2d c;  // predicted mode probabilities
  std::array<ModeInnovation, 2> pred = MixAndPredict(modes_, options_, dt, z, R, &c);
  const double nis = GateNis(modes_, options_, dt, z, R);
  // No gate while the noise estimate is still the initial guess: a wrong guess makes
  // the first two-fix velocities overconfident and would reject good fixes.
  const bool gating = third_diff_sq_m2_.size() >= static_cast<std::size_t>(options_.noise_min_fixes);
  SmoothedFix out;
  if (gating && nis > gate_nis_) {
    std::array<ModeState, 2> predicted;  // the modes without the fix
    for (int j = 0; j < 2; ++j) predicted[j] = {pred[j].x, pred[j].P, c(j)};
    out = Reject(fix.t_s, z, sigma, predicted);
  } else {
    rejection_run_ = 0;
    PushNoiseSample(fix.t_s, z);
    CorrectModes(R, c, &pred, &modes_);
    out = Output(fix.t_s, sigma);
  }
  out.nis = nis;
  return out;
}

SmoothedFix GpsSmoother::Reject(double t_s, const Eigen::Vector3d& z_ned_m, const Eigen::Vector3d& sigma_ned_m,
                                const std::array<ModeState, 2>& predicted) {
  ++rejected_;
  ++rejection_run_;
  modes_ = predicted;
  const bool reset = rejection_run_ >= options_.reset_after_rejections;
  if (reset) {
    ++resets_;
    PushNoiseSample(t_s, z_ned_m);
    Initialise(z_ned_m, sigma_ned_m);
  }
  SmoothedFix out = Output(t_s, sigma_ned_m);
  out.rejected = true;
  out.reset = reset;
  return out;
}

SmoothedFix GpsSmoother::Output(double t_s, const Eigen::Vector3d& measurement_sigma_ned_m) const {
  Vector6d x;
  Matrix6d P;
  Combine(modes_, &x, &P);
  SmoothedFix out;
  out.t_s = t_s;
  out.pos_ned_m = x.head<3>();
  out.vel_ned_mps = x.tail<3>();
  out.sigma_ned_m = P.diagonal().head<3>().cwiseSqrt();
  out.measurement_sigma_ned_m = measurement_sigma_ned_m;
  out.maneuver_probability = modes_[kManeuver].probability;
  const wgs84::Geodetic g = ToGeodetic(out.pos_ned_m);
  out.lat_rad = g.lat_rad;
  out.lon_rad = g.lon_rad;
  out.h_m = g.h_m;
  return out;
}

}  // namespace navtwin::inflight
