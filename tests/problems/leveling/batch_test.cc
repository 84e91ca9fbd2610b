// Batch leveling (problems/leveling/batch.h) on simulated windows like the seed's
// experiment (600 Hz, 120 samples = 0.2 s, body-x vibration of about 1 g near 23 Hz,
// 50 mg white noise): accuracy against the white-noise floor sigma / (g sqrt(N)), honest
// sigmas over many runs, harmonics on all axes, exact recovery without noise, and the
// fallbacks and options.
#include "problems/leveling/batch.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "core/sim/random.h"
#include "core/leveling_model.h"
#include "tests/problems/leveling/simulated_window.h"

namespace navtwin::leveling {
namespace leveling_batch_test {
using namespace test_windows;

// The seed's vibration: body x, 1 g, random phase.
Truth SeedTruth(sim::Rng& rng, double roll_deg = 0.0, double pitch_deg = 0.0) {
  Truth truth;
  truth.roll_rad = roll_deg * kDegToRad;
  truth.pitch_rad = pitch_deg * kDegToRad;
  truth.tones = {{0, 1, kG, rng.Uniform(0.0, 2.0 * kPi)}};
  return truth;
}

// The white-noise floor of the pitch (and of the roll at pitch 0): sigma / (g sqrt(N)).
double Floor(double noise_mps2 = kNoise) { return noise_mps2 / (kG * std::sqrt(kSamples)); }


TEST(LevelingBatchTest, TiltedWindowWithinItsSigmaNearTheNoiseFloor) {
  sim::Rng rng(101);
  const Truth truth = SeedTruth(rng, 3.0, -5.0);
  const AccelWindow window = Simulate(truth, rng);
  // Sigma against the floor: with the noise known it cannot be below it (nuisance
  // parameters only add variance) and the tone's terms are nearly orthogonal to the mean
  // over 4.7 periods (measured 1.004); an estimated noise adds its own spread
  // (1 / sqrt(2 dof) ~ 4 %; measured 1.06).
  struct Case {
    double noise_option;  // 0: estimated
    double min_ratio, max_ratio;
  };
  for (const Case c : {Case{kNoise, 0.999, 1.1}, Case{0.0, 0.85, 1.2}}) {
    SCOPED_TRACE(c.noise_option > 0.0 ? "noise known" : "noise estimated");
    LevelingOptions options;
    options.accel_noise_mps2 = c.noise_option;
    const BatchLevelingResult r = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options));
    const LevelEstimate& e = r.estimate;
    EXPECT_EQ(e.method, "batch");
    EXPECT_EQ(e.fallback, "");
    EXPECT_EQ(e.samples_used, kSamples);
    EXPECT_TRUE(r.converged);
    EXPECT_EQ(r.covariance_note, "");
    // 4 sigma: a Gaussian error beyond it has probability 6e-5 (fixed seed).
    EXPECT_NEAR(e.roll_rad, truth.roll_rad, 4.0 * e.roll_sigma_rad);
    EXPECT_NEAR(e.pitch_rad, truth.pitch_rad, 4.0 * e.pitch_sigma_rad);
    const double pitch_floor = Floor();
    const double roll_floor = Floor() / std::cos(truth.pitch_rad);  // roll moves f by g cos(pitch)
    EXPECT_GT(e.pitch_sigma_rad, c.min_ratio * pitch_floor);
    EXPECT_LT(e.pitch_sigma_rad, c.max_ratio * pitch_floor);
    EXPECT_GT(e.roll_sigma_rad, c.min_ratio * roll_floor);
    EXPECT_LT(e.roll_sigma_rad, c.max_ratio * roll_floor);
    // The tone: 1 g within 5 amplitude sigmas (sigma sqrt(2 / N) = 0.063 m/s^2).
    ASSERT_EQ(r.tones.size(), 3u);  // all axes modelled by default
    EXPECT_NEAR(r.tones[0].amplitude_mps2, kG, 5.0 * kNoise * std::sqrt(2.0 / kSamples));
    EXPECT_NEAR(e.vib_freq_hz, truth.f_hz, 4.0 * r.vib_freq_sigma_hz);
    EXPECT_NEAR(e.period_samples, kRate / e.vib_freq_hz, 1e-12);
    // The residual rms is the white noise: within 4 / sqrt(2 * 360) relative.
    EXPECT_NEAR(r.residual_rms_mps2, kNoise, 0.15 * kNoise);
  }
}

TEST(LevelingBatchTest, SeedExperimentRmsNearTheFloorWithHonestSigmas) {
  // 200 runs of the seed's Monte Carlo (f ~ U[22, 24] Hz, amplitude ~ N(0, 1 g), phase
  // U[0, 2 pi), 50 mg noise, level), noise estimated from the data as in the seed.
  sim::Rng rng(2000);
  LevelingOptions options;
  double roll_se = 0.0, pitch_se = 0.0, roll_sigma = 0.0, pitch_sigma = 0.0;
  constexpr int kRuns = 200;
  for (int run = 0; run < kRuns; ++run) {
    Truth truth;
    truth.f_hz = rng.Uniform(22.0, 24.0);
    truth.tones = {{0, 1, rng.Normal(kG), rng.Uniform(0.0, 2.0 * kPi)}};
    const LevelEstimate e = RunBatch(Simulate(truth, rng), options);
    roll_se += e.roll_rad * e.roll_rad;
    pitch_se += e.pitch_rad * e.pitch_rad;
    roll_sigma += e.roll_sigma_rad;
    pitch_sigma += e.pitch_sigma_rad;
  }
  const double roll_rms = std::sqrt(roll_se / kRuns), pitch_rms = std::sqrt(pitch_se / kRuns);
  roll_sigma /= kRuns;
  pitch_sigma /= kRuns;
  // The floor is 0.26 deg; the seed's period average reaches 0.92 deg. 0.30 deg leaves the
  // 5 % spread of an rms over 200 runs and the few % the tones cost.
  EXPECT_LE(pitch_rms / kDegToRad, 0.30);
  EXPECT_LE(roll_rms / kDegToRad, 0.30);
  // Honest sigma: rms / mean sigma is 1 up to the 5 % spread of the rms (1 / sqrt(2 runs))
  // and the spread of the estimated noise; [0.8, 1.25] is 4 spreads.
  EXPECT_GT(pitch_rms / pitch_sigma, 0.8);
  EXPECT_LT(pitch_rms / pitch_sigma, 1.25);
  EXPECT_GT(roll_rms / roll_sigma, 0.8);
  EXPECT_LT(roll_rms / roll_sigma, 1.25);
}

TEST(LevelingBatchTest, TwoHarmonicsOnAllAxes) {
  sim::Rng rng(7);
  Truth truth;
  truth.roll_rad = -2.0 * kDegToRad;
  truth.pitch_rad = 4.0 * kDegToRad;
  for (int axis = 0; axis < 3; ++axis) {
    truth.tones.push_back({axis, 1, (0.6 + 0.2 * axis) * kG, rng.Uniform(-kPi, kPi)});
    truth.tones.push_back({axis, 2, (0.5 - 0.1 * axis) * kG, rng.Uniform(-kPi, kPi)});
  }
  const AccelWindow window = Simulate(truth, rng);
  LevelingOptions options;
  options.vib_tones = 2;
  const BatchLevelingResult r = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options));
  ASSERT_GT(r.estimate.vib_freq_hz, 0.0) << r.estimate.fallback;
  // 4 sigma (probability 6e-5 each, fixed seed).
  EXPECT_NEAR(r.estimate.roll_rad, truth.roll_rad, 4.0 * r.estimate.roll_sigma_rad);
  EXPECT_NEAR(r.estimate.pitch_rad, truth.pitch_rad, 4.0 * r.estimate.pitch_sigma_rad);
  EXPECT_NEAR(r.estimate.vib_freq_hz, truth.f_hz, 4.0 * r.vib_freq_sigma_hz);
  // Twelve tone parameters cost little: over 4.7 and 9.3 periods the tones are nearly
  // orthogonal to the mean (measured 1.007 floors).
  EXPECT_LT(r.estimate.pitch_sigma_rad, 1.1 * Floor());
  ASSERT_EQ(r.tones.size(), 6u);
  // Amplitudes within 5 sigma of their noise (sigma sqrt(2 / N) = 0.063 m/s^2) plus the
  // effect of the frequency error; phases the same over the amplitude.
  const double amplitude_tol = 5.0 * kNoise * std::sqrt(2.0 / kSamples);
  for (const VibrationToneEstimate& est : r.tones) {
    SCOPED_TRACE("axis " + std::to_string(est.axis) + " harmonic " + std::to_string(est.harmonic));
    const Tone& tone = truth.tones[2 * est.axis + est.harmonic - 1];
    EXPECT_NEAR(est.amplitude_mps2, tone.amplitude_mps2, amplitude_tol);
    EXPECT_NEAR(WrapPi(est.phase_rad - tone.phase_rad), 0.0, amplitude_tol / tone.amplitude_mps2);
  }
}

TEST(LevelingBatchTest, StrongSecondHarmonicFindsTheFundamental) {
  // A second harmonic five times the fundamental puts the autocorrelation period at half
  // the true one; the batch must still model 23.3 Hz and 46.6 Hz.
  sim::Rng rng(19);
  Truth truth;
  truth.pitch_rad = 2.0 * kDegToRad;
  truth.tones = {{0, 1, 0.2 * kG, 0.7}, {0, 2, 1.0 * kG, -1.9}};
  const AccelWindow window = Simulate(truth, rng);
  LevelingOptions options;
  options.vib_tones = 2;
  const signal::PeriodEstimate period = EstimateWindowPeriod(window, options);
  ASSERT_TRUE(period.found) << period.reason;
  ASSERT_LT(period.refined_period_samples, 0.6 * kRate / truth.f_hz) << "the case this test is about";
  const BatchLevelingResult r = SolveLevelingBatch(window, options, period);
  // The frequency to a few of its own sigmas (about 0.02 Hz here); a wrong fundamental
  // would be off by a factor two.
  EXPECT_NEAR(r.estimate.vib_freq_hz, truth.f_hz, 0.2);
  EXPECT_NEAR(r.estimate.pitch_rad, truth.pitch_rad, 4.0 * r.estimate.pitch_sigma_rad);  // 4 sigma, fixed seed
}

TEST(LevelingBatchTest, SaturatedSamplesAreLeftOutOfTheFit) {
  // A 2 g tone on x through a +-1.9 g accelerometer at 10 deg pitch (x offset +0.17 g): the
  // positive crests clip, the negative ones do not. The batch fits the unclipped samples;
  // fitting the clipped ones too biases pitch by the clipped area.
  sim::Rng rng(23);
  Truth truth;
  truth.pitch_rad = 10.0 * kDegToRad;
  truth.tones = {{0, 1, 2.0 * kG, 0.3}};
  AccelWindow window = Simulate(truth, rng);
  LevelingOptions options;
  options.accel_range_mps2 = 1.9 * kG;
  options.accel_noise_mps2 = kNoise;
  int clipped = 0;
  for (Eigen::Vector3d& f : window.f_b_mps2) {
    if (std::abs(f.x()) > options.accel_range_mps2) {
      f.x() = std::copysign(options.accel_range_mps2, f.x());
      ++clipped;
    }
  }
  ASSERT_GT(clipped, 10) << "the case this test is about";
  const LevelEstimate kept = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options)).estimate;
  const LevelEstimate batch = RunBatch(window, options);
  // CheckWindow's rule: at or beyond 99.5 % of the range, so samples just below it count too.
  int removed = 0;
  WithoutSaturatedSamples(window, options, &removed);
  EXPECT_GE(removed, clipped);
  EXPECT_LE(removed, clipped + 3);
  EXPECT_NE(batch.fallback.find(std::to_string(removed) + " saturated samples left out"), std::string::npos)
      << batch.fallback;
  EXPECT_EQ(batch.samples_used, kSamples - removed);
  // 4 sigma (fixed seed); with the clipped samples in the fit the error is many sigma.
  EXPECT_NEAR(batch.pitch_rad, truth.pitch_rad, 4.0 * batch.pitch_sigma_rad);
  EXPECT_GT(std::abs(kept.pitch_rad - truth.pitch_rad), 4.0 * batch.pitch_sigma_rad);
}

TEST(LevelingBatchTest, NoiseFreeWindowRecoversTheVibrationExactly) {
  Truth truth;
  truth.roll_rad = 3.0 * kDegToRad;
  truth.pitch_rad = -5.0 * kDegToRad;
  truth.noise_mps2 = 0.0;
  truth.tones = {{0, 1, kG, 0.7}, {1, 1, 0.3 * kG, -2.0}};
  sim::Rng rng(1);
  const AccelWindow window = Simulate(truth, rng);
  LevelingOptions options;
  options.accel_noise_mps2 = kNoise;  // weights only: the data have no noise
  options.vib_axes = {{true, true, false}};
  const BatchLevelingResult r = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options));
  // Gauss-Newton on a zero-residual problem converges to rounding: the tolerances are
  // some 1e3 times the double rounding of 120 samples of ~10 m/s^2.
  EXPECT_NEAR(r.estimate.roll_rad, truth.roll_rad, 1e-10);
  EXPECT_NEAR(r.estimate.pitch_rad, truth.pitch_rad, 1e-10);
  EXPECT_NEAR(r.estimate.vib_freq_hz, truth.f_hz, 1e-8);
  EXPECT_LT(r.residual_rms_mps2, 1e-9);
  ASSERT_EQ(r.tones.size(), 2u);  // z is not modelled
  EXPECT_EQ(r.tones[0].axis, 0);
  EXPECT_EQ(r.tones[1].axis, 1);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(r.tones[i].amplitude_mps2, truth.tones[i].amplitude_mps2, 1e-8);
    EXPECT_NEAR(WrapPi(r.tones[i].phase_rad - truth.tones[i].phase_rad), 0.0, 1e-9);
  }
}

TEST(LevelingBatchTest, AxesWithoutTonesKeepTheirVibrationInTheResiduals) {
  // Tones on x and z, only x modelled: z's c, s stay zero, so its 0.5 g sinusoid remains in
  // the residuals: rms per axis and sample sqrt(noise^2 + (0.5 g)^2 / 2 / 3) = 2.06 m/s^2.
  sim::Rng rng(41);
  Truth truth = SeedTruth(rng);
  truth.tones.push_back({2, 1, 0.5 * kG, 1.0});
  const AccelWindow window = Simulate(truth, rng);
  LevelingOptions options;
  options.vib_axes = {{true, false, false}};
  const BatchLevelingResult r = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options));
  ASSERT_EQ(r.tones.size(), 1u);
  EXPECT_EQ(r.tones[0].axis, 0);
  EXPECT_NEAR(r.residual_rms_mps2, 2.06, 0.2);  // 10 %: the noise's share and the window's part-period
  // All three axes modelled: the residual is the white noise (within 15 %, as above).
  options.vib_axes = {{true, true, true}};
  const BatchLevelingResult all = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options));
  EXPECT_NEAR(all.residual_rms_mps2, kNoise, 0.15 * kNoise);
}

TEST(LevelingBatchTest, RollNear180DegreesStaysInRange) {
  // Upside down: the estimate is as good as anywhere else, reported in [-pi, pi] with
  // |pitch| <= pi/2 like equation 1.
  for (const double roll_deg : {179.9, -179.9}) {
    sim::Rng rng(5);
    const Truth truth = SeedTruth(rng, roll_deg, 10.0);
    const LevelEstimate e = RunBatch(Simulate(truth, rng), LevelingOptions());
    EXPECT_LE(std::abs(e.roll_rad), kPi);
    EXPECT_LE(std::abs(e.pitch_rad), kPi / 2.0);
    EXPECT_NEAR(WrapPi(e.roll_rad - truth.roll_rad), 0.0, 4.0 * e.roll_sigma_rad);  // 4 sigma: 6e-5
    EXPECT_NEAR(e.pitch_rad, truth.pitch_rad, 4.0 * e.pitch_sigma_rad);
  }
}

TEST(LevelingBatchTest, TimeOriginDoesNotMatter) {
  // The model's time is relative to the window centre: the same samples 1000 s later give
  // the same solution (up to the rounding of the shifted times, ~1e-13 s).
  sim::Rng rng_a(55), rng_b(55);
  Truth truth = SeedTruth(rng_a);
  const AccelWindow early = Simulate(truth, rng_a);
  truth = SeedTruth(rng_b);
  truth.t0_s = 1000.0;
  const AccelWindow late = Simulate(truth, rng_b);
  LevelingOptions options;
  const BatchLevelingResult a = SolveLevelingBatch(early, options, EstimateWindowPeriod(early, options));
  const BatchLevelingResult b = SolveLevelingBatch(late, options, EstimateWindowPeriod(late, options));
  EXPECT_NEAR(a.estimate.pitch_rad, b.estimate.pitch_rad, 1e-9);
  EXPECT_NEAR(a.estimate.roll_rad, b.estimate.roll_rad, 1e-9);
  EXPECT_NEAR(a.estimate.vib_freq_hz, b.estimate.vib_freq_hz, 1e-6);
  ASSERT_EQ(a.tones.size(), b.tones.size());
  EXPECT_NEAR(a.tones[0].phase_rad, b.tones[0].phase_rad, 1e-6);
}

TEST(LevelingBatchTest, NoPeriodSolvesWithoutTonesAndSaysSo) {
  // Pure white noise has no autocorrelation period.
  sim::Rng rng(3);
  Truth quiet;
  quiet.pitch_rad = 1.0 * kDegToRad;
  const AccelWindow window = Simulate(quiet, rng);
  LevelingOptions options;
  ASSERT_FALSE(EstimateWindowPeriod(window, options).found);
  const LevelEstimate e = RunBatch(window, options);
  EXPECT_EQ(e.fallback, "no autocorrelation period: batch without vibration tones");
  EXPECT_EQ(e.vib_freq_hz, 0.0);
  EXPECT_EQ(e.period_samples, 0.0);
  EXPECT_NEAR(e.pitch_rad, quiet.pitch_rad, 4.0 * e.pitch_sigma_rad);  // 4 sigma: 6e-5
  // The constant model's sigma is the floor, up to the estimated noise (~4 %, 1 / sqrt(2 dof)).
  EXPECT_NEAR(e.pitch_sigma_rad, Floor(), 0.15 * Floor());

  // A vibrating window given no period: the tone is left in the residuals, whose chi-square
  // inflates the sigma (honest about the unmodelled vibration).
  const AccelWindow vibrating = Simulate(SeedTruth(rng), rng);
  const BatchLevelingResult r = SolveLevelingBatch(vibrating, options, signal::PeriodEstimate{});
  EXPECT_EQ(r.estimate.fallback, "no autocorrelation period: batch without vibration tones");
  EXPECT_TRUE(r.tones.empty());
  // x holds a 1 g sinusoid: rms per axis and sample about sqrt(noise^2 + g^2 / 6) = 4 m/s^2.
  EXPECT_GT(r.residual_rms_mps2, 3.0);
  EXPECT_GT(r.estimate.pitch_sigma_rad, 3.0 * Floor());
}

TEST(LevelingBatchTest, InsignificantVibrationHoldsTheFrequency) {
  // A period handed in for pure noise: the fitted tone is below 5 sigma / sqrt(N), so the
  // frequency stays at its start and has no sigma.
  sim::Rng rng(8);
  Truth quiet;
  const AccelWindow window = Simulate(quiet, rng);
  signal::PeriodEstimate period;
  period.found = true;
  period.period_samples = 26;
  period.refined_period_samples = 25.75;
  const BatchLevelingResult r = SolveLevelingBatch(window, LevelingOptions(), period);
  EXPECT_NE(r.covariance_note.find("frequency held constant"), std::string::npos) << r.covariance_note;
  EXPECT_EQ(r.vib_freq_sigma_hz, 0.0);
  const double f0 = kRate / 25.75;  // the start scan covers +-8 %
  EXPECT_GE(r.estimate.vib_freq_hz, 0.92 * f0 - 1e-9);
  EXPECT_LE(r.estimate.vib_freq_hz, 1.08 * f0 + 1e-9);
  EXPECT_GT(r.estimate.pitch_sigma_rad, 0.0);
  EXPECT_NEAR(r.estimate.pitch_rad, 0.0, 4.0 * r.estimate.pitch_sigma_rad);
}

TEST(LevelingBatchTest, HarmonicsThatAliasAreNotModelled) {
  sim::Rng rng(19);
  const AccelWindow window = Simulate(SeedTruth(rng), rng);
  LevelingOptions options;
  options.vib_axes = {{true, false, false}};
  options.vib_tones = 20;
  const signal::PeriodEstimate period = EstimateWindowPeriod(window, options);
  ASSERT_TRUE(period.found);
  // Harmonics h with h x 1.08 f0 (the top of the start scan) below 0.45 x 600 Hz.
  const int usable = static_cast<int>(std::ceil(0.45 * kRate / (1.08 * kRate / period.refined_period_samples))) - 1;
  const BatchLevelingResult r = SolveLevelingBatch(window, options, period);
  EXPECT_EQ(r.estimate.fallback, "only " + std::to_string(usable) + " of 20 harmonics modelled (higher ones alias)");
  EXPECT_EQ(static_cast<int>(r.tones.size()), usable);
  EXPECT_NEAR(r.estimate.pitch_rad, 0.0, 4.0 * r.estimate.pitch_sigma_rad);  // 4 sigma: 6e-5

  // A fundamental near Nyquist: no tone at all, and the fallback says why.
  signal::PeriodEstimate fast = period;
  fast.refined_period_samples = 2.1;
  const BatchLevelingResult none = SolveLevelingBatch(window, options, fast);
  EXPECT_EQ(none.estimate.fallback, "vibration at or above 0.45 x the sample rate: batch without vibration tones");
  EXPECT_TRUE(none.tones.empty());
  EXPECT_EQ(none.estimate.vib_freq_hz, 0.0);
}

TEST(LevelingBatchTest, BiasPriorWidensTheSigmaByThePrior) {
  // f_x = g sin(pitch) + b_x: the data only see their sum, so the pitch variance gains
  // (prior / g)^2. With g known, b_z (along gravity) is observed by the data.
  sim::Rng rng(31);
  Truth truth = SeedTruth(rng, 2.0, -3.0);
  truth.bias_mps2 = Eigen::Vector3d(0.05, -0.03, 0.2);
  const AccelWindow window = Simulate(truth, rng);
  LevelingOptions options;
  options.accel_noise_mps2 = kNoise;
  const BatchLevelingResult plain = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options));
  EXPECT_EQ(plain.accel_bias_mps2, Eigen::Vector3d::Zero());
  options.accel_bias_prior_mps2 = 0.1;
  const BatchLevelingResult r = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options));
  const double expected_sigma = std::hypot(plain.estimate.pitch_sigma_rad, 0.1 / (kG * std::cos(truth.pitch_rad)));
  // Linear Gaussian algebra at the solution: a few % for the tilt and the tone terms.
  EXPECT_NEAR(r.estimate.pitch_sigma_rad, expected_sigma, 0.05 * expected_sigma);
  EXPECT_NEAR(r.estimate.pitch_rad, truth.pitch_rad, 4.0 * r.estimate.pitch_sigma_rad);
  EXPECT_NEAR(r.estimate.roll_rad, truth.roll_rad, 4.0 * r.estimate.roll_sigma_rad);
  // b_z to 4 times its data sigma noise / sqrt(N) (the prior is 2 times wider).
  EXPECT_NEAR(r.accel_bias_mps2.z(), truth.bias_mps2.z(), 4.0 * kNoise / std::sqrt(kSamples));
}

TEST(LevelingBatchTest, CovarianceOffLeavesSigmasZeroAndSaysSo) {
  sim::Rng rng(12);
  const AccelWindow window = Simulate(SeedTruth(rng), rng);
  LevelingOptions options;
  options.batch_covariance = false;
  const BatchLevelingResult r = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options));
  EXPECT_EQ(r.estimate.roll_sigma_rad, 0.0);
  EXPECT_EQ(r.estimate.pitch_sigma_rad, 0.0);
  EXPECT_EQ(r.vib_freq_sigma_hz, 0.0);
  EXPECT_NE(r.covariance_note.find("batch_covariance off"), std::string::npos) << r.covariance_note;
  // Same estimate as with the covariance: the covariance does not touch the solution.
  options.batch_covariance = true;
  const BatchLevelingResult with = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options));
  EXPECT_EQ(r.estimate.pitch_rad, with.estimate.pitch_rad);
}

TEST(LevelingBatchTest, GravityFromTheDataChangesLittle) {
  // gravity_mps2 <= 0: g is the norm of the fitted mean (tones removed), within noise /
  // sqrt(N) of 9.80665; the angles depend on the direction of f, not on its norm, to first order.
  sim::Rng rng(77);
  const Truth truth = SeedTruth(rng, 3.0, -5.0);
  const AccelWindow window = Simulate(truth, rng);
  LevelingOptions options;
  const BatchLevelingResult known = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options));
  options.gravity_mps2 = 0.0;
  const BatchLevelingResult fitted = SolveLevelingBatch(window, options, EstimateWindowPeriod(window, options));
  EXPECT_NEAR(fitted.estimate.pitch_rad, known.estimate.pitch_rad, 0.05 * known.estimate.pitch_sigma_rad);
  EXPECT_NEAR(fitted.estimate.roll_rad, known.estimate.roll_rad, 0.05 * known.estimate.roll_sigma_rad);
}

TEST(LevelingBatchTest, UnobservableRollFailsTheCovarianceAndSaysWhy) {
  // Pitch 90 deg: f = (g, 0, 0) does not depend on roll, J has a zero column.
  AccelWindow w;
  w.rate_hz = kRate;
  for (int k = 0; k < kSamples; ++k) {
    w.t_s.push_back(k / kRate);
    w.f_b_mps2.push_back(SpecificForceAtRest(0.0, kPi / 2.0, kG));
  }
  LevelingOptions options;
  options.accel_noise_mps2 = kNoise;
  const BatchLevelingResult r = SolveLevelingBatch(w, options, EstimateWindowPeriod(w, options));
  EXPECT_NE(r.covariance_note.find("ceres::Covariance (DENSE_SVD) failed"), std::string::npos) << r.covariance_note;
  EXPECT_EQ(r.estimate.roll_sigma_rad, 0.0);
  EXPECT_EQ(r.estimate.pitch_sigma_rad, 0.0);
  EXPECT_NEAR(r.estimate.pitch_rad, kPi / 2.0, 1e-12);  // exact data: rounding
}

TEST(LevelingBatchTest, TooFewSamplesIsAClearError) {
  AccelWindow w;
  w.rate_hz = kRate;
  w.source = "tiny.csv";
  w.t_s = {0.0};
  w.f_b_mps2 = {Eigen::Vector3d(0.0, 0.0, -kG)};
  try {
    RunBatch(w, LevelingOptions());
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("tiny.csv"), std::string::npos) << e.what();
  }
}

}  // namespace leveling_batch_test
}  // namespace navtwin::leveling
