// The simulated IMU: from the truth stream at the internal rate (rate_hz x oversample) to
// the IMU's output increments, in this order (docs/scenarios.md):
//   1. exact increments of the body reference point, moved to the IMU's lever arm
//      (+ (omega1 - omega0) x l + trapezoid of omega x (omega x l)) and rotated into the
//      IMU axes (mounting);
//   2. + vibration (exact integrals of the drawn tones, core/sim/vibration.h);
//   3. sensor errors (core/sim/inertial_errors.h) at the IMU temperature;
//   4. anti-alias filter on the rate (core/sim/butterworth.h), when enabled;
//   5. decimation: the sum of `oversample` internal increments;
//   6. quantisation of the output increments (residual carried);
//   7. time tags: truth time + delay_s + clock_offset_s.
#pragma once

#include <memory>
#include <optional>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include "core/sim/butterworth.h"
#include "core/sim/inertial_errors.h"
#include "core/sim/random.h"
#include "core/sim/truth.h"
#include "core/sim/vibration.h"
#include "core/config/yaml_config.h"

namespace navtwin::sim {

/// The scenario's `imu:` section.
struct ImuSimConfig {
  double rate_hz = 200.0;
  Eigen::Vector3d mounting_rpy_rad = Eigen::Vector3d::Zero();  ///< IMU axes relative to body FRD
  Eigen::Vector3d lever_arm_b_m = Eigen::Vector3d::Zero();     ///< IMU from the body reference point
  double delay_s = 0.0;         ///< sensor latency: data describe the time tag minus this
  double clock_offset_s = 0.0;  ///< sensor clock minus true time
  InertialErrorConfig errors;
  VibrationConfig vibration;
  AntiAliasConfig anti_alias;
};

/// Keys: rate_hz, mounting_deg [roll, pitch, yaw], lever_arm_b_m, delay_s, clock_offset_s,
/// errors, vibration, anti_alias.
ImuSimConfig ParseImuSimConfig(const ConfigNode& node);

class ImuSimulator {
 public:
  /// Draws from rng's streams "imu.errors", "imu.vibration". `perfect`: the ideal IMU —
  /// no sensor error, vibration, anti-alias filter, delay or clock offset; the mounting
  /// and the lever arm (the installation) stay.
  ImuSimulator(const ImuSimConfig& config, const Rng& rng, bool perfect);

  /// Rate at which Push() must be fed (rate_hz x oversample).
  double internal_rate_hz() const { return config_.rate_hz * config_.anti_alias.oversample; }

  /// One internal truth sample (the first, with no increment, only starts the stream);
  /// returns an output sample every `oversample` pushes.
  std::optional<ImuSample> Push(const TruthSample& truth);

  /// Mounting, lever arm, delays and every drawn error and vibration value.
  void EmitDrawn(YAML::Emitter& out) const;

 private:
  ImuSimConfig config_;
  Eigen::Matrix3d R_imu_b_;
  InertialErrorModel errors_;
  VibrationModel vibration_;
  std::unique_ptr<Butterworth4<Eigen::Vector3d>> gyro_filter_, accel_filter_;
  Quantizer gyro_quantizer_, accel_quantizer_;
  bool started_ = false;
  TruthSample previous_;
  int pending_ = 0;
  ImuSample accumulated_;
};

}  // namespace navtwin::sim
