// Vibration of the IMU as a sum of sinusoidal tones on chosen body axes, added to the
// sensed specific force (linear vibration) and angular rate (angular vibration). The truth
// trajectory is the vibration-free mean motion the navigator has to estimate; vibration
// only disturbs the measured increments. docs/vibration-and-aliasing.md describes the model.
//
// Each tone is  a(t) = A sin(2 pi f t + phi)  and the model returns its exact integral over
// a sample interval, so that sampling at a high internal rate, filtering and decimating
// shows aliasing as a real integrating IMU would.
//
// YAML (imu.vibration), a list of tone groups:
//   vibration:
//     tones:
//       - axes: [x]               # any of x, y, z (each axis gets its own amplitude and phase)
//         frequency_hz: [22, 24]  # fundamental f, drawn uniformly in [lo, hi] (lo > 0)
//         linear_g: 1.0           # specific-force amplitude (g); 0 or absent: none
//         angular_deg_s: 0.0      # angular-rate amplitude (deg/s); 0 or absent: none
//         amplitude: normal       # normal: each amplitude ~ N(0, value^2) (seed 000);
//                                 # fixed: the amplitude is the value itself
//         harmonics: 3            # tones at k f for k = 1..harmonics (default 1)
//         harmonic_gains: [1, 0.5, 0.333]  # amplitude of harmonic k relative to the
//                                          # fundamental (default 1/k)
// Phases are drawn uniformly in [0, 2 pi) for every axis, kind and harmonic.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include "core/sim/random.h"
#include "core/config/yaml_config.h"
#include "core/units.h"

namespace navtwin::sim {

/// One tone group: a fundamental frequency shared by its axes and harmonics.
struct VibrationToneConfig {
  std::array<bool, 3> axes{{false, false, false}};  ///< body x, y, z (FRD)
  Eigen::Vector2d frequency_hz{0.0, 0.0};           ///< range of the fundamental
  double linear_mps2 = 0.0;                         ///< specific-force amplitude (key linear_g)
  double angular_radps = 0.0;                       ///< angular-rate amplitude (key angular_deg_s)
  bool random_amplitude = true;  ///< amplitudes are 1-sigma of a zero-mean normal draw
  std::vector<double> harmonic_gains{1.0};  ///< relative amplitude of harmonic k = 1..n
};

/// imu.vibration; no tones (the default) means no vibration.
struct VibrationConfig {
  std::vector<VibrationToneConfig> tones;
};

/// Parses imu.vibration (schema above). Throws InputError naming the file, line and key.
VibrationConfig ParseVibrationConfig(const ConfigNode& node);

/// One drawn sinusoid a(t) = amplitude * sin(2 pi frequency_hz t + phase_rad).
struct VibrationTone {
  int group = 0;           ///< index in VibrationConfig::tones
  int harmonic = 1;        ///< k: frequency_hz = k x the drawn fundamental
  int axis = 0;            ///< 0, 1, 2 = body x, y, z
  bool angular = false;    ///< angular rate (rad/s) if true, specific force (m/s^2) if false
  double frequency_hz = 0.0;
  double amplitude = 0.0;  ///< rad/s or m/s^2; signed (a normal draw keeps its sign)
  double phase_rad = 0.0;
};

class VibrationModel {
 public:
  /// No vibration.
  VibrationModel() = default;
  /// Draws the tones of `config` from rng's named streams "vibration.tones[i].<quantity>"
  /// (frequency, linear, angular, linear.phase, angular.phase), so that changing one group
  /// or kind leaves the other draws unchanged. `perfect` gives no vibration.
  VibrationModel(const VibrationConfig& config, const Rng& rng, bool perfect);

  /// The exact integrals over (t0_s, t1_s] of the vibration's angular rate (rad) and
  /// specific force (m/s), in body axes. Both outputs are overwritten.
  void Increment(double t0_s, double t1_s, Eigen::Vector3d* dtheta_rad,
                 Eigen::Vector3d* dv_mps) const;
  /// The vibration's angular rate (rad/s) and specific force (m/s^2) at t_s.
  void Rate(double t_s, Eigen::Vector3d* omega_radps, Eigen::Vector3d* f_mps2) const;

  /// The drawn tones as a YAML map {tones: [{group, harmonic, axis, kind, frequency_hz,
  /// amplitude_g | amplitude_deg_s, phase_rad}, ...]}.
  void EmitDrawn(YAML::Emitter& out) const;

  const std::vector<VibrationTone>& tones() const { return tones_; }

 private:
  std::vector<VibrationTone> tones_;
};

}  // namespace navtwin::sim
