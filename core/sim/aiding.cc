#include "core/sim/aiding.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/units.h"

namespace navtwin::sim {
namespace {

/// Truth samples and epochs closer than this are the same instant (epoch times k / rate
/// and truth times k * dt may differ in the last bits).
constexpr double kSameTime_s = 1e-9;

// ------------------------------------------------------------------ interpolation

/// Cubic Hermite weights at s in [0, 1] for an interval of length h:
/// y(s) = h00 y0 + h10 h y0' + h01 y1 + h11 h y1'.
struct Hermite {
  Hermite(double s, double h)
      : h00(2 * s * s * s - 3 * s * s + 1),
        h10((s * s * s - 2 * s * s + s) * h),
        h01(-2 * s * s * s + 3 * s * s),
        h11((s * s * s - s * s) * h) {}
  Eigen::Vector3d Blend(const Eigen::Vector3d& y0, const Eigen::Vector3d& d0,
                        const Eigen::Vector3d& y1, const Eigen::Vector3d& d1) const {
    return h00 * y0 + h10 * d0 + h01 * y1 + h11 * d1;
  }
  double h00, h10, h01, h11;
};

/// d(lat, lon, h)/dt of a state.
Eigen::Vector3d PositionRate(const NavState& s) {
  return {s.v_n_mps.x() / (wgs84::MeridianRadius(s.lat_rad) + s.h_m),
          s.v_n_mps.y() / ((wgs84::PrimeVerticalRadius(s.lat_rad) + s.h_m) * std::cos(s.lat_rad)),
          -s.v_n_mps.z()};
}

/// Body rate over the NED frame, omega_nb_b = omega_ib_b - R_b_n (omega_ie_n + omega_en_n).
Eigen::Vector3d BodyRateOverNed(const TruthSample& x) {
  const NavState& s = x.state;
  const Eigen::Vector3d w_in =
      wgs84::EarthRateNed(s.lat_rad) + wgs84::TransportRateNed(s.lat_rad, s.h_m, s.v_n_mps);
  return x.omega_ib_b_radps - s.q_n_b.conjugate() * w_in;
}

Eigen::Vector3d Lerp(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double s) {
  return (1.0 - s) * a + s * b;
}

}  // namespace

// ------------------------------------------------------------------- interpolation

TruthSample InterpolateTruth(const TruthSample& a, const TruthSample& b, double t_s) {
  if (!(a.t_s < b.t_s) || !(t_s >= a.t_s && t_s <= b.t_s)) {
    throw std::invalid_argument("InterpolateTruth: need a.t_s < b.t_s and t_s between them");
  }
  if (t_s == a.t_s) return a;
  if (t_s == b.t_s) return b;
  const double h = b.t_s - a.t_s;
  const double s = (t_s - a.t_s) / h;
  const Hermite w(s, h);
  const NavState& sa = a.state;
  const NavState& sb = b.state;

  TruthSample out;
  out.t_s = t_s;
  out.exact.t_s = t_s;
  out.state.t_s = t_s;
  out.state.gps_week = sa.gps_week;
  // Longitude of b on a's branch, so that a crossing of +-180 deg interpolates the short way.
  const Eigen::Vector3d pa(sa.lat_rad, sa.lon_rad, sa.h_m);
  const Eigen::Vector3d pb(sb.lat_rad, sa.lon_rad + WrapPi(sb.lon_rad - sa.lon_rad), sb.h_m);
  const Eigen::Vector3d p = w.Blend(pa, PositionRate(sa), pb, PositionRate(sb));
  out.state.lat_rad = p.x();
  out.state.lon_rad = p.y();
  out.state.h_m = p.z();
  out.state.v_n_mps = w.Blend(sa.v_n_mps, a.a_n_mps2, sb.v_n_mps, b.a_n_mps2);

  // Attitude: q_a Exp(phi(s)), phi a cubic Hermite from 0 (slope omega_nb_b(a)) to
  // phi_1 = Log(q_a^-1 q_b) (slope Jr^-1(phi_1) omega_nb_b(b)).
  const Eigen::Vector3d phi1 = RotVecFromQuat(Eigen::Quaterniond(sa.q_n_b.conjugate() * sb.q_n_b));
  const Eigen::Vector3d phi = w.Blend(Eigen::Vector3d::Zero(), BodyRateOverNed(a), phi1,
                                      RightJacobianInverseSO3(phi1) * BodyRateOverNed(b));
  out.state.q_n_b = (sa.q_n_b * QuatFromRotVec(phi)).normalized();

  out.omega_ib_b_radps =
      w.Blend(a.omega_ib_b_radps, a.alpha_ib_b_rad_s2, b.omega_ib_b_radps, b.alpha_ib_b_rad_s2);
  out.f_b_mps2 = Lerp(a.f_b_mps2, b.f_b_mps2, s);
  out.alpha_ib_b_rad_s2 = Lerp(a.alpha_ib_b_rad_s2, b.alpha_ib_b_rad_s2, s);
  out.a_n_mps2 = Lerp(a.a_n_mps2, b.a_n_mps2, s);
  return out;
}

// ------------------------------------------------------------------ epoch sampler

EpochSampler::EpochSampler(double rate_hz, double offset_s, double start_s, double delay_s)
    : rate_hz_(rate_hz), offset_s_(offset_s), start_s_(start_s), delay_s_(delay_s) {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz) || !(delay_s >= 0.0) || !std::isfinite(delay_s) ||
      !std::isfinite(offset_s) || !std::isfinite(start_s)) {
    throw std::invalid_argument("EpochSampler: rate_hz must be > 0, delay_s >= 0, all finite");
  }
}

std::optional<EpochSampler::Epoch> EpochSampler::Push(const TruthSample& truth) {
  if (!buffer_.empty() && !(truth.t_s > buffer_.back().t_s)) {
    throw std::invalid_argument("EpochSampler: truth times must increase");
  }
  if (!started_) {
    // First epoch: tag >= start_s and data time >= the first truth time.
    const double first_tag = std::max(start_s_, truth.t_s + delay_s_) - kSameTime_s;
    k_ = static_cast<long>(std::ceil((first_tag - offset_s_) * rate_hz_));
    while (TagAt(k_) < first_tag) ++k_;
    while (TagAt(k_ - 1) >= first_tag) --k_;
    started_ = true;
  }
  buffer_.push_back(truth);
  const double tag = TagAt(k_);
  std::optional<Epoch> out;
  if (tag <= truth.t_s + kSameTime_s) {
    out = Epoch{tag, TruthAt(tag - delay_s_)};
    ++k_;
    if (TagAt(k_) <= truth.t_s + kSameTime_s) {
      throw std::invalid_argument(
          "EpochSampler: two epochs in one truth interval (a rate above the truth rate)");
    }
  }
  // Keep the last sample at or before the next epoch's data time, and everything after it.
  const double next_data_s = TagAt(k_) - delay_s_;
  while (buffer_.size() >= 2 && buffer_[1].t_s <= next_data_s + kSameTime_s) buffer_.pop_front();
  return out;
}

TruthSample EpochSampler::TruthAt(double t_s) const {
  const auto it = std::lower_bound(buffer_.begin(), buffer_.end(), t_s - kSameTime_s,
                                   [](const TruthSample& x, double t) { return x.t_s < t; });
  if (it == buffer_.end()) throw std::logic_error("EpochSampler: data time beyond the truth");
  if (std::fabs(it->t_s - t_s) <= kSameTime_s) return *it;
  if (it == buffer_.begin()) throw std::logic_error("EpochSampler: data time before the truth");
  return InterpolateTruth(*(it - 1), *it, t_s);
}

}  // namespace navtwin::sim
