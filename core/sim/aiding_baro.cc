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

}  // namespace navtwin::sim
