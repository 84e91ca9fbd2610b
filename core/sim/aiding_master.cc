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
