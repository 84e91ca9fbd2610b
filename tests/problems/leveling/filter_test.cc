#include "problems/leveling/filter.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "core/sim/random.h"
#include "core/leveling_model.h"
#include "core/units.h"
#include "problems/leveling/monte_carlo.h"
#include "tests/problems/leveling/simulated_window.h"

namespace navtwin::leveling {
namespace leveling_filter_test {

constexpr double kG = kStandardGravity_mps2;
constexpr double kRate_hz = 600.0;
constexpr int kSamples = 120;  // 0.2 s at 600 Hz: the seed's window

// One window with a body-x tone amplitude_mps2 sin(2 pi f (t - t_centre) + phase) plus
// white noise on every axis.
AccelWindow OneTone(double roll_rad, double pitch_rad, double freq_hz, double amplitude_mps2, double phase_rad,
                    double noise_mps2, sim::Rng* rng) {
  test_windows::Truth truth;
  truth.roll_rad = roll_rad;
  truth.pitch_rad = pitch_rad;
  truth.f_hz = freq_hz;
  truth.tones = {{0, 1, amplitude_mps2, phase_rad}};
  truth.noise_mps2 = noise_mps2;
  return test_windows::Simulate(truth, *rng);
}

TEST(LevelingFilterTest, NoiseFreeSinusoidLevelsWithinTwoHundredthsOfADegree) {
  const double roll = 6.0 * kDegToRad, pitch = -11.0 * kDegToRad;
  sim::Rng rng(1);  // unused: no noise
  LevelingOptions options;
  options.accel_noise_mps2 = 0.01;  // the noise the filter assumes (estimated, it would be ~0)
  for (const double freq_hz : {22.0, 22.6, 23.3, 24.0}) {
    for (const double phase : {0.4, 2.9, 5.1}) {
      const AccelWindow w = OneTone(roll, pitch, freq_hz, kG, phase, 0.0, &rng);
      const LevelEstimate e = RunFilter(w, options);
      ASSERT_TRUE(e.fallback.empty()) << e.fallback;
      EXPECT_EQ(e.method, "filter");
      // What is left: the period error (~1e-3 samples, the linear interpolation in the
      // difference cost) times A / P, and the error of the linearly interpolated averages at
      // the fractional block ends (~A w^2 / 12 per cell, over P): each ~1e-4 rad = 0.006 deg
      // at 1 g; the measured worst over these cases and 0.3-2.5 g is 0.004 deg.
      EXPECT_NEAR(e.roll_rad * kRadToDeg, roll * kRadToDeg, 0.02) << freq_hz << " Hz, phase " << phase;
      EXPECT_NEAR(e.pitch_rad * kRadToDeg, pitch * kRadToDeg, 0.02) << freq_hz << " Hz, phase " << phase;
      EXPECT_NEAR(e.period_samples, kRate_hz / freq_hz, 0.01);  // measured worst 1.1e-3
      EXPECT_NEAR(e.vib_freq_hz, freq_hz, 0.01);
    }
  }
}

TEST(LevelingFilterTest, StrongSecondHarmonicStillAveragesWholePeriods) {
  // Fundamental 0.2 g under a 1 g second harmonic: the autocorrelation peaks every half
  // period (13 samples), but only whole periods (26.09) cancel the fundamental.
  const double roll = -4.0 * kDegToRad, pitch = 7.0 * kDegToRad, freq_hz = 23.0;
  AccelWindow w;
  w.rate_hz = kRate_hz;
  w.source = "simulation";
  for (int k = 0; k < kSamples; ++k) {
    const double phase = 2.0 * kPi * freq_hz * k / kRate_hz;
    Eigen::Vector3d f = SpecificForceAtRest(roll, pitch, kG);
    f.x() += 0.2 * kG * std::sin(phase + 0.3) + kG * std::sin(2.0 * phase + 1.2);
    w.f_b_mps2.push_back(f);
  }
  LevelingOptions options;
  options.accel_noise_mps2 = 0.01;
  const LevelEstimate e = RunFilter(w, options);
  ASSERT_TRUE(e.fallback.empty()) << e.fallback;
  EXPECT_NEAR(e.period_samples, kRate_hz / freq_hz, 0.01);
  // As the noise-free one-tone case. Half periods would leave up to 0.2 g x 2/pi / 9 blocks,
  // ~0.8 deg (0.65 deg here).
  EXPECT_NEAR(e.roll_rad * kRadToDeg, roll * kRadToDeg, 0.02);
  EXPECT_NEAR(e.pitch_rad * kRadToDeg, pitch * kRadToDeg, 0.02);
}

struct MonteCarloResult {
  double pitch_rms_deg = 0.0, pitch_sigma_deg = 0.0;  // RMS error, mean 1-sigma
  double roll_rms_deg = 0.0, roll_sigma_deg = 0.0;
  int fallbacks = 0;
};

MonteCarloResult RunSeedExperiment(int runs, double roll, double pitch, const LevelingOptions& options,
                                   std::uint64_t seed) {
  MonteCarloConfig config;  // the seed's draws (problems/leveling/monte_carlo.h)
  config.true_roll_deg = roll * kRadToDeg;
  config.true_pitch_deg = pitch * kRadToDeg;
  config.seed = seed;
  MonteCarloResult m;
  for (int i = 0; i < runs; ++i) {
    const LevelEstimate e = RunFilter(SimulateWindow(config, i), options);
    m.pitch_rms_deg += std::pow((e.pitch_rad - pitch) * kRadToDeg, 2) / runs;
    m.roll_rms_deg += std::pow((e.roll_rad - roll) * kRadToDeg, 2) / runs;
    m.pitch_sigma_deg += e.pitch_sigma_rad * kRadToDeg / runs;
    m.roll_sigma_deg += e.roll_sigma_rad * kRadToDeg / runs;
    m.fallbacks += e.fallback.empty() ? 0 : 1;
  }
  m.pitch_rms_deg = std::sqrt(m.pitch_rms_deg);
  m.roll_rms_deg = std::sqrt(m.roll_rms_deg);
  return m;
}

// Bounds shared by the Monte Carlo tests (500 runs of the seed's experiment each).
void ExpectSeedExperimentBounds(const MonteCarloResult& m) {
  // The seed's method reaches 0.92 deg, the white-noise floor over the ~106 samples the
  // blocks use is 0.28 deg; 10,000 runs give 0.30 deg; 500 runs scatter it by ~5 %.
  EXPECT_LT(m.pitch_rms_deg, 0.6);
  // Honest sigma: the filter's sigma is the white noise over the samples used; the vibration
  // the period error leaves adds a little (10,000 runs: RMS / mean sigma = 1.05-1.07).
  EXPECT_GT(m.pitch_rms_deg / m.pitch_sigma_deg, 0.85);
  EXPECT_LT(m.pitch_rms_deg / m.pitch_sigma_deg, 1.3);
  // No vibration on y and z: roll sees white noise only.
  EXPECT_GT(m.roll_rms_deg / m.roll_sigma_deg, 0.85);
  EXPECT_LT(m.roll_rms_deg / m.roll_sigma_deg, 1.2);
  // |A| < ~0.1 g leaves no period: the plain mean (10,000 runs: 8.6 %).
  EXPECT_LT(m.fallbacks, 500 / 5);
}

TEST(LevelingFilterTest, SeedExperimentLevelTruthKnownNoise) {
  LevelingOptions options;
  options.accel_noise_mps2 = 0.05 * kG;
  const MonteCarloResult m = RunSeedExperiment(500, 0.0, 0.0, options, 2021);
  ExpectSeedExperimentBounds(m);
}

TEST(LevelingFilterTest, SeedExperimentTiltedTruthEstimatedNoise) {
  const MonteCarloResult m = RunSeedExperiment(500, 10.0 * kDegToRad, -20.0 * kDegToRad, LevelingOptions{}, 77);
  ExpectSeedExperimentBounds(m);
}

TEST(LevelingFilterTest, CovarianceShrinksAsBlocksArrive) {
  sim::Rng rng(12);
  const double sigma = 0.05 * kG;
  const AccelWindow w = OneTone(0.02, -0.03, 23.0, kG, 1.0, sigma, &rng);
  LevelingOptions options;
  options.accel_noise_mps2 = sigma;
  OnlineLeveler filter(options, kRate_hz, kSamples / 2);
  Eigen::Matrix2d previous = Eigen::Matrix2d::Zero();
  int updates = 0, first_update_samples = 0, samples = 0;
  for (const Eigen::Vector3d& f : w.f_b_mps2) {
    ++samples;
    if (!filter.Add(f)) continue;
    if (updates == 0) first_update_samples = samples;
    const Eigen::Matrix2d p = filter.covariance();
    if (updates > 0) {
      EXPECT_LT(p(0, 0), previous(0, 0));
      EXPECT_LT(p(1, 1), previous(1, 1));
    } else {
      EXPECT_FALSE(filter.Converged(1e-3));  // the first two blocks, 52 samples: ~0.4 deg
    }
    previous = p;
    ++updates;
  }
  ASSERT_TRUE(filter.initialized());
  // A period is taken once the samples hold 2.5 of it (26.09 samples: from sample 66), and
  // with a clean 1 g vibration at once; the blocks up to there are then averaged together.
  EXPECT_GE(first_update_samples, 66);
  EXPECT_LE(first_update_samples, 68);
  EXPECT_EQ(updates, 3);  // samples 66 (two blocks), 80 and 106
  const LevelEstimate e = filter.Estimate();
  // samples_used - 1 = floor(blocks x period), the index where the last block ends.
  const int blocks = static_cast<int>(std::lround((e.samples_used - 1) / e.period_samples));
  EXPECT_EQ(blocks, 4);  // 4 x 26.09 samples fit in 120
  // With R = sigma^2 / P per block, the pitch variance is sigma^2 / (g^2 P blocks); the block
  // means differ from g in length by the noise (~0.1 %), linearisation points by ~1 deg.
  const double expected = sigma / (kG * std::sqrt(e.period_samples * blocks));
  EXPECT_NEAR(e.pitch_sigma_rad / expected, 1.0, 0.01);
  EXPECT_TRUE(filter.Converged(1.1 * expected));
  EXPECT_FALSE(filter.Converged(0.9 * expected));
}

TEST(LevelingFilterTest, WithoutAPeriodItReportsThePlainMean) {
  sim::Rng rng(8);
  AccelWindow w;
  w.source = "simulation";
  for (int k = 0; k < kSamples; ++k) {
    w.f_b_mps2.push_back(SpecificForceAtRest(0.01, 0.02, kG) + rng.Normal3(0.5));
    w.t_s.push_back(k / kRate_hz);
  }
  OnlineLeveler filter(LevelingOptions{}, kRate_hz, kSamples / 2);
  for (const Eigen::Vector3d& f : w.f_b_mps2) EXPECT_FALSE(filter.Add(f));
  EXPECT_FALSE(filter.initialized());
  EXPECT_FALSE(filter.Converged(1.0));
  const LevelEstimate e = filter.Estimate();
  EXPECT_EQ(e.method, "filter");
  EXPECT_EQ(e.fallback, "no vibration period found yet: plain mean of 120 samples");
  EXPECT_EQ(e.period_samples, 0.0);
  EXPECT_EQ(e.samples_used, kSamples);
  // The same mean and spread-based sigma as the plain-mean method (sums in another order).
  const LevelEstimate plain = PlainMean(w, LevelingOptions{});
  EXPECT_NEAR(e.roll_rad, plain.roll_rad, 1e-12);
  EXPECT_NEAR(e.pitch_rad, plain.pitch_rad, 1e-12);
  EXPECT_NEAR(e.roll_sigma_rad, plain.roll_sigma_rad, 1e-12);
  EXPECT_NEAR(e.pitch_sigma_rad, plain.pitch_sigma_rad, 1e-12);
  EXPECT_NEAR(filter.covariance()(1, 1), e.pitch_sigma_rad * e.pitch_sigma_rad, 1e-15);
  EXPECT_EQ(RunFilter(w, LevelingOptions{}).fallback, e.fallback);
}

TEST(LevelingFilterTest, NoSamplesIsAClearError) {
  OnlineLeveler filter(LevelingOptions{}, kRate_hz, 60);
  EXPECT_THROW(filter.Estimate(), std::logic_error);
  AccelWindow w;
  w.source = "x.csv";
  w.f_b_mps2.push_back(Eigen::Vector3d(0.0, 0.0, -kG));
  w.t_s.push_back(0.0);
  try {
    RunFilter(w, LevelingOptions{});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("x.csv"), std::string::npos) << e.what();
  }
}

}  // namespace leveling_filter_test
}  // namespace navtwin::leveling
