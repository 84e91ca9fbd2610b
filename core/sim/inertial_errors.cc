#include "core/sim/inertial_errors.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/rotation.h"
#include "core/units.h"

namespace navtwin::sim {
namespace {


/// How one triad's quantities are named and scaled in YAML (parsing and errors.yaml
/// share this table, so the two cannot disagree). `*_si` converts a YAML value to SI.
struct TriadUnits {
  std::string rate;             ///< unit suffix of bias keys: "deg_h" or "ug"
  double rate_si;               ///< SI rate (rad/s, m/s^2) per YAML unit
  std::string white_key;        ///< "arw_deg_sqrt_h" or "vrw_m_s_sqrt_h"
  double white_si;
  std::string random_walk_key;  ///< "rate_random_walk_deg_h_sqrt_h" or "acceleration_random_walk_ug_sqrt_h"
  double random_walk_si;
  std::string quantum_key;      ///< "quantization_rad" or "quantization_m_s"
};

TriadUnits GyroUnits() {
  return {"deg_h", kDegPerHour_radps, "arw_deg_sqrt_h", kDegToRad / kSqrtHour_sqrts,
          "rate_random_walk_deg_h_sqrt_h", kDegPerHour_radps / kSqrtHour_sqrts, "quantization_rad"};
}

TriadUnits AccelUnits() {
  return {"ug", kMicroG_mps2, "vrw_m_s_sqrt_h", 1.0 / kSqrtHour_sqrts,
          "acceleration_random_walk_ug_sqrt_h", kMicroG_mps2 / kSqrtHour_sqrts, "quantization_m_s"};
}

// ---------------------------------------------------------------- parsing

Eigen::Matrix3d ParseMatrix3(const ConfigNode& node, const std::string& key) {
  const YAML::Node rows = node.yaml()[key];
  const std::string shape = "expected a 3x3 matrix [[a, b, c], [d, e, f], [g, h, i]]";
  if (!rows.IsSequence() || rows.size() != 3) node.Fail(key, shape);
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    const YAML::Node row = rows[r];
    if (!row.IsSequence() || row.size() != 3) node.Fail(key, shape);
    for (int c = 0; c < 3; ++c) {
      try {
        m(r, c) = row[c].as<double>();
      } catch (const YAML::Exception&) {
        node.Fail(key, shape + " of numbers");
      }
      if (!std::isfinite(m(r, c))) node.Fail(key, "must be finite");
    }
  }
  return m;
}

void RequireNotBoth(const ConfigNode& node, const std::string& sigma_key, const std::string& fixed_key) {
  if (node.Has(sigma_key) && node.Has(fixed_key)) {
    node.Fail(fixed_key, "give either " + sigma_key + " (1-sigma of a per-run draw) or " + fixed_key +
                             " (fixed values), not both");
  }
}

/// `sigma_key: s` (1-sigma per axis, >= 0) or `fixed_key: [x, y, z]`, times `si`.
AxisConstant ParseAxisConstant(const ConfigNode& node, const std::string& sigma_key,
                               const std::string& fixed_key, double si) {
  RequireNotBoth(node, sigma_key, fixed_key);
  AxisConstant c;
  c.sigma = node.NonNegative(sigma_key, 0.0) * si;
  if (node.Has(fixed_key)) c.fixed = node.Vector(fixed_key, Eigen::Vector3d::Zero()) * si;
  return c;
}

MatrixConstant ParseMatrixConstant(const ConfigNode& node, const std::string& sigma_key,
                                   const std::string& fixed_key, double si) {
  RequireNotBoth(node, sigma_key, fixed_key);
  MatrixConstant c;
  c.sigma = node.NonNegative(sigma_key, 0.0) * si;
  if (node.Has(fixed_key)) c.fixed = ParseMatrix3(node, fixed_key) * si;
  return c;
}

void ParseTemperatureSensitivity(const ConfigNode& node, const TriadUnits& u, TriadErrorConfig* c) {
  const std::string b1 = "bias_" + u.rate + "_per_degC", b1f = "bias_fixed_" + u.rate + "_per_degC";
  const std::string b2 = b1 + "2", b2f = b1f + "2";
  const std::string s1 = "scale_factor_ppm_per_degC", s1f = "scale_factor_fixed_ppm_per_degC";
  const std::string s2 = s1 + "2", s2f = s1f + "2";
  node.RequireKeys({b1.c_str(), b1f.c_str(), b2.c_str(), b2f.c_str(), s1.c_str(), s1f.c_str(),
                    s2.c_str(), s2f.c_str()});
  c->bias_per_degC = ParseAxisConstant(node, b1, b1f, u.rate_si);
  c->bias_per_degC2 = ParseAxisConstant(node, b2, b2f, u.rate_si);
  c->scale_factor_per_degC = ParseAxisConstant(node, s1, s1f, kPpm);
  c->scale_factor_per_degC2 = ParseAxisConstant(node, s2, s2f, kPpm);
}

TriadErrorConfig ParseTriad(const ConfigNode& node, const TriadUnits& u) {
  const std::string bias = "bias_" + u.rate, bias_fixed = "bias_fixed_" + u.rate;
  const std::string instability = "bias_instability_" + u.rate;
  node.RequireKeys({bias.c_str(), bias_fixed.c_str(), instability.c_str(), "correlation_time_s",
                    u.random_walk_key.c_str(), u.white_key.c_str(), "scale_factor_ppm",
                    "scale_factor_fixed_ppm", "misalignment_arcsec", "misalignment_fixed_arcsec",
                    u.quantum_key.c_str(), "temperature"});
  TriadErrorConfig c;
  c.bias = ParseAxisConstant(node, bias, bias_fixed, u.rate_si);
  c.bias_instability = node.NonNegative(instability, 0.0) * u.rate_si;
  c.correlation_time_s = node.NonNegative("correlation_time_s", 0.0);
  if (c.bias_instability > 0.0 && !(c.correlation_time_s > 0.0)) {
    node.Fail("correlation_time_s", "required (> 0) with " + instability);
  }
  c.random_walk = node.NonNegative(u.random_walk_key, 0.0) * u.random_walk_si;
  c.white_noise = node.NonNegative(u.white_key, 0.0) * u.white_si;
  c.scale_factor = ParseAxisConstant(node, "scale_factor_ppm", "scale_factor_fixed_ppm", kPpm);
  c.misalignment = ParseMatrixConstant(node, "misalignment_arcsec", "misalignment_fixed_arcsec", kArcsec_rad);
  if (c.misalignment.fixed && c.misalignment.fixed->diagonal().cwiseAbs().maxCoeff() > 0.0) {
    node.Fail("misalignment_fixed_arcsec", "the diagonal must be 0 (scale factors are the diagonal)");
  }
  c.quantum = node.NonNegative(u.quantum_key, 0.0);
  ParseTemperatureSensitivity(node.Child("temperature"), u, &c);
  return c;
}

TemperatureProfile ParseTemperatureProfile(const ConfigNode& node) {
  node.RequireKeys({"reference_degC", "initial_degC", "final_degC", "time_constant_s"});
  constexpr double kAbsZero_degC = -273.15, kMax_degC = 1000.0;
  TemperatureProfile p;
  p.reference_degC = node.Double("reference_degC", p.reference_degC, kAbsZero_degC, kMax_degC);
  p.initial_degC = node.Double("initial_degC", p.reference_degC, kAbsZero_degC, kMax_degC);
  p.final_degC = node.Double("final_degC", p.initial_degC, kAbsZero_degC, kMax_degC);
  p.time_constant_s = node.NonNegative("time_constant_s", 0.0);
  if (p.final_degC != p.initial_degC && !(p.time_constant_s > 0.0)) {
    node.Fail("time_constant_s", "required (> 0) when final_degC differs from initial_degC");
  }
  return p;
}

// ---------------------------------------------------------------- drawing

Eigen::Vector3d DrawAxis(const AxisConstant& c, const Rng& rng, const std::string& stream) {
  if (c.fixed) return *c.fixed;
  if (!(c.sigma > 0.0)) return Eigen::Vector3d::Zero();
  Rng r = rng.Stream(stream);
  return r.Normal3(c.sigma);
}

/// Draws the entries of `c` where `use(row, col)`, row by row; the others stay 0.
template <typename Use>
Eigen::Matrix3d DrawMatrix(const MatrixConstant& c, const Rng& rng, const std::string& stream, Use use) {
  if (c.fixed) return *c.fixed;
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  if (!(c.sigma > 0.0)) return m;
  Rng r = rng.Stream(stream);
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) {
      if (use(row, col)) m(row, col) = r.Normal(c.sigma);
    }
  }
  return m;
}

/// x - 2 (1 - e^-x) + (1 - e^-2x) / 2: the variance of the Gauss–Markov integral over
/// dt in units of 2 sigma^2 tau^2 (x = dt / tau). Its series near 0 avoids cancellation.
double GaussMarkovIntegralShape(double x) {
  if (x < 1e-3) return x * x * x * (1.0 / 3.0 - x * (1.0 / 4.0 - x * (7.0 / 60.0 - x / 24.0)));
  return x + 2.0 * std::expm1(-x) - 0.5 * std::expm1(-2.0 * x);
}

// ---------------------------------------------------------------- errors.yaml

void EmitTriad(YAML::Emitter& out, const TriadErrorModel& model, const TriadUnits& u) {
  const TriadErrorConfig& c = model.config();
  const DrawnTriadErrors& d = model.drawn();
  out << YAML::BeginMap;
  EmitVector(out, "bias_" + u.rate, d.bias, u.rate_si);
  out << YAML::Key << "bias_instability_" + u.rate << YAML::Value << c.bias_instability / u.rate_si;
  out << YAML::Key << "correlation_time_s" << YAML::Value << c.correlation_time_s;
  EmitVector(out, "bias_instability_initial_" + u.rate, d.bias_instability_initial, u.rate_si);
  out << YAML::Key << u.random_walk_key << YAML::Value << c.random_walk / u.random_walk_si;
  out << YAML::Key << u.white_key << YAML::Value << c.white_noise / u.white_si;
  EmitVector(out, "scale_factor_ppm", d.scale_factor, kPpm);
  EmitMatrix(out, "misalignment_arcsec", d.misalignment, kArcsec_rad);
  out << YAML::Key << u.quantum_key << YAML::Value << c.quantum;
  out << YAML::Key << "temperature" << YAML::Value << YAML::BeginMap;
  EmitVector(out, "bias_" + u.rate + "_per_degC", d.bias_per_degC, u.rate_si);
  EmitVector(out, "bias_" + u.rate + "_per_degC2", d.bias_per_degC2, u.rate_si);
  EmitVector(out, "scale_factor_ppm_per_degC", d.scale_factor_per_degC, kPpm);
  EmitVector(out, "scale_factor_ppm_per_degC2", d.scale_factor_per_degC2, kPpm);
  out << YAML::EndMap << YAML::EndMap;
}

}  // namespace

double TemperatureProfile::At(double t_s) const {
  if (final_degC == initial_degC) return initial_degC;
  return final_degC + (initial_degC - final_degC) * std::exp(-std::max(t_s, 0.0) / time_constant_s);
}

InertialErrorConfig ParseInertialErrorConfig(const ConfigNode& node) {
  node.RequireKeys({"gyro", "accel", "g_sensitivity_deg_h_per_g", "g_sensitivity_fixed_deg_h_per_g",
                    "temperature_profile"});
  InertialErrorConfig c;
  c.gyro = ParseTriad(node.Child("gyro"), GyroUnits());
  c.accel = ParseTriad(node.Child("accel"), AccelUnits());
  c.g_sensitivity = ParseMatrixConstant(node, "g_sensitivity_deg_h_per_g", "g_sensitivity_fixed_deg_h_per_g",
                                        kDegPerHour_radps / kStandardGravity_mps2);
  c.temperature = ParseTemperatureProfile(node.Child("temperature_profile"));
  return c;
}

// ---------------------------------------------------------------- TriadErrorModel

TriadErrorModel::TriadErrorModel(const TriadErrorConfig& config, const Rng& rng, const std::string& name,
                                 bool perfect)
    : config_(perfect ? TriadErrorConfig{} : config),
      perfect_(perfect),
      gauss_markov_(Eigen::Vector3d::Zero()),
      random_walk_(Eigen::Vector3d::Zero()),
      gauss_markov_rng_(rng.Stream(name + ".bias_instability")),
      random_walk_rng_(rng.Stream(name + ".random_walk")),
      noise_rng_(rng.Stream(name + ".noise")) {
  if (perfect_) return;
  drawn_.bias = DrawAxis(config.bias, rng, name + ".bias");
  drawn_.scale_factor = DrawAxis(config.scale_factor, rng, name + ".scale_factor");
  drawn_.misalignment = DrawMatrix(config.misalignment, rng, name + ".misalignment",
                                   [](int r, int c) { return r != c; });
  drawn_.bias_per_degC = DrawAxis(config.bias_per_degC, rng, name + ".bias_per_degC");
  drawn_.bias_per_degC2 = DrawAxis(config.bias_per_degC2, rng, name + ".bias_per_degC2");
  drawn_.scale_factor_per_degC = DrawAxis(config.scale_factor_per_degC, rng, name + ".scale_factor_per_degC");
  drawn_.scale_factor_per_degC2 = DrawAxis(config.scale_factor_per_degC2, rng, name + ".scale_factor_per_degC2");
  // The Gauss–Markov bias starts in its stationary distribution, so its statistics do
  // not depend on time.
  if (config.bias_instability > 0.0) {
    gauss_markov_ = gauss_markov_rng_.Normal3(config.bias_instability);
    drawn_.bias_instability_initial = gauss_markov_;
  }
}

Eigen::Vector3d TriadErrorModel::Apply(double dt_s, double dT_degC, const Eigen::Vector3d& truth) {
  if (perfect_) return truth;
  const DrawnTriadErrors& d = drawn_;
  const Eigen::Vector3d sf = d.scale_factor + dT_degC * (d.scale_factor_per_degC + dT_degC * d.scale_factor_per_degC2);
  const Eigen::Vector3d bias = d.bias + dT_degC * (d.bias_per_degC + dT_degC * d.bias_per_degC2);
  // (I + S + M) truth written as truth + ..., so that zero errors return truth exactly.
  Eigen::Vector3d out = truth + sf.cwiseProduct(truth) + d.misalignment * truth + bias * dt_s;
  if (config_.bias_instability > 0.0) out += GaussMarkovIntegral(dt_s);
  if (config_.random_walk > 0.0) out += RandomWalkIntegral(dt_s);
  // White rate noise of density N integrates to an increment of variance N^2 dt.
  if (config_.white_noise > 0.0) out += noise_rng_.Normal3(config_.white_noise * std::sqrt(dt_s));
  return out;
}

Eigen::Vector3d TriadErrorModel::GaussMarkovIntegral(double dt_s) {
  // dβ = -β/τ dt + sqrt(2 σ²/τ) dW. Over dt, given β(0), the end state β(dt) and the
  // integral I = ∫β are jointly Gaussian:
  //   β(dt) = φ β(0) + w1,   I = τ (1 - φ) β(0) + w2,   φ = exp(-dt/τ),
  //   var w1 = σ² (1 - φ²), cov(w1, w2) = σ² τ (1 - φ)², var w2 = 2 σ² τ² g(dt/τ),
  // drawn through the Cholesky factor of that covariance (exact for any dt).
  if (dt_s != gm_dt_s_) {
    const double tau = config_.correlation_time_s, var = config_.bias_instability * config_.bias_instability;
    const double x = dt_s / tau;
    const double one_minus_phi = -std::expm1(-x);
    const double v11 = var * -std::expm1(-2.0 * x);
    const double v21 = var * tau * one_minus_phi * one_minus_phi;
    const double v22 = 2.0 * var * tau * tau * GaussMarkovIntegralShape(x);
    gm_dt_s_ = dt_s;
    gm_phi_ = std::exp(-x);
    gm_mean_gain_ = tau * one_minus_phi;
    gm_l11_ = std::sqrt(v11);
    gm_l21_ = v21 / gm_l11_;
    gm_l22_ = std::sqrt(std::max(0.0, v22 - gm_l21_ * gm_l21_));
  }
  Eigen::Vector3d integral;
  for (int i = 0; i < 3; ++i) {
    const double z1 = gauss_markov_rng_.Normal(), z2 = gauss_markov_rng_.Normal();
    integral[i] = gm_mean_gain_ * gauss_markov_[i] + gm_l21_ * z1 + gm_l22_ * z2;
    gauss_markov_[i] = gm_phi_ * gauss_markov_[i] + gm_l11_ * z1;
  }
  return integral;
}

Eigen::Vector3d TriadErrorModel::RandomWalkIntegral(double dt_s) {
  // dr = K dW. Over dt: r(dt) = r(0) + K W(dt) and ∫r = r(0) dt + K ∫W, where
  // var W = dt, cov(W, ∫W) = dt²/2, var ∫W = dt³/3; Cholesky: W = sqrt(dt) z1,
  // ∫W = dt^1.5 (z1/2 + z2/sqrt(12)) (the trapezoid plus the Brownian-bridge area).
  const double k = config_.random_walk, sqrt_dt = std::sqrt(dt_s);
  Eigen::Vector3d integral;
  for (int i = 0; i < 3; ++i) {
    const double z1 = random_walk_rng_.Normal(), z2 = random_walk_rng_.Normal();
    integral[i] = random_walk_[i] * dt_s + k * dt_s * sqrt_dt * (0.5 * z1 + z2 / std::sqrt(12.0));
    random_walk_[i] += k * sqrt_dt * z1;
  }
  return integral;
}

Eigen::Vector3d TriadErrorModel::Bias(double dT_degC) const {
  const DrawnTriadErrors& d = drawn_;
  return d.bias + dT_degC * (d.bias_per_degC + dT_degC * d.bias_per_degC2) + gauss_markov_ + random_walk_;
}

// ---------------------------------------------------------------- InertialErrorModel

InertialErrorModel::InertialErrorModel(const InertialErrorConfig& config, const Rng& rng, bool perfect)
    : config_(config),
      perfect_(perfect),
      gyro_(config.gyro, rng, "gyro", perfect),
      accel_(config.accel, rng, "accel", perfect) {
  if (!perfect) {
    g_sensitivity_ = DrawMatrix(config.g_sensitivity, rng, "g_sensitivity", [](int, int) { return true; });
  }
}

void InertialErrorModel::Apply(double t_s, double dt_s, double temperature_degC,
                               const Eigen::Vector3d& dtheta_true, const Eigen::Vector3d& dv_true,
                               Eigen::Vector3d* dtheta_meas, Eigen::Vector3d* dv_meas) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) {
    throw std::invalid_argument("InertialErrorModel::Apply: dt_s must be positive and finite");
  }
  if (!(t_s > last_t_s_)) {
    throw std::invalid_argument("InertialErrorModel::Apply: t_s must increase from call to call");
  }
  last_t_s_ = t_s;
  if (perfect_) {
    *dtheta_meas = dtheta_true;
    *dv_meas = dv_true;
    return;
  }
  const double dT = temperature_degC - config_.temperature.reference_degC;
  const Eigen::Vector3d dtheta = gyro_.Apply(dt_s, dT, dtheta_true) + g_sensitivity_ * dv_true;
  const Eigen::Vector3d dv = accel_.Apply(dt_s, dT, dv_true);
  *dtheta_meas = dtheta;
  *dv_meas = dv;
}

void InertialErrorModel::EmitDrawn(YAML::Emitter& out) const {
  const TemperatureProfile& t = config_.temperature;
  out << YAML::BeginMap;
  out << YAML::Key << "perfect" << YAML::Value << perfect_;
  out << YAML::Key << "temperature_profile" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "reference_degC" << YAML::Value << t.reference_degC;
  out << YAML::Key << "initial_degC" << YAML::Value << t.initial_degC;
  out << YAML::Key << "final_degC" << YAML::Value << t.final_degC;
  out << YAML::Key << "time_constant_s" << YAML::Value << t.time_constant_s;
  out << YAML::EndMap;
  out << YAML::Key << "gyro" << YAML::Value;
  EmitTriad(out, gyro_, GyroUnits());
  out << YAML::Key << "accel" << YAML::Value;
  EmitTriad(out, accel_, AccelUnits());
  EmitMatrix(out, "g_sensitivity_deg_h_per_g", g_sensitivity_, kDegPerHour_radps / kStandardGravity_mps2);
  out << YAML::EndMap;
}

// ---------------------------------------------------------------- Quantizer

Eigen::Vector3d Quantizer::Apply(const Eigen::Vector3d& increment) {
  if (!(quantum_ > 0.0)) return increment;
  // The counter holds the sum of all inputs; the output is the change of its value
  // rounded to whole quanta, and the rounding remainder stays in the counter.
  const Eigen::Vector3d total = increment + residual_;
  Eigen::Vector3d out;
  for (int i = 0; i < 3; ++i) out[i] = quantum_ * std::round(total[i] / quantum_);
  residual_ = total - out;
  return out;
}

}  // namespace navtwin::sim
