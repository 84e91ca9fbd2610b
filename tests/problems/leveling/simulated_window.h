// Simulated accelerometer windows with known truth for the leveling tests: a resting
// triad at a given roll and pitch, vibration tones, a bias and white noise, 600 Hz,
// 120 samples (the seed's 0.2 s). The seed's random draws per run are the library's
// leveling::SimulateWindow (problems/leveling/monte_carlo.h); this one places exactly the
// tones a test asks for.
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "core/leveling_model.h"
#include "core/sim/random.h"
#include "core/units.h"
#include "problems/leveling/leveling.h"

namespace navtwin::leveling::test_windows {

constexpr double kG = kStandardGravity_mps2;
constexpr double kNoise = 0.05 * kG;  // 50 mg
constexpr int kSamples = 120;
constexpr double kRate = 600.0;

// amplitude sin(2 pi harmonic f (t - t_centre) + phase): the phase at the window centre,
// the batch's time reference.
struct Tone {
  int axis;
  int harmonic;
  double amplitude_mps2;
  double phase_rad;
};

struct Truth {
  double roll_rad = 0.0;
  double pitch_rad = 0.0;
  double f_hz = 23.3;
  std::vector<Tone> tones;
  Eigen::Vector3d bias_mps2 = Eigen::Vector3d::Zero();
  double noise_mps2 = kNoise;
  double t0_s = 0.0;
};

inline AccelWindow Simulate(const Truth& truth, sim::Rng& rng) {
  AccelWindow w;
  w.rate_hz = kRate;
  w.source = "simulation";
  const double t_centre = truth.t0_s + 0.5 * (kSamples - 1) / kRate;
  const Eigen::Vector3d at_rest = SpecificForceAtRest(truth.roll_rad, truth.pitch_rad, kG) + truth.bias_mps2;
  for (int k = 0; k < kSamples; ++k) {
    const double t = truth.t0_s + k / kRate;
    Eigen::Vector3d f = at_rest + rng.Normal3(truth.noise_mps2);
    for (const Tone& tone : truth.tones) {
      f[tone.axis] += tone.amplitude_mps2 * std::sin(2.0 * kPi * tone.harmonic * truth.f_hz * (t - t_centre) + tone.phase_rad);
    }
    w.t_s.push_back(t);
    w.f_b_mps2.push_back(f);
  }
  return w;
}

}  // namespace navtwin::leveling::test_windows
