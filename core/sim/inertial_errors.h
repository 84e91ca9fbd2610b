// Error models of the simulated inertial sensors (one gyro triad, one accelerometer triad)
// and the quantiser of their output increments. docs/imu-error-model.md gives the model,
// the YAML schema and the meaning of every key; in short, over one interval of length dt
// (the simulator's internal rate) with exact increments dtheta_true (rad), dv_true (m/s):
//
//   dtheta = (I + S_g(T) + M_g) dtheta_true + G dv_true + b_g(T) dt + ∫(β_g + r_g) + n_g
//   dv     = (I + S_a(T) + M_a) dv_true                 + b_a(T) dt + ∫(β_a + r_a) + n_a
//
// S = diag(scale factors), M = misalignment / non-orthogonality (off-diagonal), G = gyro
// g-sensitivity, b = constant bias, β = first-order Gauss–Markov bias (bias instability),
// r = bias random walk, n = white noise of the increments (ARW, VRW); S and b are
// quadratic in T - T_ref. Constants are drawn once per run from named streams of the
// run's Rng; the processes β, r, n advance with exact discretisation.
#pragma once

#include <limits>
#include <optional>
#include <string>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include "core/sim/random.h"
#include "core/config/yaml_config.h"

namespace navtwin::sim {

/// A per-axis constant of a triad: each axis drawn once per run from N(0, sigma^2), or,
/// where `fixed` is set, exactly those values (no draw).
struct AxisConstant {
  double sigma = 0.0;
  std::optional<Eigen::Vector3d> fixed;
};

/// A 3x3 constant: each used entry drawn from N(0, sigma^2), or `fixed`.
struct MatrixConstant {
  double sigma = 0.0;
  std::optional<Eigen::Matrix3d> fixed;
};

/// Errors of one triad in SI units. "u" is the rate unit of the triad (gyro rad/s,
/// accelerometer m/s^2); its increments are u*s (rad, m/s). Zero everywhere = no error.
struct TriadErrorConfig {
  AxisConstant bias;                  ///< u; constant (turn-on) bias
  double bias_instability = 0.0;      ///< u; stationary 1-sigma of the Gauss–Markov bias
  double correlation_time_s = 0.0;    ///< Gauss–Markov correlation time (> 0 when used)
  double random_walk = 0.0;           ///< u/sqrt(s); bias random walk (RRW / accel. RW)
  double white_noise = 0.0;           ///< u*sqrt(s); ARW (rad/sqrt(s)) or VRW (m/s/sqrt(s))
  AxisConstant scale_factor;          ///< dimensionless (1e-6 = 1 ppm)
  MatrixConstant misalignment;        ///< rad; off-diagonal entries only (diagonal is 0)
  double quantum = 0.0;               ///< increment units (rad, m/s); 0: no quantisation
  AxisConstant bias_per_degC;         ///< u/degC
  AxisConstant bias_per_degC2;        ///< u/degC^2
  AxisConstant scale_factor_per_degC;   ///< 1/degC
  AxisConstant scale_factor_per_degC2;  ///< 1/degC^2
};

/// IMU temperature along the run: T(t) = final + (initial - final) exp(-t / time_constant)
/// (a warm-up; constant when initial == final). Biases and scale factors depend on
/// T - reference_degC.
struct TemperatureProfile {
  double reference_degC = 25.0;
  double initial_degC = 25.0;
  double final_degC = 25.0;
  double time_constant_s = 0.0;  ///< > 0 whenever initial != final
  double At(double t_s) const;
};

/// The `imu.errors` section. A default-constructed config means "no error".
struct InertialErrorConfig {
  TriadErrorConfig gyro;
  TriadErrorConfig accel;
  MatrixConstant g_sensitivity;  ///< (rad/s) per (m/s^2); all nine entries
  TemperatureProfile temperature;
};

/// Parses `imu.errors` (schema in docs/imu-error-model.md). Throws InputError naming the
/// file, line and key for unknown keys, negative sigmas, a Gauss–Markov bias without a
/// positive correlation time, a value given both as a sigma and as fixed values, ...
InertialErrorConfig ParseInertialErrorConfig(const ConfigNode& node);

/// The constants drawn for one triad (SI, as TriadErrorConfig).
struct DrawnTriadErrors {
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d scale_factor = Eigen::Vector3d::Zero();
  Eigen::Matrix3d misalignment = Eigen::Matrix3d::Zero();
  Eigen::Vector3d bias_per_degC = Eigen::Vector3d::Zero();
  Eigen::Vector3d bias_per_degC2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d scale_factor_per_degC = Eigen::Vector3d::Zero();
  Eigen::Vector3d scale_factor_per_degC2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d bias_instability_initial = Eigen::Vector3d::Zero();  ///< β at t = 0
};

/// One triad: its drawn constants and the state of its random processes.
class TriadErrorModel {
 public:
  /// Draws the constants from the streams "<name>.bias", "<name>.scale_factor", ... of
  /// `rng`; the processes use "<name>.bias_instability", "<name>.random_walk",
  /// "<name>.noise". With `perfect`, nothing is drawn and Apply returns the truth.
  TriadErrorModel(const TriadErrorConfig& config, const Rng& rng, const std::string& name,
                  bool perfect);

  /// The measured increment over an interval of dt_s at temperature offset dT_degC
  /// (T - reference) for the true increment `truth`; advances β and r by dt_s.
  Eigen::Vector3d Apply(double dt_s, double dT_degC, const Eigen::Vector3d& truth);

  /// Total bias (u) at the end of the last interval: constant + temperature + β + r.
  Eigen::Vector3d Bias(double dT_degC) const;
  const DrawnTriadErrors& drawn() const { return drawn_; }
  /// The configuration in effect: all zero when perfect.
  const TriadErrorConfig& config() const { return config_; }

 private:
  /// Integral over dt_s of the Gauss–Markov bias; advances it (exact discretisation).
  Eigen::Vector3d GaussMarkovIntegral(double dt_s);
  /// Integral over dt_s of the bias random walk; advances it (exact in distribution).
  Eigen::Vector3d RandomWalkIntegral(double dt_s);

  TriadErrorConfig config_;
  bool perfect_;
  DrawnTriadErrors drawn_;
  Eigen::Vector3d gauss_markov_;  ///< β, u
  Eigen::Vector3d random_walk_;   ///< r, u
  Rng gauss_markov_rng_;
  Rng random_walk_rng_;
  Rng noise_rng_;
  // Gauss–Markov coefficients for the last dt (recomputed when dt changes).
  double gm_dt_s_ = -1.0;
  double gm_phi_ = 0.0;       // exp(-dt/tau)
  double gm_mean_gain_ = 0.0; // integral of β over dt given β(0) = 1: tau (1 - phi)
  double gm_l11_ = 0.0, gm_l21_ = 0.0, gm_l22_ = 0.0;  // Cholesky of cov(state, integral)
};

/// Both triads and the gyro g-sensitivity, for one IMU.
class InertialErrorModel {
 public:
  /// Draws every constant from named streams of `rng` ("gyro.*", "accel.*",
  /// "g_sensitivity"); pass e.g. Rng(seed).Stream("imu") so that another IMU of the same
  /// run (a master INS) draws from Rng(seed).Stream("master") independently.
  InertialErrorModel(const InertialErrorConfig& config, const Rng& rng, bool perfect);

  /// One internal interval (t_s - dt_s, t_s] at the IMU temperature temperature_degC
  /// (e.g. config().temperature.At(t_s - dt_s / 2)): the measured increments from the exact
  /// ones (vibration included). t_s must increase from call to call; the outputs may alias
  /// the inputs.
  /// Throws std::invalid_argument for dt_s <= 0 or a time that does not increase.
  void Apply(double t_s, double dt_s, double temperature_degC, const Eigen::Vector3d& dtheta_true,
             const Eigen::Vector3d& dv_true, Eigen::Vector3d* dtheta_meas, Eigen::Vector3d* dv_meas);

  /// Writes a YAML map of every drawn value and every process parameter, units in the
  /// keys (deg/h, ug, ppm, arcsec, deg/h/g), in the layout of the config.
  void EmitDrawn(YAML::Emitter& out) const;

  const TriadErrorModel& gyro() const { return gyro_; }
  const TriadErrorModel& accel() const { return accel_; }
  const Eigen::Matrix3d& g_sensitivity() const { return g_sensitivity_; }  ///< (rad/s)/(m/s^2)
  const InertialErrorConfig& config() const { return config_; }
  bool perfect() const { return perfect_; }
  /// Quantum of the output increments (rad, m/s); 0 when perfect.
  double gyro_quantum() const { return perfect_ ? 0.0 : config_.gyro.quantum; }
  double accel_quantum() const { return perfect_ ? 0.0 : config_.accel.quantum; }

 private:
  InertialErrorConfig config_;
  bool perfect_;
  TriadErrorModel gyro_;
  TriadErrorModel accel_;
  Eigen::Matrix3d g_sensitivity_ = Eigen::Matrix3d::Zero();
  double last_t_s_ = -std::numeric_limits<double>::infinity();
};

/// Quantisation of output increments to multiples of `quantum`, as an IMU whose counter
/// accumulates: the part below one quantum is carried to the next sample, so each output
/// is within one quantum of its input and the sum of outputs stays within half a quantum
/// of the sum of inputs (quantisation error does not accumulate into angle or velocity).
class Quantizer {
 public:
  explicit Quantizer(double quantum = 0.0) : quantum_(quantum) {}  ///< 0: pass-through
  Eigen::Vector3d Apply(const Eigen::Vector3d& increment);
  /// Sum of inputs minus sum of outputs so far; each component in [-quantum/2, quantum/2].
  const Eigen::Vector3d& residual() const { return residual_; }

 private:
  double quantum_;
  Eigen::Vector3d residual_ = Eigen::Vector3d::Zero();
};

}  // namespace navtwin::sim
