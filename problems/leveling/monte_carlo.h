// The Monte Carlo experiment of seed 000 (spec "Published experiment"): many short
// windows of a level, resting accelerometer triad disturbed by rotor vibration and white
// noise, each levelled by all four methods (plain_mean, period_average, filter, batch);
// per method the RMS and largest roll and pitch errors. `navtwin level-mc` runs it;
// docs/leveling-results.md gives the figures.
//
// One run: the fundamental f ~ U[lo, hi]; on every vibrating axis and for every harmonic
// h = 1..tones an amplitude A ~ N(0, (vib_amp_g g / h)^2) (harmonic gain 1/h, the
// simulator's default harmonic_gains in core/sim/vibration.h) and a phase phi ~ U[0, 2 pi);
//   f_k = SpecificForceAtRest(roll, pitch, g) + sum A sin(2 pi h f t_k + phi) + n_k,
//   t_k = k / rate_hz, k = 0..N-1, N = round(window_s rate_hz), n_k ~ N(0, noise^2 I).
// Each run draws from its own streams of sim::Rng(seed), so the results do not depend on
// the number of threads.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "problems/leveling/leveling.h"
#include "solvers/mc_record.h"
#include "solvers/monte_carlo.h"

namespace navtwin::leveling {

/// The experiment; the defaults are the seed's (spec "Published experiment").
struct MonteCarloConfig {
  int runs = 10000;
  double rate_hz = 600.0;
  double window_s = 0.2;
  std::array<bool, 3> vib_axes{{true, false, false}};  ///< body x, y, z (FRD)
  double vib_freq_lo_hz = 22.0;                        ///< fundamental ~ U[lo, hi]
  double vib_freq_hi_hz = 24.0;
  double vib_amp_g = 1.0;   ///< 1 sigma of the fundamental's amplitude (g)
  int vib_tones = 1;        ///< harmonics h = 1..vib_tones, amplitude 1 sigma vib_amp_g / h
  double noise_mg = 50.0;   ///< white accelerometer noise, 1 sigma per axis (mg)
  double true_roll_deg = 0.0;
  double true_pitch_deg = 0.0;
  std::uint64_t seed = 0;
  int threads = 2;          ///< <= 0: hardware concurrency
};

/// Why `config` cannot run (one message naming the field), or empty when it can: runs >= 1,
/// rate > 0, at least 2 samples per window, 0 < lo <= hi, every harmonic tones x hi below
/// Nyquist (rate / 2), amplitude >= 0, tones >= 1, noise >= 0, |roll| <= 180 deg,
/// |pitch| < 90 deg, all values finite.
std::string ValidateMonteCarloConfig(const MonteCarloConfig& config);

/// Samples per window: round(window_s rate_hz).
int MonteCarloWindowSamples(const MonteCarloConfig& config);

/// One drawn sinusoid of a run: amplitude_mps2 sin(2 pi frequency_hz t + phase_rad).
struct SimulatedTone {
  int axis = 0;      ///< 0, 1, 2 = body x, y, z
  int harmonic = 1;  ///< frequency = harmonic x the run's fundamental
  double frequency_hz = 0.0;
  double amplitude_mps2 = 0.0;  ///< signed normal draw
  double phase_rad = 0.0;
};

/// The window of run `run` (source "simulation"); `tones`, if given, receives the drawn
/// vibration (vibrating axes in x, y, z order, harmonics 1..tones within each axis).
/// Throws std::invalid_argument for an invalid config.
AccelWindow SimulateWindow(const MonteCarloConfig& config, int run, std::vector<SimulatedTone>* tones = nullptr);

/// One method over all runs. Errors are estimate - truth (roll wrapped to (-180, 180]).
struct MethodStatistics {
  std::string method;  ///< "plain_mean", "period_average", "filter", "batch"
  double roll_rms_deg = 0.0;
  double roll_max_deg = 0.0;    ///< largest |error|
  double pitch_rms_deg = 0.0;
  double pitch_max_deg = 0.0;
  /// Mean reported 1 sigma over the runs that report one (a positive sigma; the batch
  /// without batch_covariance reports none); NaN when no run does.
  double roll_sigma_mean_deg = 0.0;
  double pitch_sigma_mean_deg = 0.0;
  /// RMS of pitch error / reported sigma over the same runs: 1 for a consistent sigma,
  /// above 1 when the method is over-confident (NaN: no run reports a sigma).
  double pitch_error_over_sigma_rms = 0.0;
  int fallbacks = 0;            ///< runs whose estimate reports a fallback
  std::string first_fallback;   ///< the first such run's message (in run order)
  double cpu_time_s = 0.0;      ///< summed over runs and threads
  std::vector<double> roll_error_deg;   ///< per run; only with keep_errors
  std::vector<double> pitch_error_deg;
};

struct MonteCarloResult {
  int runs = 0;
  int threads = 0;          ///< workers used
  double run_time_s = 0.0;  ///< wall time of all runs
  std::vector<MethodStatistics> methods;  ///< plain_mean, period_average, filter, batch
};

struct MonteCarloRunOptions {
  bool keep_errors = false;  ///< fill MethodStatistics::*_error_deg
  MonteCarloProgress progress;
};

/// Runs the experiment. Each method gets `options` with accel_noise_mps2 = the configured
/// noise, vib_axes and vib_tones = the configured vibration (the rest as given, e.g.
/// batch_covariance). Throws std::invalid_argument for an invalid config; an exception
/// of a method stops the runs and passes through.
MonteCarloResult RunLevelingMonteCarlo(const MonteCarloConfig& config, const LevelingOptions& options,
                                       const MonteCarloRunOptions& run_options = {});

/// Run `run` of `navtwin mc --problem leveling` (docs/monte-carlo.md): the window of
/// SimulateWindow(config, run) levelled by every method (options as RunLevelingMonteCarlo
/// gives them); per method the quantity "level" (roll, pitch; error estimate - truth, deg,
/// with the reported sigma where the method gives one) at one point (axis "final").
mc::RunRecord LevelingMcRun(const MonteCarloConfig& config, const LevelingOptions& options, int run);

}  // namespace navtwin::leveling
