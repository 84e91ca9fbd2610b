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

using aiding_config::RequireNotBoth;
using aiding_config::Matrix3x3;
using aiding_config::Rate;
using aiding_config::EmitValue;

namespace {

/// IGRF-13 axial dipole term |g10| at epoch 2020.0 (29404.8 nT), uT.
constexpr double kDipoleField_uT = 29.4048;

}  // namespace

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
  if (node.Has("soft_iron_fixed")) c.soft_iron_fixed = Matrix3x3(node, "soft_iron_fixed");
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

}  // namespace navtwin::sim
