#include "core/sim/vibration.h"

#include <cmath>
#include <string>

#include "core/rotation.h"

namespace navtwin::sim {
namespace {

constexpr const char* kAxisNames[3] = {"x", "y", "z"};

std::array<bool, 3> ParseAxes(const ConfigNode& node) {
  if (!node.Has("axes")) node.Fail("axes", "required (a list of x, y, z)");
  const YAML::Node list = node.yaml()["axes"];
  if (!list.IsSequence() || list.size() == 0) node.Fail("axes", "expected a list of x, y, z");
  std::array<bool, 3> axes{{false, false, false}};
  for (const YAML::Node& item : list) {
    const std::string name = item.IsScalar() ? item.as<std::string>() : std::string();
    int axis = -1;
    for (int i = 0; i < 3; ++i) axis = name == kAxisNames[i] ? i : axis;
    if (axis < 0) node.Fail("axes", "expected a list of x, y, z, got '" + name + "'");
    if (axes[axis]) node.Fail("axes", "axis " + name + " listed twice");
    axes[axis] = true;
  }
  return axes;
}

std::vector<double> ParseGains(const ConfigNode& node) {
  const YAML::Node list = node.yaml()["harmonic_gains"];
  if (!list.IsSequence() || list.size() == 0) node.Fail("harmonic_gains", "expected a list");
  std::vector<double> gains;
  for (const YAML::Node& item : list) {
    double g = -1.0;
    try {
      g = item.as<double>();
    } catch (const YAML::Exception&) {
      node.Fail("harmonic_gains", "expected a list of numbers");
    }
    if (!std::isfinite(g) || g < 0.0) node.Fail("harmonic_gains", "each gain must be >= 0");
    gains.push_back(g);
  }
  return gains;
}

// Harmonic gains: the list if given (its length must match `harmonics` when both are
// given), else 1/k for k = 1..harmonics.
std::vector<double> ParseHarmonics(const ConfigNode& node) {
  constexpr int kMaxHarmonics = 100;
  if (node.Has("harmonic_gains")) {
    std::vector<double> gains = ParseGains(node);
    const int n = node.Int("harmonics", static_cast<int>(gains.size()), 1, kMaxHarmonics);
    if (static_cast<int>(gains.size()) != n) {
      node.Fail("harmonic_gains", "expected " + std::to_string(n) + " gains (one per harmonic)");
    }
    return gains;
  }
  const int n = node.Int("harmonics", 1, 1, kMaxHarmonics);
  std::vector<double> gains;
  for (int k = 1; k <= n; ++k) gains.push_back(1.0 / k);
  return gains;
}

VibrationToneConfig ParseTone(const ConfigNode& node) {
  node.RequireKeys({"axes", "frequency_hz", "linear_g", "angular_deg_s", "amplitude", "harmonics",
                    "harmonic_gains"});
  VibrationToneConfig tone;
  tone.axes = ParseAxes(node);
  if (!node.Has("frequency_hz")) node.Fail("frequency_hz", "required ([lo, hi] in Hz)");
  tone.frequency_hz = node.Range("frequency_hz", Eigen::Vector2d::Zero());
  if (!(tone.frequency_hz[0] > 0.0)) node.Fail("frequency_hz", "must be > 0");
  tone.linear_mps2 = node.Double("linear_g", 0.0, 0.0, 1e6) * kStandardGravity_mps2;
  tone.angular_radps = node.Double("angular_deg_s", 0.0, 0.0, 1e9) * kDegPerSecond_radps;
  const std::string amplitude = node.String("amplitude", "normal");
  if (amplitude != "normal" && amplitude != "fixed") {
    node.Fail("amplitude", "expected normal or fixed, got '" + amplitude + "'");
  }
  tone.random_amplitude = amplitude == "normal";
  tone.harmonic_gains = ParseHarmonics(node);
  return tone;
}

// The fractional part of f t (cycles), computed so that the low-order bits of the product
// survive at large t: the rounding error of f*t is recovered exactly with an fma, and
// subtracting the integer part of a double is exact. The phase of a 200 Hz tone after 1 h
// is thus accurate to ~1e-16 cycles instead of ~1e-10.
double CycleFraction(double f_hz, double t_s) {
  const double c = f_hz * t_s;
  const double rounding = std::fma(f_hz, t_s, -c);
  return (c - std::floor(c)) + rounding;
}

// Appends the tones of one kind (linear or angular) of one group: per axis one amplitude
// (drawn or fixed) shared by the harmonics through their gains, and a phase per harmonic.
void DrawKind(const VibrationToneConfig& config, int group, bool angular, double fundamental_hz,
              const Rng& group_rng, std::vector<VibrationTone>* tones) {
  const double value = angular ? config.angular_radps : config.linear_mps2;
  if (value == 0.0) return;
  const std::string kind = angular ? "angular" : "linear";
  Rng amplitude_rng = group_rng.Stream(kind);
  Rng phase_rng = group_rng.Stream(kind + ".phase");
  for (int axis = 0; axis < 3; ++axis) {
    if (!config.axes[axis]) continue;
    const double amplitude = config.random_amplitude ? amplitude_rng.Normal(value) : value;
    for (std::size_t k = 1; k <= config.harmonic_gains.size(); ++k) {
      VibrationTone tone;
      tone.group = group;
      tone.harmonic = static_cast<int>(k);
      tone.axis = axis;
      tone.angular = angular;
      tone.frequency_hz = static_cast<double>(k) * fundamental_hz;
      tone.amplitude = config.harmonic_gains[k - 1] * amplitude;
      tone.phase_rad = phase_rng.Uniform(0.0, 2.0 * M_PI);
      tones->push_back(tone);
    }
  }
}

}  // namespace

VibrationConfig ParseVibrationConfig(const ConfigNode& node) {
  node.RequireKeys({"tones"});
  VibrationConfig config;
  for (const ConfigNode& tone : node.Elements("tones")) config.tones.push_back(ParseTone(tone));
  return config;
}

VibrationModel::VibrationModel(const VibrationConfig& config, const Rng& rng, bool perfect) {
  if (perfect) return;
  for (std::size_t i = 0; i < config.tones.size(); ++i) {
    const VibrationToneConfig& group = config.tones[i];
    const Rng group_rng = rng.Stream("vibration.tones[" + std::to_string(i) + "]");
    Rng frequency_rng = group_rng.Stream("frequency");
    const double fundamental_hz =
        frequency_rng.Uniform(group.frequency_hz[0], group.frequency_hz[1]);
    DrawKind(group, static_cast<int>(i), false, fundamental_hz, group_rng, &tones_);
    DrawKind(group, static_cast<int>(i), true, fundamental_hz, group_rng, &tones_);
  }
}

void VibrationModel::Increment(double t0_s, double t1_s, Eigen::Vector3d* dtheta_rad,
                               Eigen::Vector3d* dv_mps) const {
  dtheta_rad->setZero();
  dv_mps->setZero();
  const double dt_s = t1_s - t0_s;
  for (const VibrationTone& tone : tones_) {
    // integral_{t0}^{t1} A sin(2 pi f t + phi) dt
    //   = (A / (pi f)) sin(2 pi f t_mid + phi) sin(pi f (t1 - t0)),
    // the product form, which has no cancellation for short intervals.
    const double half_cycles = 0.5 * tone.frequency_hz * dt_s;
    const double mid_phase =
        2.0 * M_PI * (CycleFraction(tone.frequency_hz, t0_s) + half_cycles) + tone.phase_rad;
    const double integral = tone.amplitude / (M_PI * tone.frequency_hz) * std::sin(mid_phase) *
                            std::sin(M_PI * tone.frequency_hz * dt_s);
    (tone.angular ? *dtheta_rad : *dv_mps)[tone.axis] += integral;
  }
}

void VibrationModel::Rate(double t_s, Eigen::Vector3d* omega_radps, Eigen::Vector3d* f_mps2) const {
  omega_radps->setZero();
  f_mps2->setZero();
  for (const VibrationTone& tone : tones_) {
    const double phase = 2.0 * M_PI * CycleFraction(tone.frequency_hz, t_s) + tone.phase_rad;
    (tone.angular ? *omega_radps : *f_mps2)[tone.axis] += tone.amplitude * std::sin(phase);
  }
}

void VibrationModel::EmitDrawn(YAML::Emitter& out) const {
  out << YAML::BeginMap << YAML::Key << "tones" << YAML::Value << YAML::BeginSeq;
  for (const VibrationTone& tone : tones_) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "group" << YAML::Value << tone.group;
    out << YAML::Key << "harmonic" << YAML::Value << tone.harmonic;
    out << YAML::Key << "axis" << YAML::Value << kAxisNames[tone.axis];
    out << YAML::Key << "kind" << YAML::Value << (tone.angular ? "angular" : "linear");
    out << YAML::Key << "frequency_hz" << YAML::Value << tone.frequency_hz;
    if (tone.angular) {
      out << YAML::Key << "amplitude_deg_s" << YAML::Value << tone.amplitude * kRadToDeg;
    } else {
      out << YAML::Key << "amplitude_g" << YAML::Value << tone.amplitude / kStandardGravity_mps2;
    }
    out << YAML::Key << "phase_rad" << YAML::Value << tone.phase_rad;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
}

}  // namespace navtwin::sim
