// Aiding and reference streams of the simulator: GNSS position and velocity at the
// antenna, magnetometer, barometer and a master INS delivered with a transfer delay.
// Each model takes the truth stream (TruthSample at the internal rate, >= 100 Hz) one
// sample at a time and emits its own samples at its own epochs. docs/aiding-models.md
// gives the models, the YAML schema and the choices made (interpolation, perfect mode).
//
// Common rules:
//  - Epochs are t_k = k / rate_hz (+ an offset) on the truth time scale; the value at an
//    epoch is the truth sample at that time when one lies within 1e-9 s, else the truth
//    interpolated between the two samples around it (InterpolateTruth).
//  - Each model draws from its own named streams of the run's Rng ("gnss.position_noise",
//    "mag.hard_iron", ...), so switching one error source off leaves the others unchanged.
//  - `perfect` turns every sensor error off (noise, bias, iron, outliers, master attitude
//    errors); scenario conditions stay: GNSS outages, lever arm and epoch offset, the
//    magnetometer's field and 2-axis mode, the master's transfer delay.
//  - EmitDrawn writes a YAML map of the drawn values with units in the keys.
#pragma once

#include <deque>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include "core/config/yaml_config.h"
#include "core/mag_iron_model.h"
#include "core/sim/random.h"
#include "core/sim/truth.h"
#include "core/io/csv_odometer.h"
#include "core/types.h"

namespace navtwin::sim {

/// The truth at a.t_s <= t_s <= b.t_s from the two samples around it (accurate to O(h^4),
/// h = b.t_s - a.t_s):
///  - position (lat, lon, h) and velocity: cubic Hermite with the end derivatives (the
///    position rate from v_n; a_n_mps2 for the velocity);
///  - attitude: q_a Exp(phi(t)) with phi a cubic Hermite in the body rotation vector whose
///    end slopes are the body rates over NED (omega_ib_b - R_b_n (omega_ie + omega_en));
///  - omega_ib_b: cubic Hermite with alpha_ib_b; f_b, alpha, a_n: linear.
/// `exact` carries no increment (dt_s = 0). t_s == a.t_s or b.t_s returns that sample.
/// Throws std::invalid_argument unless a.t_s < b.t_s and t_s lies in [a.t_s, b.t_s].
TruthSample InterpolateTruth(const TruthSample& a, const TruthSample& b, double t_s);

/// Epochs t_k = k / rate_hz + offset_s (k integer, no accumulated rounding) at or after
/// start_s, taken from a truth stream. With a delay, the epoch tagged t_k carries the
/// truth at t_k - delay_s (a ring buffer keeps the truth of the last delay_s seconds).
class EpochSampler {
 public:
  /// Throws std::invalid_argument unless rate_hz > 0 and delay_s >= 0 (finite).
  EpochSampler(double rate_hz, double offset_s, double start_s, double delay_s = 0.0);

  struct Epoch {
    double tag_s;       ///< the epoch t_k
    TruthSample truth;  ///< the truth at t_k - delay_s
  };

  /// The epoch in (time of the previous push, truth.t_s], if there is one. Epochs whose
  /// truth time lies before the first pushed sample are skipped. Pushes must increase in
  /// time; throws std::invalid_argument when two epochs fall in one truth interval (a
  /// rate above the truth rate).
  std::optional<Epoch> Push(const TruthSample& truth);

 private:
  double TagAt(long k) const { return static_cast<double>(k) / rate_hz_ + offset_s_; }
  TruthSample TruthAt(double t_s) const;

  double rate_hz_;
  double offset_s_;
  double start_s_;
  double delay_s_;
  long k_ = 0;  ///< index of the next epoch
  bool started_ = false;
  std::deque<TruthSample> buffer_;  ///< truth from just before the next epoch's data time
};

// ------------------------------------------------------------------------------- GNSS

/// `gnss:` (SI inside; YAML keys in docs/aiding-models.md).
struct GnssSimConfig {
  double rate_hz = 1.0;
  Eigen::Vector3d position_sigma_ned_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_sigma_ned_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d lever_arm_b_m = Eigen::Vector3d::Zero();  ///< antenna from the IMU, body axes
  double time_offset_s = 0.0;              ///< epochs at k / rate_hz + time_offset_s
  double latency_s = 0.0;                  ///< the fix tagged t describes the antenna at t - latency_s
  std::vector<Eigen::Vector2d> outages_s;  ///< [start, end): no sample in these intervals
  double outlier_probability = 0.0;        ///< per epoch
  double outlier_size_m = 0.0;             ///< length of an outlier's position offset
  double start_s = 0.0;                    ///< no epoch before this time
};

/// Parses `gnss:`. position_sigma_m / velocity_sigma_mps are a scalar (every axis),
/// [horizontal, vertical] or [N, E, D]. Throws InputError naming the file, line and key.
GnssSimConfig ParseGnssSimConfig(const ConfigNode& node);

/// Error-free antenna position and velocity for the IMU truth and a lever arm (body axes):
/// position = IMU position + R_n_b l through ECEF (exact at any size), velocity
/// v_n + R_n_b (omega_ib_b x l) - omega_ie_n x (R_n_b l), expressed in the antenna's NED.
GnssSample AntennaTruth(const TruthSample& truth, const Eigen::Vector3d& lever_arm_b_m);

/// One outlier: when it happened and the position offset added (NED at the antenna, m).
struct GnssOutlier {
  double t_s = 0.0;
  Eigen::Vector3d offset_ned_m = Eigen::Vector3d::Zero();
};

/// GNSS receiver: antenna position and velocity (of latency_s before the tag) with white
/// noise (N(0, sigma^2) per NED
/// axis), outliers (with probability p an extra position offset of outlier_size_m in a
/// uniformly random direction) and outages. The reported standard deviations are the
/// configured sigmas (also in perfect mode: they describe the receiver), at least 1 mm and
/// 1 mm/s because readers reject zero sigmas. quality 1, num_sats 10, gps_week -1.
/// Noise is drawn for every epoch, outage or not, so outages do not shift the noise of
/// later samples.
class GnssSimulator {
 public:
  /// Throws std::invalid_argument for a configuration ParseGnssSimConfig would reject.
  GnssSimulator(const GnssSimConfig& config, const Rng& rng, bool perfect);
  std::optional<GnssSample> Push(const TruthSample& truth);
  /// rate, sigmas, lever arm, time offset, latency, outages, outlier settings and the outliers
  /// drawn so far (call after the run for the full list).
  void EmitDrawn(YAML::Emitter& out) const;
  const std::vector<GnssOutlier>& outliers() const { return outliers_; }

 private:
  bool InOutage(double t_s) const;
  std::optional<GnssSample> Measure(double t_s, const TruthSample& truth);

  GnssSimConfig config_;
  bool perfect_;
  EpochSampler sampler_;
  Rng position_rng_;
  Rng velocity_rng_;
  Rng outlier_rng_;
  std::vector<GnssOutlier> outliers_;
};

// ----------------------------------------------------------------------- magnetometer

/// `mag:` (SI inside). The field defaults come from an axial dipole (MagSimulator).
struct MagSimConfig {
  double rate_hz = 10.0;
  std::optional<double> declination_rad;  ///< east of true north positive
  std::optional<double> inclination_rad;  ///< below the horizontal positive
  std::optional<double> intensity_uT;
  double hard_iron_sigma_uT = 0.0;  ///< per-axis 1-sigma of a per-run draw
  std::optional<Eigen::Vector3d> hard_iron_fixed_uT;
  double soft_iron_sigma = 0.0;  ///< per-entry 1-sigma of S (dimensionless)
  std::optional<Eigen::Matrix3d> soft_iron_fixed;
  bool soft_iron_symmetric = false;  ///< draw S symmetric (6 draws, mirrored)
  double noise_uT = 0.0;             ///< white noise per axis, 1-sigma
  bool two_axis = false;             ///< no z axis: m_z reads 0
};

MagSimConfig ParseMagSimConfig(const ConfigNode& node);

/// Earth field in NED (uT) from declination D, inclination I and intensity B:
/// B [cos I cos D, cos I sin D, sin I].
Eigen::Vector3d MagneticFieldNed_uT(double declination_rad, double inclination_rad,
                                    double intensity_uT);

/// Magnetometer: m_b = (I + S) R_b_n m_n + h + n (uT), S soft iron, h hard iron
/// (core/mag_iron_model.h), n white noise. A 2-axis sensor (seed 001's HMC1052) has no z axis: m_z = 0 (noise and iron
/// included), so its readers must ignore z. Missing field values default to a centred
/// axial dipole at the start latitude lat (geographic = magnetic latitude):
/// D = 0, tan I = 2 tan(lat), B = B0 sqrt(1 + 3 sin^2 lat), B0 = 29.4 uT (the IGRF-13
/// dipole term |g10| at 2020.0); e.g. I = 57 deg at 37.5 deg N as in seed 001.
class MagSimulator {
 public:
  MagSimulator(const MagSimConfig& config, double start_lat_rad, const Rng& rng, bool perfect);
  std::optional<MagSample> Push(const TruthSample& truth);
  /// Field (NED, declination, inclination, intensity), hard and soft iron, noise.
  void EmitDrawn(YAML::Emitter& out) const;

  const Eigen::Vector3d& field_ned_uT() const { return field_ned_uT_; }
  const MagIronModel& iron() const { return iron_; }
  const Eigen::Vector3d& hard_iron_uT() const { return iron_.hard_iron_uT; }
  const Eigen::Matrix3d& soft_iron() const { return iron_.soft_iron; }  ///< S of (I + S)

 private:
  MagSimConfig config_;
  bool perfect_;
  double declination_rad_, inclination_rad_, intensity_uT_;
  Eigen::Vector3d field_ned_uT_;
  MagIronModel iron_;  ///< zero when perfect
  EpochSampler sampler_;
  Rng noise_rng_;
};

// -------------------------------------------------------------------------- barometer

/// `baro:` (SI inside).
struct BaroSimConfig {
  double rate_hz = 10.0;
  double bias_sigma_m = 0.0;  ///< 1-sigma of a per-run constant bias
  std::optional<double> bias_fixed_m;
  double noise_m = 0.0;  ///< white noise, 1-sigma
  bool pressure = true;  ///< also give pressure and temperature (ISA)
};

BaroSimConfig ParseBaroSimConfig(const ConfigNode& node);

/// International Standard Atmosphere (ISO 2533:1975, identical to the U.S. Standard
/// Atmosphere 1976 below 32 km): pressure (Pa) and temperature (K) at geometric altitude
/// z (m above mean sea level), converted to geopotential H = r0 z / (r0 + z), r0 =
/// 6356766 m. Troposphere (H < 11 km): T = 288.15 - 0.0065 H, p = 101325 (T/288.15)^5.255877;
/// tropopause (11-20 km): T = 216.65 K, p = 22632.06 exp(-g0 M (H - 11000)/(R* 216.65)).
/// Throws std::out_of_range outside -5 km ... 20 km geopotential.
double IsaPressure_pa(double altitude_m);
double IsaTemperature_K(double altitude_m);

/// Barometer: altitude_m = h + b + n (the truth height is taken as the height above mean
/// sea level: no geoid model), b a constant bias, n white noise; with `pressure`,
/// pressure_pa and temperature_degC are the ISA values at that (erroneous) altitude.
class BaroSimulator {
 public:
  BaroSimulator(const BaroSimConfig& config, const Rng& rng, bool perfect);
  std::optional<BaroSample> Push(const TruthSample& truth);
  void EmitDrawn(YAML::Emitter& out) const;
  double bias_m() const { return bias_m_; }

 private:
  BaroSimConfig config_;
  bool perfect_;
  double bias_m_ = 0.0;
  EpochSampler sampler_;
  Rng noise_rng_;
};

// --------------------------------------------------------------------------- odometer

/// `odometer:` (SI inside): a wheel odometer at the vehicle reference point lever_arm_b_m
/// (body axes; the simulated vehicle frame is the body frame).
struct OdometerSimConfig {
  double rate_hz = 10.0;
  double scale_factor_sigma = 0.0;  ///< 1-sigma of a per-run constant scale-factor error
  std::optional<double> scale_factor_fixed;
  double noise_mps = 0.0;           ///< white noise, 1-sigma
  Eigen::Vector3d lever_arm_b_m = Eigen::Vector3d::Zero();
};

/// YAML keys: rate_hz, scale_factor_ppm | scale_factor_fixed_ppm, noise_mps, lever_arm_b_m.
OdometerSimConfig ParseOdometerSimConfig(const ConfigNode& node);

/// Odometer: speed_mps = (1 + s) [R_n_b^T v_n + omega_ib_b x l_b]_x + n, the forward
/// speed of the reference point with a constant scale-factor error s and white noise n.
class OdometerSimulator {
 public:
  OdometerSimulator(const OdometerSimConfig& config, const Rng& rng, bool perfect);
  std::optional<OdometerSample> Push(const TruthSample& truth);
  void EmitDrawn(YAML::Emitter& out) const;
  double scale_factor() const { return scale_factor_; }

 private:
  OdometerSimConfig config_;
  bool perfect_;
  double scale_factor_ = 0.0;
  EpochSampler sampler_;
  Rng noise_rng_;
};

// ------------------------------------------------------------------------- master INS

/// `master:` (SI inside).
struct MasterSimConfig {
  double rate_hz = 50.0;
  double transfer_delay_s = 0.0;
  double attitude_error_sigma_rad = 0.0;  ///< per-axis 1-sigma of the constant error
  std::optional<Eigen::Vector3d> attitude_error_fixed_rad;
  double attitude_random_walk_rad_sqrt_s = 0.0;  ///< slow drift of the attitude error
  double velocity_noise_mps = 0.0;               ///< white noise per NED axis, 1-sigma
};

MasterSimConfig ParseMasterSimConfig(const ConfigNode& node);

/// Master INS for transfer alignment: the record TAGGED t carries the master's solution
/// for time t - transfer_delay_s (the slave receives late data; the delay is what transfer
/// alignment estimates). The solution is the truth (position exact) with
///   attitude R_master = Exp(-phi) R_true, i.e. R_true = Exp(phi) R_master (the project's
///   attitude-error convention), phi = phi0 + w(t): phi0 a constant drawn per axis,
///   w a random walk stepped at each epoch by N(0, q^2 / rate_hz);
///   velocity = v_n + white noise.
/// The first record is the first epoch whose data time is covered by the truth
/// (tag >= first truth time + delay).
class MasterSimulator {
 public:
  MasterSimulator(const MasterSimConfig& config, const Rng& rng, bool perfect);
  std::optional<NavState> Push(const TruthSample& truth);
  void EmitDrawn(YAML::Emitter& out) const;
  const Eigen::Vector3d& attitude_error_rad() const { return constant_error_rad_; }  ///< phi0

 private:
  MasterSimConfig config_;
  bool perfect_;
  Eigen::Vector3d constant_error_rad_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d random_walk_rad_ = Eigen::Vector3d::Zero();
  EpochSampler sampler_;
  Rng random_walk_rng_;
  Rng velocity_rng_;
};

}  // namespace navtwin::sim
