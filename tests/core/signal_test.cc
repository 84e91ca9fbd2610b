#include "core/signal.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/sim/random.h"
#include "core/units.h"

namespace navtwin::signal {
namespace core_signal_test {


std::vector<Eigen::Vector3d> Sinusoid(int n, double period_samples, double amplitude, double phase,
                                      const Eigen::Vector3d& offset) {
  std::vector<Eigen::Vector3d> x(n);
  for (int i = 0; i < n; ++i) {
    x[i] = offset;
    x[i].x() += amplitude * std::sin(kTwoPi * i / period_samples + phase);
  }
  return x;
}

// Equation 2 written out term by term, as in the seed.
double DirectEquation2(const std::vector<double>& x, int t) {
  const int k = static_cast<int>(x.size());
  double mu = 0.0;
  for (double v : x) mu += v;
  mu /= k;
  double num = 0.0, den = 0.0;
  for (int j = t + 1; j <= k; ++j) num += (x[j - 1] - mu) * (x[j - t - 1] - mu);
  for (int j = 1; j <= k; ++j) den += (x[j - 1] - mu) * (x[j - 1] - mu);
  return num / den;
}

TEST(SignalTest, AutocorrelationIsEquationTwo) {
  sim::Rng rng(7);
  std::vector<double> x(50);
  for (double& v : x) v = rng.Normal() + 3.0;
  const std::vector<double> r = Autocorrelation(x, 20);
  ASSERT_EQ(r.size(), 21u);
  EXPECT_DOUBLE_EQ(r[0], 1.0);
  // Rounding only: both sum the same 50 products in a different order.
  for (int t = 1; t <= 20; ++t) EXPECT_NEAR(r[t], DirectEquation2(x, t), 1e-12) << "lag " << t;
  // max_lag beyond the data is clamped to k - 1.
  EXPECT_EQ(Autocorrelation(x, 500).size(), 50u);
}

TEST(SignalTest, ConstantSignalHasNoCorrelation) {
  const std::vector<double> r = Autocorrelation(std::vector<double>(30, 9.81), 10);
  for (double v : r) EXPECT_EQ(v, 0.0);
}

TEST(SignalTest, RunningAutocorrelationMatchesTheBatchSumsAtEverySize) {
  sim::Rng rng(11);
  RunningAutocorrelation running(15, {{true, false, true}});
  std::vector<Eigen::Vector3d> x;
  for (int i = 0; i < 60; ++i) {
    x.push_back(rng.Normal3(1.0) + Eigen::Vector3d(0.0, 5.0, -9.8));
    running.Add(x.back());
    // Multi-channel equation 2 = summed numerators over summed denominators.
    std::vector<double> a, c;
    for (const Eigen::Vector3d& v : x) {
      a.push_back(v.x());
      c.push_back(v.z());
    }
    const std::vector<double> r = running.Evaluate();
    ASSERT_EQ(static_cast<int>(r.size()), std::min(15, i) + 1);
    if (i < 2) continue;
    const std::vector<double> direct = Autocorrelation(x, 15, {{true, false, true}});
    for (size_t t = 0; t < r.size(); ++t) EXPECT_NEAR(r[t], direct[t], 1e-10);
    // One channel: equation 2 itself (the y channel is excluded above).
    RunningAutocorrelation one(15, {{true, false, false}});
    for (const Eigen::Vector3d& v : x) one.Add(v);
    const std::vector<double> rx = one.Evaluate();
    for (size_t t = 1; t < rx.size(); ++t) EXPECT_NEAR(rx[t], DirectEquation2(a, static_cast<int>(t)), 1e-10);
  }
}

TEST(SignalTest, SeedExamplePeriodOfFiveAndThreeQuarterSamples) {
  // The seed's example: 120 samples, peaks every 5 or 6 lags, mean 5.75 -> 6 samples.
  const auto x = Sinusoid(120, 5.75, 1.0, 0.3, Eigen::Vector3d(0.0, 0.0, -9.8));
  const std::vector<double> r = Autocorrelation(x, 60);
  const PeriodEstimate p = EstimatePeriod(r, 120, PeakOptions{});
  ASSERT_TRUE(p.found) << p.reason;
  ASSERT_GE(p.peak_lags.size(), 9u);
  for (size_t i = 1; i < p.peak_lags.size(); ++i) {
    const int step = p.peak_lags[i] - p.peak_lags[i - 1];
    EXPECT_TRUE(step == 5 || step == 6) << "step " << step;
  }
  EXPECT_EQ(p.period_samples, 6);
  EXPECT_NEAR(p.mean_relative_lag, 5.75, 0.15);  // integer peak lags: at most 1 lag over ~10 peaks
  // Parabolic interpolation: a sampled cosine's peak is found to a few hundredths.
  EXPECT_NEAR(p.refined_period_samples, 5.75, 0.03);
}

TEST(SignalTest, RotorPeriodUnderNoise) {
  // Seed 000 conditions: 23 Hz at 600 Hz (26.09 samples), 1 g amplitude, 50 mg noise.
  sim::Rng rng(3);
  auto x = Sinusoid(120, 600.0 / 23.0, 9.80665, 1.0, Eigen::Vector3d(0.0, 0.0, -9.80665));
  for (auto& v : x) v += rng.Normal3(0.49);
  const PeriodEstimate p = EstimatePeriod(Autocorrelation(x, 60), 120, PeakOptions{});
  ASSERT_TRUE(p.found) << p.reason;
  EXPECT_EQ(p.period_samples, 26);
  // Noise shifts a peak by a fraction of a lag at this signal-to-noise ratio.
  EXPECT_NEAR(p.refined_period_samples, 600.0 / 23.0, 0.3);
}

TEST(SignalTest, WhiteNoiseHasNoPeriod) {
  sim::Rng rng(5);
  std::vector<Eigen::Vector3d> x(120);
  for (auto& v : x) v = rng.Normal3(0.5);
  const PeriodEstimate p = EstimatePeriod(Autocorrelation(x, 60), 120, PeakOptions{});
  // White noise correlations are ~1/sqrt(120 x 3) ~ 0.05, far below the 0.5 threshold.
  EXPECT_FALSE(p.found);
  EXPECT_NE(p.reason.find("no autocorrelation peak"), std::string::npos) << p.reason;
}

TEST(SignalTest, WindowShorterThanTwoPeriods) {
  const auto x = Sinusoid(120, 70.0, 1.0, 0.0, Eigen::Vector3d::Zero());
  const PeriodEstimate p = EstimatePeriod(Autocorrelation(x, 119), 120, PeakOptions{});
  EXPECT_FALSE(p.found);
  EXPECT_NE(p.reason.find("fewer than two periods"), std::string::npos) << p.reason;
}

TEST(SignalTest, WholePeriodAverageCancelsTheSinusoid) {
  const Eigen::Vector3d offset(0.1, -0.2, -9.8);
  const auto x = Sinusoid(125, 24.0, 9.8, 0.7, offset);
  const WholePeriodAverage avg = AverageWholePeriods(x, 24);
  EXPECT_EQ(avg.blocks, 5);
  EXPECT_EQ(avg.samples_used, 120);
  // A sampled sinusoid over whole periods sums to zero up to rounding.
  EXPECT_NEAR((avg.mean - offset).norm(), 0.0, 1e-12);
  EXPECT_EQ(AverageWholePeriods(x, 200).blocks, 0);
  EXPECT_THROW(AverageWholePeriods(x, 0), std::invalid_argument);
}

TEST(SignalTest, InterpolatedAverageOverAFractionalPeriod) {
  // Linear data: the interpolant is exact, the mean is the value at the centre.
  std::vector<Eigen::Vector3d> ramp(20);
  for (int i = 0; i < 20; ++i) ramp[i] = Eigen::Vector3d(i, 2.0 * i, 1.0);
  const Eigen::Vector3d m = AverageInterpolated(ramp, 2.3, 7.45);
  EXPECT_NEAR(m.x(), 2.3 + 7.45 / 2.0, 1e-12);
  EXPECT_NEAR(m.y(), 2.0 * (2.3 + 7.45 / 2.0), 1e-12);
  // One whole non-integer period of a sinusoid: only the interpolation error of about
  // A (w dt)^2 / 8 ~ 7e-3 A per cell is left, and it averages out over the period.
  const double period = 26.37;
  const auto x = Sinusoid(60, period, 1.0, 0.4, Eigen::Vector3d(0.0, 0.0, -1.0));
  const Eigen::Vector3d avg = AverageInterpolated(x, 3.6, period);
  EXPECT_NEAR(avg.x(), 0.0, 1e-3);
  // The rounded period leaves a residual of order A e / P (here ~0.014).
  EXPECT_GT(std::abs(AverageWholePeriods(std::vector<Eigen::Vector3d>(x.begin() + 3, x.begin() + 29), 26).mean.x()),
            2e-3);
  EXPECT_THROW(AverageInterpolated(x, 50.0, 20.0), std::invalid_argument);
}

}  // namespace core_signal_test
}  // namespace navtwin::signal
