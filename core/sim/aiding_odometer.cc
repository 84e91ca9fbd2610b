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
using aiding_config::Rate;
using aiding_config::EmitValue;

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

}  // namespace navtwin::sim
