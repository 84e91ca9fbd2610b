#include "problems/leveling/monte_carlo.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "core/leveling_model.h"
#include "core/units.h"

namespace navtwin::leveling {
namespace leveling_monte_carlo_test {

constexpr double kG = kStandardGravity_mps2;

// Sample mean and standard deviation.
struct Moments {
  double mean = 0.0;
  double std = 0.0;
};
Moments MomentsOf(const std::vector<double>& x) {
  Moments m;
  for (const double v : x) m.mean += v;
  m.mean /= x.size();
  for (const double v : x) m.std += (v - m.mean) * (v - m.mean);
  m.std = std::sqrt(m.std / (x.size() - 1));
  return m;
}

// Expected plain-mean pitch RMS (deg) of the seed's experiment to first order in the
// error: a tone A sin(w t_k + phi) averaged over N samples keeps A Im(D e^{i phi}) with
// D = (1/N) sum_k e^{i w t_k}, so E[mean^2] = sigma_A^2 |D|^2 / 2 over phi and A, here also
// averaged over f ~ U[lo, hi] (1000 points); the white noise adds sigma^2 / N; pitch error
// = mean_x / g. (The atan2 nonlinearity changes the RMS by ~0.3 % at these amplitudes.)
double PlainMeanPitchRmsTheoryDeg(const MonteCarloConfig& c) {
  const int n = MonteCarloWindowSamples(c);
  double d2 = 0.0;
  const int grid = 1000;
  for (int i = 0; i < grid; ++i) {
    const double f = c.vib_freq_lo_hz + (c.vib_freq_hi_hz - c.vib_freq_lo_hz) * (i + 0.5) / grid;
    std::complex<double> d = 0.0;
    for (int k = 0; k < n; ++k) d += std::polar(1.0, 2.0 * kPi * f * k / c.rate_hz);
    d2 += std::norm(d / static_cast<double>(n)) / grid;
  }
  const double sigma_a = c.vib_amp_g * kG, sigma_n = c.noise_mg * 1e-3 * kG;
  return std::sqrt(sigma_a * sigma_a * d2 / 2.0 + sigma_n * sigma_n / n) / kG * kRadToDeg;
}

TEST(LevelingMonteCarloTest, WindowHasTheConfiguredSamplesAndTimes) {
  MonteCarloConfig c;
  const AccelWindow w = SimulateWindow(c, 0);
  ASSERT_EQ(w.size(), 120);  // round(0.2 s x 600 Hz), the seed's window
  ASSERT_EQ(w.t_s.size(), 120u);
  EXPECT_EQ(w.t_s[0], 0.0);
  EXPECT_DOUBLE_EQ(w.t_s[119], 119.0 / 600.0);
  EXPECT_EQ(w.rate_hz, 600.0);
  EXPECT_TRUE(w.omega_b_radps.empty());
  c.window_s = 0.1;
  c.rate_hz = 1000.0;
  EXPECT_EQ(SimulateWindow(c, 0).size(), 100);
}

TEST(LevelingMonteCarloTest, WindowIsRestPlusTheDrawnTonesPlusNoise) {
  MonteCarloConfig c;
  c.vib_axes = {{true, false, true}};
  c.vib_tones = 2;
  c.noise_mg = 0.0;
  c.true_roll_deg = 10.0;
  c.true_pitch_deg = -5.0;
  std::vector<SimulatedTone> tones;
  const AccelWindow w = SimulateWindow(c, 3, &tones);
  ASSERT_EQ(tones.size(), 4u);  // axes x and z, harmonics 1 and 2 each
  EXPECT_EQ(tones[0].axis, 0);
  EXPECT_EQ(tones[1].harmonic, 2);
  EXPECT_EQ(tones[2].axis, 2);
  EXPECT_DOUBLE_EQ(tones[1].frequency_hz, 2.0 * tones[0].frequency_hz);
  EXPECT_DOUBLE_EQ(tones[2].frequency_hz, tones[0].frequency_hz);  // one fundamental per run
  const Eigen::Vector3d rest = SpecificForceAtRest(10.0 * kDegToRad, -5.0 * kDegToRad, kG);
  for (int k = 0; k < w.size(); ++k) {
    Eigen::Vector3d f = rest;
    for (const SimulatedTone& t : tones) {
      f[t.axis] += t.amplitude_mps2 * std::sin(2.0 * kPi * t.frequency_hz * w.t_s[k] + t.phase_rad);
    }
    // Same formula, rounding only.
    EXPECT_NEAR((w.f_b_mps2[k] - f).norm(), 0.0, 1e-12) << "sample " << k;
  }
}

TEST(LevelingMonteCarloTest, NoiseHasTheConfiguredSigmaOnEveryAxis) {
  MonteCarloConfig c;
  c.vib_amp_g = 0.0;
  c.window_s = 10.0;  // 6000 samples per axis
  const AccelWindow w = SimulateWindow(c, 0);
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> x;
    for (const Eigen::Vector3d& f : w.f_b_mps2) x.push_back(f[axis]);
    const Moments m = MomentsOf(x);
    // 50 mg; the sample std of 6000 normal values has relative std 1/sqrt(2 x 6000) = 0.9 %:
    // 4 sigma = 3.6 %. The mean is the rest value, std 50 mg / sqrt(6000) = 0.65 mg: 3 mg.
    EXPECT_NEAR(m.std / (0.05 * kG), 1.0, 0.036) << "axis " << axis;
    EXPECT_NEAR(m.mean, axis == 2 ? -kG : 0.0, 3e-3 * kG) << "axis " << axis;
  }
}

TEST(LevelingMonteCarloTest, DrawsFollowTheSeedsDistributions) {
  MonteCarloConfig c;
  c.vib_axes = {{true, true, true}};
  c.vib_tones = 2;
  const int runs = 4000;
  std::vector<double> freq, phase, amp1, amp2;
  for (int run = 0; run < runs; ++run) {
    std::vector<SimulatedTone> tones;
    SimulateWindow(c, run, &tones);
    ASSERT_EQ(tones.size(), 6u);
    freq.push_back(tones[0].frequency_hz);
    for (const SimulatedTone& t : tones) {
      ASSERT_GE(t.phase_rad, 0.0);
      ASSERT_LT(t.phase_rad, 2.0 * kPi);
      phase.push_back(t.phase_rad);
      (t.harmonic == 1 ? amp1 : amp2).push_back(t.amplitude_mps2 / kG);
    }
  }
  for (const double f : freq) {
    ASSERT_GE(f, 22.0);
    ASSERT_LE(f, 24.0);
  }
  const Moments f = MomentsOf(freq), p = MomentsOf(phase), a1 = MomentsOf(amp1), a2 = MomentsOf(amp2);
  // U[22, 24]: mean 23, std 2/sqrt(12) = 0.577 Hz; standard error of the mean of 4000
  // draws 0.009 Hz (tolerance 0.04, > 4 sigma); of the std ~0.6 % (tolerance 3 %).
  EXPECT_NEAR(f.mean, 23.0, 0.04);
  EXPECT_NEAR(f.std, 2.0 / std::sqrt(12.0), 0.03 * 0.577);
  // U[0, 2 pi): mean pi, std 1.81; 24000 draws: standard error 0.012 (tolerance 0.05).
  EXPECT_NEAR(p.mean, kPi, 0.05);
  // Fundamental N(0, (1 g)^2), second harmonic N(0, (0.5 g)^2); 12000 draws each: the std
  // has relative standard error 1/sqrt(24000) = 0.65 % (tolerance 3 %), the mean 0.009 g
  // and 0.0046 g (tolerance 4 sigma).
  EXPECT_NEAR(a1.std, 1.0, 0.03);
  EXPECT_NEAR(a2.std, 0.5, 0.015);
  EXPECT_NEAR(a1.mean, 0.0, 0.037);
  EXPECT_NEAR(a2.mean, 0.0, 0.019);
}

TEST(LevelingMonteCarloTest, RunsAreReproducibleAndIndependent) {
  MonteCarloConfig c;
  std::vector<SimulatedTone> a, b, quiet;
  const AccelWindow w1 = SimulateWindow(c, 17, &a);
  const AccelWindow w2 = SimulateWindow(c, 17, &b);
  EXPECT_EQ(w1.f_b_mps2, w2.f_b_mps2);  // same seed and run: identical
  EXPECT_NE(SimulateWindow(c, 18).f_b_mps2, w1.f_b_mps2);
  c.noise_mg = 0.0;  // the noise has its own stream: the vibration draws do not change
  SimulateWindow(c, 17, &quiet);
  EXPECT_EQ(quiet[0].amplitude_mps2, a[0].amplitude_mps2);
  EXPECT_EQ(quiet[0].frequency_hz, a[0].frequency_hz);
  c.seed = 1;
  SimulateWindow(c, 17, &b);
  EXPECT_NE(b[0].amplitude_mps2, a[0].amplitude_mps2);
}

TEST(LevelingMonteCarloTest, PlainMeanOfTheSimulatorMatchesTheTheory) {
  // Many cheap plain means: the simulator reproduces the seed's 2.4957 deg and the theory.
  const MonteCarloConfig c;
  const int runs = 4000;
  LevelingOptions options;
  options.accel_noise_mps2 = 0.05 * kG;
  double sum2 = 0.0;
  for (int run = 0; run < runs; ++run) {
    const double e = PlainMean(SimulateWindow(c, run), options).pitch_rad * kRadToDeg;
    sum2 += e * e;
  }
  const double rms = std::sqrt(sum2 / runs), theory = PlainMeanPitchRmsTheoryDeg(c);
  EXPECT_NEAR(theory, 2.5, 0.1);  // the seed reports 2.4957 deg
  // e^2 = (normal amplitude)^2 x (sin^2 of a uniform phase) x ...: E[e^4] ~ 4.5 E[e^2]^2,
  // so the mean square of 4000 runs has relative std sqrt(3.5 / 4000) = 3 %, the RMS
  // 1.5 %; tolerance 6 % (4 sigma).
  EXPECT_NEAR(rms / theory, 1.0, 0.06);
}

TEST(LevelingMonteCarloTest, ConfigValidationNamesTheProblem) {
  EXPECT_EQ(ValidateMonteCarloConfig(MonteCarloConfig()), "");
  const auto problem = [](void (*edit)(MonteCarloConfig&)) {
    MonteCarloConfig c;
    edit(c);
    return ValidateMonteCarloConfig(c);
  };
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.runs = 0; }).find("runs"), std::string::npos);
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.rate_hz = 0.0; }).find("rate_hz"), std::string::npos);
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.window_s = 1.0 / 600.0; }).find("window_s"), std::string::npos);
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.vib_freq_lo_hz = 25.0; }).find("low <= high"), std::string::npos);
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.vib_freq_lo_hz = 0.0; }).find("positive"), std::string::npos);
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.vib_freq_hi_hz = 300.0; }).find("Nyquist"), std::string::npos);
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.vib_tones = 13; }).find("Nyquist"), std::string::npos);
  EXPECT_EQ(problem([](MonteCarloConfig& c) { c.vib_tones = 12; }), "");  // 12 x 24 = 288 < 300 Hz
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.vib_tones = 0; }).find("vib_tones"), std::string::npos);
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.noise_mg = -1.0; }).find("noise_mg"), std::string::npos);
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.vib_amp_g = -1.0; }).find("vib_amp_g"), std::string::npos);
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.true_pitch_deg = 90.0; }).find("pitch"), std::string::npos);
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.true_roll_deg = 181.0; }).find("roll"), std::string::npos);
  EXPECT_NE(problem([](MonteCarloConfig& c) { c.noise_mg = NAN; }).find("finite"), std::string::npos);
  MonteCarloConfig bad;
  bad.runs = 0;
  EXPECT_THROW(RunLevelingMonteCarlo(bad, LevelingOptions()), std::invalid_argument);
  EXPECT_THROW(SimulateWindow(bad, 0), std::invalid_argument);
}

TEST(LevelingMonteCarloTest, SmallExperimentReproducesTheSeedsOrdering) {
  MonteCarloConfig c;
  c.runs = 300;
  LevelingOptions options;
  options.batch_covariance = false;
  MonteCarloRunOptions run_options;
  run_options.keep_errors = true;
  const MonteCarloResult r = RunLevelingMonteCarlo(c, options, run_options);
  ASSERT_EQ(r.methods.size(), 4u);
  EXPECT_EQ(r.runs, 300);
  EXPECT_EQ(r.threads, 2);
  EXPECT_GT(r.run_time_s, 0.0);
  const char* names[] = {"plain_mean", "period_average", "filter", "batch"};
  for (int m = 0; m < 4; ++m) {
    const MethodStatistics& s = r.methods[m];
    EXPECT_EQ(s.method, names[m]);
    ASSERT_EQ(s.pitch_error_deg.size(), 300u);
    ASSERT_EQ(s.roll_error_deg.size(), 300u);
    double sum2 = 0.0, max = 0.0;
    for (const double e : s.pitch_error_deg) {
      sum2 += e * e;
      max = std::max(max, std::abs(e));
    }
    // The statistics are those of the kept errors (same order of summation).
    EXPECT_DOUBLE_EQ(s.pitch_rms_deg, std::sqrt(sum2 / 300));
    EXPECT_EQ(s.pitch_max_deg, max);
    EXPECT_GE(s.pitch_max_deg, s.pitch_rms_deg);
    EXPECT_GT(s.cpu_time_s, 0.0);
  }
  const MethodStatistics& plain = r.methods[0];
  const MethodStatistics& period = r.methods[1];
  // 300 runs: the RMS has relative std ~sqrt(3.5 / 300) / 2 = 5.4 % (see the theory test);
  // tolerance 22 % (4 sigma).
  EXPECT_NEAR(plain.pitch_rms_deg / PlainMeanPitchRmsTheoryDeg(c), 1.0, 0.22);
  // The seed: 0.92 deg against 2.50 deg; 300 runs cannot turn that around.
  EXPECT_LT(period.pitch_rms_deg, 0.6 * plain.pitch_rms_deg);
  // Vibration on x only: roll sees white noise alone, sigma/(g sqrt(N)) = 0.26 deg for the
  // plain mean; with 300 runs the RMS is within 16 % (4 sigma of 1/sqrt(600)).
  EXPECT_NEAR(plain.roll_rms_deg / (0.05 / std::sqrt(120.0) * kRadToDeg), 1.0, 0.16);
  // Every run's plain mean reports sigma = noise / (g sqrt(N)) = 0.26 deg through the
  // Jacobian at its own mean, which differs from level by a few degrees: within 2 %.
  EXPECT_NEAR(plain.pitch_sigma_mean_deg / (0.05 / std::sqrt(120.0) * kRadToDeg), 1.0, 0.02);
}

TEST(LevelingMonteCarloTest, ResultsDoNotDependOnTheThreadCount) {
  MonteCarloConfig c;
  c.runs = 60;
  LevelingOptions options;
  options.batch_covariance = false;
  MonteCarloRunOptions run_options;
  run_options.keep_errors = true;
  c.threads = 1;
  const MonteCarloResult one = RunLevelingMonteCarlo(c, options, run_options);
  c.threads = 2;
  const MonteCarloResult two = RunLevelingMonteCarlo(c, options, run_options);
  EXPECT_EQ(one.threads, 1);
  EXPECT_EQ(two.threads, 2);
  // Same draws, same reduction order: bit-identical (NaN, no sigma reported, on both).
  const auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
  for (int m = 0; m < 4; ++m) {
    const MethodStatistics& a = one.methods[m];
    const MethodStatistics& b = two.methods[m];
    EXPECT_EQ(a.pitch_error_deg, b.pitch_error_deg) << a.method;
    EXPECT_EQ(a.roll_error_deg, b.roll_error_deg) << a.method;
    EXPECT_EQ(a.pitch_rms_deg, b.pitch_rms_deg) << a.method;
    EXPECT_EQ(a.roll_max_deg, b.roll_max_deg) << a.method;
    EXPECT_TRUE(same(a.pitch_sigma_mean_deg, b.pitch_sigma_mean_deg)) << a.method;
    EXPECT_TRUE(same(a.pitch_error_over_sigma_rms, b.pitch_error_over_sigma_rms)) << a.method;
    EXPECT_EQ(a.fallbacks, b.fallbacks) << a.method;
  }
}

TEST(LevelingMonteCarloTest, ErrorsAreTakenAgainstATiltedTruthWithRollWrapped) {
  // Upside down (roll 180 deg): the estimates scatter around +-180 deg and a roll error
  // taken without wrapping would be ~360 deg for about half of the runs.
  MonteCarloConfig c;
  c.runs = 40;
  c.vib_amp_g = 0.0;
  c.noise_mg = 5.0;
  c.true_roll_deg = 180.0;
  c.true_pitch_deg = 30.0;
  LevelingOptions options;
  options.batch_covariance = false;
  const MonteCarloResult r = RunLevelingMonteCarlo(c, options);
  // plain_mean: 5 mg over 120 samples, 1 sigma 0.026 deg (roll: / cos(pitch) = 0.030);
  // the largest of 40 runs stays below 0.2 deg (> 6 sigma).
  EXPECT_LT(r.methods[0].roll_max_deg, 0.2);
  EXPECT_LT(r.methods[0].pitch_max_deg, 0.2);
  EXPECT_GT(r.methods[0].roll_max_deg, 0.0);
}

}  // namespace leveling_monte_carlo_test
}  // namespace navtwin::leveling
