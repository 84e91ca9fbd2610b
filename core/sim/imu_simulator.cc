#include "core/sim/imu_simulator.h"

#include "core/rotation.h"

namespace navtwin::sim {

ImuSimConfig ParseImuSimConfig(const ConfigNode& node) {
  node.RequireKeys({"rate_hz", "mounting_deg", "lever_arm_b_m", "delay_s", "clock_offset_s",
                    "errors", "vibration", "anti_alias"});
  ImuSimConfig c;
  c.rate_hz = node.Double("rate_hz", c.rate_hz, 1.0, 10000.0);
  c.mounting_rpy_rad = node.Vector("mounting_deg", Eigen::Vector3d::Zero()) * kDegToRad;
  c.lever_arm_b_m = node.Vector("lever_arm_b_m", Eigen::Vector3d::Zero());
  c.delay_s = node.Double("delay_s", 0.0, 0.0, 10.0);
  c.clock_offset_s = node.Double("clock_offset_s", 0.0, -1e6, 1e6);
  c.errors = ParseInertialErrorConfig(node.Child("errors"));
  c.vibration = ParseVibrationConfig(node.Child("vibration"));
  c.anti_alias = ParseAntiAliasConfig(node.Child("anti_alias"), c.rate_hz);
  return c;
}

ImuSimulator::ImuSimulator(const ImuSimConfig& config, const Rng& rng, bool perfect)
    : config_(config),
      R_imu_b_(DcmFromEuler(config.mounting_rpy_rad.x(), config.mounting_rpy_rad.y(),
                            config.mounting_rpy_rad.z())
                   .transpose()),
      errors_(config.errors, rng.Stream("imu.errors"), perfect),
      vibration_(config.vibration, rng.Stream("imu.vibration"), perfect),
      gyro_quantizer_(errors_.gyro_quantum()),
      accel_quantizer_(errors_.accel_quantum()) {
  // Perfect mode is the ideal IMU: no anti-alias filter (its lag is an error of the
  // sensor), no delay or clock offset; mounting and lever arm (installation) stay.
  if (perfect) {
    config_.delay_s = 0.0;
    config_.clock_offset_s = 0.0;
  }
  if (config_.anti_alias.enabled && !perfect) {
    const double fs = internal_rate_hz();
    gyro_filter_ = std::make_unique<Butterworth4<Eigen::Vector3d>>(config_.anti_alias.cutoff_hz, fs);
    accel_filter_ = std::make_unique<Butterworth4<Eigen::Vector3d>>(config_.anti_alias.cutoff_hz, fs);
  }
}

std::optional<ImuSample> ImuSimulator::Push(const TruthSample& truth) {
  if (!started_) {
    started_ = true;
    previous_ = truth;
    // Start the filters in the steady state of the initial rates: no start-up transient.
    const Eigen::Vector3d w0 = R_imu_b_ * truth.omega_ib_b_radps;
    if (gyro_filter_) gyro_filter_->Reset(w0);
    if (accel_filter_) {
      const Eigen::Vector3d& w = truth.omega_ib_b_radps;
      const Eigen::Vector3d& l = config_.lever_arm_b_m;
      accel_filter_->Reset(R_imu_b_ * (truth.f_b_mps2 + truth.alpha_ib_b_rad_s2.cross(l) +
                                       w.cross(w.cross(l))));
    }
    return std::nullopt;
  }
  const double t0 = previous_.t_s, t1 = truth.t_s, h = t1 - t0;
  const Eigen::Vector3d& l = config_.lever_arm_b_m;
  // 1. Lever arm (body axes): the alpha x l term integrates exactly to d(omega) x l.
  const Eigen::Vector3d& w0 = previous_.omega_ib_b_radps;
  const Eigen::Vector3d& w1 = truth.omega_ib_b_radps;
  Eigen::Vector3d dv_b = truth.exact.dv_b_mps + (w1 - w0).cross(l) +
                         0.5 * h * (w0.cross(w0.cross(l)) + w1.cross(w1.cross(l)));
  Eigen::Vector3d dtheta = R_imu_b_ * truth.exact.dtheta_b_rad;
  Eigen::Vector3d dv = R_imu_b_ * dv_b;
  // 2. Vibration.
  Eigen::Vector3d vib_dtheta, vib_dv;
  vibration_.Increment(t0, t1, &vib_dtheta, &vib_dv);
  dtheta += vib_dtheta;
  dv += vib_dv;
  // 3. Sensor errors at the IMU temperature of the interval's midpoint.
  errors_.Apply(t1, h, config_.errors.temperature.At(0.5 * (t0 + t1)), dtheta, dv, &dtheta, &dv);
  // 4. Anti-alias filter on the rates.
  if (gyro_filter_) {
    dtheta = gyro_filter_->Filter(dtheta / h) * h;
    dv = accel_filter_->Filter(dv / h) * h;
  }
  previous_ = truth;
  // 5. Decimation.
  if (pending_ == 0) accumulated_ = ImuSample();
  accumulated_.dtheta_b_rad += dtheta;
  accumulated_.dv_b_mps += dv;
  accumulated_.dt_s += h;
  if (++pending_ < config_.anti_alias.oversample) return std::nullopt;
  pending_ = 0;
  // 6. Quantisation, 7. time tags.
  ImuSample out = accumulated_;
  out.dtheta_b_rad = gyro_quantizer_.Apply(out.dtheta_b_rad);
  out.dv_b_mps = accel_quantizer_.Apply(out.dv_b_mps);
  out.t_s = t1 + config_.delay_s + config_.clock_offset_s;
  return out;
}

void ImuSimulator::EmitDrawn(YAML::Emitter& out) const {
  out << YAML::BeginMap;
  out << YAML::Key << "rate_hz" << YAML::Value << config_.rate_hz;
  EmitVector(out, "mounting_deg", config_.mounting_rpy_rad, kDegToRad);
  EmitVector(out, "lever_arm_b_m", config_.lever_arm_b_m);
  out << YAML::Key << "delay_s" << YAML::Value << config_.delay_s;
  out << YAML::Key << "clock_offset_s" << YAML::Value << config_.clock_offset_s;
  out << YAML::Key << "oversample" << YAML::Value << config_.anti_alias.oversample;
  out << YAML::Key << "anti_alias_cutoff_hz" << YAML::Value
      << (config_.anti_alias.enabled ? config_.anti_alias.cutoff_hz : 0.0);
  out << YAML::Key << "errors" << YAML::Value;
  errors_.EmitDrawn(out);
  out << YAML::Key << "vibration" << YAML::Value;
  vibration_.EmitDrawn(out);
  out << YAML::EndMap;
}

}  // namespace navtwin::sim
