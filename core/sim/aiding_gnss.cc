#include "core/sim/aiding.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/sim/aiding_config.h"
#include "core/units.h"

namespace navtwin::sim {

using aiding_config::SigmaNed;
using aiding_config::Interval;
using aiding_config::Rate;
using aiding_config::EmitValue;

namespace {

/// Smallest standard deviation written to a GNSS sample (readers reject 0).
constexpr double kMinReportedSigma = 1e-3;
/// Largest receiver latency accepted (the sampler keeps this much truth in memory).
constexpr double kMaxGnssLatency_s = 10.0;

}  // namespace

GnssSimConfig ParseGnssSimConfig(const ConfigNode& node) {
  node.RequireKeys({"rate_hz", "position_sigma_m", "velocity_sigma_mps", "lever_arm_b_m",
                    "time_offset_s", "latency_s", "outages", "outlier_probability", "outlier_size_m",
                    "start_s"});
  GnssSimConfig c;
  c.rate_hz = Rate(node, c.rate_hz, 100.0);
  c.position_sigma_ned_m = SigmaNed(node, "position_sigma_m");
  c.velocity_sigma_ned_mps = SigmaNed(node, "velocity_sigma_mps");
  c.lever_arm_b_m = node.Vector("lever_arm_b_m", c.lever_arm_b_m);
  c.time_offset_s = node.Double("time_offset_s", 0.0, -kSecondsPerDay, kSecondsPerDay);
  c.latency_s = node.Double("latency_s", 0.0, 0.0, kMaxGnssLatency_s);
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
      sampler_(config.rate_hz, config.time_offset_s, config.start_s, config.latency_s),
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
  EmitValue(out, "latency_s", config_.latency_s);
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

}  // namespace navtwin::sim
