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
/// Smallest standard deviation written to a GNSS sample (readers reject 0).
constexpr double kMinReportedSigma = 1e-3;
/// IGRF-13 axial dipole term |g10| at epoch 2020.0 (29404.8 nT), uT.
constexpr double kDipoleField_uT = 29.4048;

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

// ----------------------------------------------------------------------- parsing

void RequireNotBoth(const ConfigNode& node, const std::string& sigma_key,
                    const std::string& fixed_key) {
  if (node.Has(sigma_key) && node.Has(fixed_key)) {
    node.Fail(fixed_key, "give either " + sigma_key + " (1-sigma of a per-run draw) or " +
                             fixed_key + " (fixed values), not both");
  }
}

/// The numbers of a YAML sequence node (or a scalar as one number); Fail on anything else.
std::vector<double> Numbers(const ConfigNode& node, const std::string& key) {
  const YAML::Node v = node.yaml()[key];
  std::vector<double> out;
  if (v.IsScalar()) return {node.Double(key, 0.0)};
  if (!v.IsSequence()) node.Fail(key, "expected a number or a list of numbers");
  for (const YAML::Node& e : v) {
    try {
      out.push_back(e.as<double>());
    } catch (const YAML::Exception&) {
      node.Fail(key, "expected a list of numbers");
    }
    if (!std::isfinite(out.back())) node.Fail(key, "must be finite");
  }
  return out;
}

/// A 1-sigma per NED axis: a scalar (every axis), [horizontal, vertical] or [N, E, D];
/// every value >= 0; absent: 0.
Eigen::Vector3d SigmaNed(const ConfigNode& node, const std::string& key) {
  if (!node.Has(key)) return Eigen::Vector3d::Zero();
  const std::vector<double> v = Numbers(node, key);
  Eigen::Vector3d sigma;
  if (v.size() == 1) {
    sigma.setConstant(v[0]);
  } else if (v.size() == 2) {
    sigma << v[0], v[0], v[1];
  } else if (v.size() == 3) {
    sigma << v[0], v[1], v[2];
  } else {
    node.Fail(key, "expected a number, [horizontal, vertical] or [N, E, D]");
  }
  if (sigma.minCoeff() < 0.0) node.Fail(key, "must be >= 0");
  return sigma;
}

/// [[a, b, c], [d, e, f], [g, h, i]].
Eigen::Matrix3d Matrix3(const ConfigNode& node, const std::string& key) {
  const YAML::Node m = node.yaml()[key];
  const char* shape = "expected [[a, b, c], [d, e, f], [g, h, i]] of finite numbers";
  if (!m.IsSequence() || m.size() != 3) node.Fail(key, shape);
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r) {
    if (!m[r].IsSequence() || m[r].size() != 3) node.Fail(key, shape);
    for (int c = 0; c < 3; ++c) {
      try {
        out(r, c) = m[r][c].as<double>();
      } catch (const YAML::Exception&) {
        node.Fail(key, shape);
      }
    }
  }
  if (!out.allFinite()) node.Fail(key, shape);
  return out;
}

/// An element [start_s, end_s] of a list, start < end.
Eigen::Vector2d Interval(const ConfigNode& element) {
  const YAML::Node& v = element.yaml();
  const char* shape = "expected [start_s, end_s] with start_s < end_s";
  if (!v.IsSequence() || v.size() != 2) element.Fail("", shape);
  Eigen::Vector2d out;
  for (int i = 0; i < 2; ++i) {
    try {
      out[i] = v[i].as<double>();
    } catch (const YAML::Exception&) {
      element.Fail("", shape);
    }
  }
  if (!out.allFinite() || !(out[0] < out[1])) element.Fail("", shape);
  return out;
}

double Rate(const ConfigNode& node, double fallback, double hi) {
  return node.Double("rate_hz", fallback, 0.1, hi);
}

// ------------------------------------------------------------------ errors.yaml

void EmitValue(YAML::Emitter& out, const std::string& key, double value) {
  out << YAML::Key << key << YAML::Value << value;
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

// --------------------------------------------------------------------------- GNSS

GnssSimConfig ParseGnssSimConfig(const ConfigNode& node) {
  node.RequireKeys({"rate_hz", "position_sigma_m", "velocity_sigma_mps", "lever_arm_b_m",
                    "time_offset_s", "outages", "outlier_probability", "outlier_size_m",
                    "start_s"});
  GnssSimConfig c;
  c.rate_hz = Rate(node, c.rate_hz, 100.0);
  c.position_sigma_ned_m = SigmaNed(node, "position_sigma_m");
  c.velocity_sigma_ned_mps = SigmaNed(node, "velocity_sigma_mps");
  c.lever_arm_b_m = node.Vector("lever_arm_b_m", c.lever_arm_b_m);
  c.time_offset_s = node.Double("time_offset_s", 0.0, -kSecondsPerDay, kSecondsPerDay);
  for (const ConfigNode& e : node.Elements("outages")) c.outages_s.push_back(Interval(e));
  c.outlier_probability = node.Double("outlier_probability", 0.0, 0.0, 1.0);
  c.outlier_size_m = node.NonNegative("outlier_size_m", 0.0);
  if (c.outlier_probability > 0.0 && !(c.outlier_size_m > 0.0)) {
    node.Fail("outlier_size_m", "must be > 0 when outlier_probability > 0");
  }
  c.start_s = node.NonNegative("start_s", 0.0);
  return c;
}

GnssSample AntennaTruth(const TruthSample& truth, const Eigen::Vector3d& lever_arm_b_m) {
  const NavState& s = truth.state;
  GnssSample g;
  g.t_s = truth.t_s;
  g.gps_week = s.gps_week;
  g.has_velocity = true;
  g.quality = 1;
  g.num_sats = 10;
  g.lat_rad = s.lat_rad;
  g.lon_rad = s.lon_rad;
  g.h_m = s.h_m;
  g.v_n_mps = s.v_n_mps;
  if (lever_arm_b_m.isZero(0.0)) return g;  // exactly the IMU (no ECEF round trip)

  const Eigen::Matrix3d R_n_b = DcmFromQuat(s.q_n_b);
  const Eigen::Vector3d arm_n = R_n_b * lever_arm_b_m;
  const wgs84::Geodetic imu{s.lat_rad, s.lon_rad, s.h_m};
  const wgs84::Geodetic antenna = wgs84::NedToGeodetic(arm_n, imu);
  g.lat_rad = antenna.lat_rad;
  g.lon_rad = antenna.lon_rad;
  g.h_m = antenna.h_m;
  // Earth-relative velocity of the antenna in the IMU's NED, then in the antenna's NED.
  const Eigen::Vector3d v_imu_ned = s.v_n_mps +
                                    R_n_b * truth.omega_ib_b_radps.cross(lever_arm_b_m) -
                                    wgs84::EarthRateNed(s.lat_rad).cross(arm_n);
  g.v_n_mps = wgs84::RotationEcefFromNed(antenna.lat_rad, antenna.lon_rad).transpose() *
              wgs84::RotationEcefFromNed(s.lat_rad, s.lon_rad) * v_imu_ned;
  return g;
}

GnssSimulator::GnssSimulator(const GnssSimConfig& config, const Rng& rng, bool perfect)
    : config_(config),
      perfect_(perfect),
      sampler_(config.rate_hz, config.time_offset_s, config.start_s),
      position_rng_(rng.Stream("gnss.position_noise")),
      velocity_rng_(rng.Stream("gnss.velocity_noise")),
      outlier_rng_(rng.Stream("gnss.outlier")) {
  if (config.position_sigma_ned_m.minCoeff() < 0.0 ||
      config.velocity_sigma_ned_mps.minCoeff() < 0.0 || !(config.outlier_probability >= 0.0) ||
      config.outlier_probability > 1.0 || !(config.outlier_size_m >= 0.0)) {
    throw std::invalid_argument("GnssSimulator: negative sigma or bad outlier settings");
  }
}

bool GnssSimulator::InOutage(double t_s) const {
  for (const Eigen::Vector2d& o : config_.outages_s) {
    if (t_s >= o[0] && t_s < o[1]) return true;
  }
  return false;
}

std::optional<GnssSample> GnssSimulator::Push(const TruthSample& truth) {
  const std::optional<EpochSampler::Epoch> epoch = sampler_.Push(truth);
  if (!epoch) return std::nullopt;
  return Measure(epoch->tag_s, epoch->truth);
}

std::optional<GnssSample> GnssSimulator::Measure(double t_s, const TruthSample& truth) {
  // Draws for every epoch (outage or not) so that outages do not shift later noise.
  Eigen::Vector3d dp_n = Eigen::Vector3d::Zero(), dv_n = Eigen::Vector3d::Zero();
  std::optional<GnssOutlier> outlier;
  if (!perfect_) {
    dp_n = position_rng_.Normal3(1.0).cwiseProduct(config_.position_sigma_ned_m);
    dv_n = velocity_rng_.Normal3(1.0).cwiseProduct(config_.velocity_sigma_ned_mps);
    if (outlier_rng_.Uniform() < config_.outlier_probability) {
      outlier = GnssOutlier{t_s, config_.outlier_size_m * outlier_rng_.Normal3(1.0).normalized()};
    }
  }
  if (InOutage(t_s)) return std::nullopt;
  GnssSample g = AntennaTruth(truth, config_.lever_arm_b_m);
  g.t_s = t_s;
  if (outlier) {
    dp_n += outlier->offset_ned_m;
    outliers_.push_back(*outlier);
  }
  if (!dp_n.isZero(0.0)) {
    const wgs84::Geodetic p = wgs84::NedToGeodetic(dp_n, {g.lat_rad, g.lon_rad, g.h_m});
    g.lat_rad = p.lat_rad;
    g.lon_rad = p.lon_rad;
    g.h_m = p.h_m;
  }
  g.v_n_mps += dv_n;
  g.pos_std_ned_m = config_.position_sigma_ned_m.cwiseMax(kMinReportedSigma);
  g.vel_std_ned_mps = config_.velocity_sigma_ned_mps.cwiseMax(kMinReportedSigma);
  return g;
}

void GnssSimulator::EmitDrawn(YAML::Emitter& out) const {
  out << YAML::BeginMap;
  out << YAML::Key << "perfect" << YAML::Value << perfect_;
  EmitValue(out, "rate_hz", config_.rate_hz);
  EmitVector(out, "position_sigma_ned_m", config_.position_sigma_ned_m);
  EmitVector(out, "velocity_sigma_ned_mps", config_.velocity_sigma_ned_mps);
  EmitVector(out, "lever_arm_b_m", config_.lever_arm_b_m);
  EmitValue(out, "time_offset_s", config_.time_offset_s);
  EmitValue(out, "start_s", config_.start_s);
  out << YAML::Key << "outages_s" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const Eigen::Vector2d& o : config_.outages_s) {
    out << YAML::BeginSeq << o[0] << o[1] << YAML::EndSeq;
  }
  out << YAML::EndSeq;
  EmitValue(out, "outlier_probability", config_.outlier_probability);
  EmitValue(out, "outlier_size_m", config_.outlier_size_m);
  out << YAML::Key << "outliers" << YAML::Value << YAML::BeginSeq;
  for (const GnssOutlier& o : outliers_) {
    out << YAML::Flow << YAML::BeginMap;
    EmitValue(out, "t_s", o.t_s);
    EmitVector(out, "offset_ned_m", o.offset_ned_m);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
}

// ------------------------------------------------------------------- magnetometer

MagSimConfig ParseMagSimConfig(const ConfigNode& node) {
  node.RequireKeys({"rate_hz", "declination_deg", "inclination_deg", "intensity_uT", "hard_iron_uT",
                    "hard_iron_fixed_uT", "soft_iron", "soft_iron_fixed", "soft_iron_symmetric",
                    "noise_uT", "two_axis"});
  MagSimConfig c;
  c.rate_hz = Rate(node, c.rate_hz, 1000.0);
  if (node.Has("declination_deg")) {
    c.declination_rad = node.Double("declination_deg", 0.0, -180.0, 180.0) * kDegToRad;
  }
  if (node.Has("inclination_deg")) {
    c.inclination_rad = node.Double("inclination_deg", 0.0, -90.0, 90.0) * kDegToRad;
  }
  if (node.Has("intensity_uT")) {
    c.intensity_uT = node.Double("intensity_uT", 0.0);
    if (!(*c.intensity_uT > 0.0)) node.Fail("intensity_uT", "must be > 0");
  }
  RequireNotBoth(node, "hard_iron_uT", "hard_iron_fixed_uT");
  c.hard_iron_sigma_uT = node.NonNegative("hard_iron_uT", 0.0);
  if (node.Has("hard_iron_fixed_uT")) {
    c.hard_iron_fixed_uT = node.Vector("hard_iron_fixed_uT", Eigen::Vector3d::Zero());
  }
  RequireNotBoth(node, "soft_iron", "soft_iron_fixed");
  c.soft_iron_sigma = node.NonNegative("soft_iron", 0.0);
  if (node.Has("soft_iron_fixed")) c.soft_iron_fixed = Matrix3(node, "soft_iron_fixed");
  c.soft_iron_symmetric = node.Bool("soft_iron_symmetric", false);
  c.noise_uT = node.NonNegative("noise_uT", 0.0);
  c.two_axis = node.Bool("two_axis", false);
  return c;
}

Eigen::Vector3d MagneticFieldNed_uT(double declination_rad, double inclination_rad,
                                    double intensity_uT) {
  const double horizontal = intensity_uT * std::cos(inclination_rad);
  return {horizontal * std::cos(declination_rad), horizontal * std::sin(declination_rad),
          intensity_uT * std::sin(inclination_rad)};
}

namespace {

Eigen::Vector3d DrawHardIron(const MagSimConfig& c, Rng rng) {
  if (c.hard_iron_fixed_uT) return *c.hard_iron_fixed_uT;
  return rng.Normal3(c.hard_iron_sigma_uT);
}

Eigen::Matrix3d DrawSoftIron(const MagSimConfig& c, Rng rng) {
  if (c.soft_iron_fixed) return *c.soft_iron_fixed;
  Eigen::Matrix3d s;
  for (int r = 0; r < 3; ++r) {
    for (int col = 0; col < 3; ++col) {
      s(r, col) = (c.soft_iron_symmetric && col < r) ? s(col, r) : rng.Normal(c.soft_iron_sigma);
    }
  }
  return s;
}

}  // namespace

MagSimulator::MagSimulator(const MagSimConfig& config, double start_lat_rad, const Rng& rng,
                           bool perfect)
    : config_(config),
      perfect_(perfect),
      declination_rad_(config.declination_rad.value_or(0.0)),
      inclination_rad_(config.inclination_rad.value_or(std::atan(2.0 * std::tan(start_lat_rad)))),
      intensity_uT_(config.intensity_uT.value_or(
          kDipoleField_uT * std::sqrt(1.0 + 3.0 * std::pow(std::sin(start_lat_rad), 2)))),
      field_ned_uT_(MagneticFieldNed_uT(declination_rad_, inclination_rad_, intensity_uT_)),
      sampler_(config.rate_hz, 0.0, 0.0),
      noise_rng_(rng.Stream("mag.noise")) {
  if (!perfect) {
    iron_.hard_iron_uT = DrawHardIron(config, rng.Stream("mag.hard_iron"));
    iron_.soft_iron = DrawSoftIron(config, rng.Stream("mag.soft_iron"));
  }
}

std::optional<MagSample> MagSimulator::Push(const TruthSample& truth) {
  const std::optional<EpochSampler::Epoch> epoch = sampler_.Push(truth);
  if (!epoch) return std::nullopt;
  MagSample m;
  m.t_s = epoch->tag_s;
  const Eigen::Vector3d field_b = epoch->truth.state.q_n_b.conjugate() * field_ned_uT_;
  m.m_b_uT = iron_.Apply(field_b);
  if (!perfect_) m.m_b_uT += noise_rng_.Normal3(config_.noise_uT);
  if (config_.two_axis) m.m_b_uT.z() = 0.0;
  return m;
}

void MagSimulator::EmitDrawn(YAML::Emitter& out) const {
  out << YAML::BeginMap;
  out << YAML::Key << "perfect" << YAML::Value << perfect_;
  EmitValue(out, "rate_hz", config_.rate_hz);
  EmitValue(out, "declination_deg", declination_rad_ * kRadToDeg);
  EmitValue(out, "inclination_deg", inclination_rad_ * kRadToDeg);
  EmitValue(out, "intensity_uT", intensity_uT_);
  EmitVector(out, "field_ned_uT", field_ned_uT_, 1.0);
  EmitVector(out, "hard_iron_uT", iron_.hard_iron_uT, 1.0);
  EmitMatrix(out, "soft_iron", iron_.soft_iron);
  EmitValue(out, "noise_uT", perfect_ ? 0.0 : config_.noise_uT);
  out << YAML::Key << "two_axis" << YAML::Value << config_.two_axis;
  out << YAML::EndMap;
}

// ---------------------------------------------------------------------- barometer

BaroSimConfig ParseBaroSimConfig(const ConfigNode& node) {
  node.RequireKeys({"rate_hz", "bias_m", "bias_fixed_m", "noise_m", "pressure"});
  BaroSimConfig c;
  c.rate_hz = Rate(node, c.rate_hz, 1000.0);
  RequireNotBoth(node, "bias_m", "bias_fixed_m");
  c.bias_sigma_m = node.NonNegative("bias_m", 0.0);
  if (node.Has("bias_fixed_m")) c.bias_fixed_m = node.Double("bias_fixed_m", 0.0);
  c.noise_m = node.NonNegative("noise_m", 0.0);
  c.pressure = node.Bool("pressure", true);
  return c;
}

namespace {

// ISO 2533:1975 / U.S. Standard Atmosphere 1976 constants.
constexpr double kIsaP0_pa = 101325.0;
constexpr double kIsaT0_K = 288.15;
constexpr double kIsaLapse_K_m = 0.0065;  // troposphere, 0-11 km geopotential
constexpr double kIsaTropopause_m = 11000.0;
constexpr double kIsaT11_K = 216.65;
constexpr double kIsaTop_m = 20000.0;  // end of the isothermal layer
constexpr double kIsaBottom_m = -5000.0;
constexpr double kIsaMolarMass_kg_mol = 0.0289644;
constexpr double kIsaGasConstant = 8.31432;      // J/(mol K), the 1976 value
constexpr double kIsaEarthRadius_m = 6356766.0;  // r0 of the geopotential altitude

double Geopotential_m(double altitude_m) {
  const double H = kIsaEarthRadius_m * altitude_m / (kIsaEarthRadius_m + altitude_m);
  if (!(H >= kIsaBottom_m && H <= kIsaTop_m)) {
    throw std::out_of_range("ISA: altitude " + std::to_string(altitude_m) +
                            " m is outside -5 km ... 20 km geopotential");
  }
  return H;
}

}  // namespace

double IsaTemperature_K(double altitude_m) {
  const double H = Geopotential_m(altitude_m);
  return H < kIsaTropopause_m ? kIsaT0_K - kIsaLapse_K_m * H : kIsaT11_K;
}

double IsaPressure_pa(double altitude_m) {
  const double H = Geopotential_m(altitude_m);
  const double exponent = kStandardGravity_mps2 * kIsaMolarMass_kg_mol / (kIsaGasConstant * kIsaLapse_K_m);
  if (H < kIsaTropopause_m) {
    return kIsaP0_pa * std::pow((kIsaT0_K - kIsaLapse_K_m * H) / kIsaT0_K, exponent);
  }
  const double p11 = kIsaP0_pa * std::pow(kIsaT11_K / kIsaT0_K, exponent);
  return p11 * std::exp(-kStandardGravity_mps2 * kIsaMolarMass_kg_mol * (H - kIsaTropopause_m) /
                        (kIsaGasConstant * kIsaT11_K));
}

BaroSimulator::BaroSimulator(const BaroSimConfig& config, const Rng& rng, bool perfect)
    : config_(config),
      perfect_(perfect),
      sampler_(config.rate_hz, 0.0, 0.0),
      noise_rng_(rng.Stream("baro.noise")) {
  if (!perfect) {
    bias_m_ = config.bias_fixed_m ? *config.bias_fixed_m
                                  : rng.Stream("baro.bias").Normal(config.bias_sigma_m);
  }
}

std::optional<BaroSample> BaroSimulator::Push(const TruthSample& truth) {
  const std::optional<EpochSampler::Epoch> epoch = sampler_.Push(truth);
  if (!epoch) return std::nullopt;
  BaroSample b;
  b.t_s = epoch->tag_s;
  b.altitude_m = epoch->truth.state.h_m + bias_m_;
  if (!perfect_) b.altitude_m += noise_rng_.Normal(config_.noise_m);
  if (config_.pressure) {
    b.pressure_pa = IsaPressure_pa(b.altitude_m);
    b.temperature_degC = IsaTemperature_K(b.altitude_m) - 273.15;
  }
  return b;
}

void BaroSimulator::EmitDrawn(YAML::Emitter& out) const {
  out << YAML::BeginMap;
  out << YAML::Key << "perfect" << YAML::Value << perfect_;
  EmitValue(out, "rate_hz", config_.rate_hz);
  EmitValue(out, "bias_m", bias_m_);
  EmitValue(out, "noise_m", perfect_ ? 0.0 : config_.noise_m);
  out << YAML::Key << "pressure" << YAML::Value << config_.pressure;
  out << YAML::EndMap;
}

// ----------------------------------------------------------------------- odometer

OdometerSimConfig ParseOdometerSimConfig(const ConfigNode& node) {
  node.RequireKeys({"rate_hz", "scale_factor_ppm", "scale_factor_fixed_ppm", "noise_mps", "lever_arm_b_m"});
  OdometerSimConfig c;
  c.rate_hz = Rate(node, c.rate_hz, 1000.0);
  RequireNotBoth(node, "scale_factor_ppm", "scale_factor_fixed_ppm");
  c.scale_factor_sigma = node.Double("scale_factor_ppm", 0.0, 0.0, 1e5) * 1e-6;
  if (node.Has("scale_factor_fixed_ppm")) {
    c.scale_factor_fixed = node.Double("scale_factor_fixed_ppm", 0.0, -1e5, 1e5) * 1e-6;
  }
  c.noise_mps = node.NonNegative("noise_mps", 0.0);
  c.lever_arm_b_m = node.Vector("lever_arm_b_m", Eigen::Vector3d::Zero());
  return c;
}

OdometerSimulator::OdometerSimulator(const OdometerSimConfig& config, const Rng& rng, bool perfect)
    : config_(config),
      perfect_(perfect),
      sampler_(config.rate_hz, 0.0, 0.0),
      noise_rng_(rng.Stream("odometer.noise")) {
  if (!perfect) {
    scale_factor_ = config.scale_factor_fixed ? *config.scale_factor_fixed
                                              : rng.Stream("odometer.scale_factor").Normal(config.scale_factor_sigma);
  }
}

std::optional<OdometerSample> OdometerSimulator::Push(const TruthSample& truth) {
  const std::optional<EpochSampler::Epoch> epoch = sampler_.Push(truth);
  if (!epoch) return std::nullopt;
  const TruthSample& x = epoch->truth;
  const Eigen::Vector3d v_b =
      x.state.q_n_b.conjugate() * x.state.v_n_mps + x.omega_ib_b_radps.cross(config_.lever_arm_b_m);
  OdometerSample s;
  s.t_s = epoch->tag_s;
  s.speed_mps = (1.0 + scale_factor_) * v_b.x();
  if (!perfect_) s.speed_mps += noise_rng_.Normal(config_.noise_mps);
  return s;
}

void OdometerSimulator::EmitDrawn(YAML::Emitter& out) const {
  out << YAML::BeginMap;
  out << YAML::Key << "perfect" << YAML::Value << perfect_;
  EmitValue(out, "rate_hz", config_.rate_hz);
  EmitValue(out, "scale_factor_ppm", scale_factor_ * 1e6);
  EmitValue(out, "noise_mps", perfect_ ? 0.0 : config_.noise_mps);
  out << YAML::EndMap;
}

// --------------------------------------------------------------------- master INS

MasterSimConfig ParseMasterSimConfig(const ConfigNode& node) {
  node.RequireKeys({"rate_hz", "transfer_delay_s", "attitude_error_sigma_mrad",
                    "attitude_error_fixed_mrad", "attitude_random_walk_mrad_sqrt_h",
                    "velocity_noise_mps"});
  MasterSimConfig c;
  c.rate_hz = Rate(node, c.rate_hz, 1000.0);
  c.transfer_delay_s = node.Double("transfer_delay_s", 0.0, 0.0, 10.0);
  RequireNotBoth(node, "attitude_error_sigma_mrad", "attitude_error_fixed_mrad");
  c.attitude_error_sigma_rad = node.NonNegative("attitude_error_sigma_mrad", 0.0) * kMrad_rad;
  if (node.Has("attitude_error_fixed_mrad")) {
    c.attitude_error_fixed_rad =
        node.Vector("attitude_error_fixed_mrad", Eigen::Vector3d::Zero()) * kMrad_rad;
  }
  c.attitude_random_walk_rad_sqrt_s =
      node.NonNegative("attitude_random_walk_mrad_sqrt_h", 0.0) * kMrad_rad / kSqrtHour_sqrts;
  c.velocity_noise_mps = node.NonNegative("velocity_noise_mps", 0.0);
  return c;
}

MasterSimulator::MasterSimulator(const MasterSimConfig& config, const Rng& rng, bool perfect)
    : config_(config),
      perfect_(perfect),
      sampler_(config.rate_hz, 0.0, 0.0, config.transfer_delay_s),
      random_walk_rng_(rng.Stream("master.attitude_random_walk")),
      velocity_rng_(rng.Stream("master.velocity_noise")) {
  if (!perfect) {
    constant_error_rad_ =
        config.attitude_error_fixed_rad
            ? *config.attitude_error_fixed_rad
            : rng.Stream("master.attitude_error").Normal3(config.attitude_error_sigma_rad);
  }
}

std::optional<NavState> MasterSimulator::Push(const TruthSample& truth) {
  const std::optional<EpochSampler::Epoch> epoch = sampler_.Push(truth);
  if (!epoch) return std::nullopt;
  NavState s = epoch->truth.state;
  s.t_s = epoch->tag_s;
  if (!perfect_) {
    const Eigen::Vector3d phi = constant_error_rad_ + random_walk_rad_;
    s.q_n_b = ApplyAttitudeError(Eigen::Vector3d(-phi), s.q_n_b);  // R_true = Exp(phi) R_master
    s.v_n_mps += velocity_rng_.Normal3(config_.velocity_noise_mps);
    random_walk_rad_ += random_walk_rng_.Normal3(config_.attitude_random_walk_rad_sqrt_s /
                                                 std::sqrt(config_.rate_hz));
  }
  return s;
}

void MasterSimulator::EmitDrawn(YAML::Emitter& out) const {
  out << YAML::BeginMap;
  out << YAML::Key << "perfect" << YAML::Value << perfect_;
  EmitValue(out, "rate_hz", config_.rate_hz);
  EmitValue(out, "transfer_delay_s", config_.transfer_delay_s);
  EmitVector(out, "attitude_error_mrad", constant_error_rad_, kMrad_rad);
  EmitValue(out, "attitude_random_walk_mrad_sqrt_h",
            perfect_ ? 0.0 : config_.attitude_random_walk_rad_sqrt_s * kSqrtHour_sqrts / kMrad_rad);
  EmitVector(out, "attitude_random_walk_now_mrad", random_walk_rad_, kMrad_rad);
  EmitValue(out, "velocity_noise_mps", perfect_ ? 0.0 : config_.velocity_noise_mps);
  out << YAML::EndMap;
}

}  // namespace navtwin::sim
