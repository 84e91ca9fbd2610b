// Allan deviation: the estimator against an exact deterministic case, the IEEE Std 952
// slopes of white noise and rate random walk, and the noise coefficients read off them.
#include "core/allan.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "core/sim/random.h"

namespace navtwin {
namespace core_allan_test {

constexpr double kTau0_s = 0.01;                    // 100 Hz
constexpr std::size_t kHour = 360000;               // 1 h of 100 Hz samples

/// White rate noise of density n (rate*sqrt(s)): samples of variance n^2 / tau0.
std::vector<double> WhiteRate(double n, std::size_t count, std::uint64_t seed) {
  sim::Rng rng(seed);
  std::vector<double> y(count);
  for (double& v : y) v = rng.Normal(n / std::sqrt(kTau0_s));
  return y;
}

/// Rate random walk of intensity k (rate/sqrt(s)), each sample the exact mean of the
/// walk over its interval (trapezoid plus Brownian-bridge area, as the simulator does).
std::vector<double> RandomWalkRate(double k, std::size_t count, std::uint64_t seed) {
  sim::Rng rng(seed);
  std::vector<double> y(count);
  double r = 0.0;
  const double s = k * std::sqrt(kTau0_s);
  for (double& v : y) {
    const double z1 = rng.Normal(), z2 = rng.Normal();
    v = r + s * (0.5 * z1 + z2 / std::sqrt(12.0));
    r += s * z1;
  }
  return y;
}

/// Least-squares slope of log adev against log tau over points with >= min_clusters.
double LogLogSlope(const std::vector<AllanPoint>& c, std::size_t min_clusters) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (const AllanPoint& p : c) {
    if (p.clusters < min_clusters) continue;
    const double x = std::log(p.tau_s), y = std::log(p.adev);
    sx += x, sy += y, sxx += x * x, sxy += x * y;
    ++n;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

TEST(Allan, LinearRampGivesExactDeviation) {
  // y = R t: every second difference of the angle is R tau^2, so sigma = R tau / sqrt(2)
  // exactly; the tolerance covers rounding in the cumulative sums.
  const double ramp = 0.3;
  std::vector<double> y(1000);
  for (std::size_t k = 0; k < y.size(); ++k) y[k] = ramp * (static_cast<double>(k) + 0.5) * kTau0_s;
  const std::vector<AllanPoint> curve = OverlappingAllanDeviation(y, kTau0_s);
  ASSERT_FALSE(curve.empty());
  for (const AllanPoint& p : curve) {
    EXPECT_NEAR(p.adev, ramp * p.tau_s / std::sqrt(2.0), 1e-9 * ramp * p.tau_s) << p.tau_s;
  }
}

TEST(Allan, ClusterTimesAreLogSpacedAndClustersCounted) {
  const std::vector<double> y(10000, 1.0);
  const std::vector<AllanPoint> curve = OverlappingAllanDeviation(y, kTau0_s, {10.0, 3});
  ASSERT_GE(curve.size(), 30u);  // 1 .. 3333 samples at 10 per decade
  EXPECT_DOUBLE_EQ(curve.front().tau_s, kTau0_s);
  EXPECT_EQ(curve.front().clusters, 10000u);
  for (std::size_t i = 1; i < curve.size(); ++i) {
    EXPECT_GT(curve[i].tau_s, curve[i - 1].tau_s);
    EXPECT_LE(curve[i].tau_s / curve[i - 1].tau_s, 2.0 + 1e-12);  // octave or finer
    EXPECT_GE(curve[i].clusters, 3u);
    EXPECT_EQ(curve[i].adev, 0.0);  // a constant has no Allan deviation
  }
}

TEST(Allan, RejectsBadInput) {
  EXPECT_THROW(OverlappingAllanDeviation(std::vector<double>(3, 0.0), kTau0_s), std::invalid_argument);
  EXPECT_THROW(OverlappingAllanDeviation(std::vector<double>(100, 0.0), 0.0), std::invalid_argument);
  std::vector<double> y(100, 0.0);
  y[50] = NAN;
  EXPECT_THROW(OverlappingAllanDeviation(y, kTau0_s), std::invalid_argument);
  EXPECT_THROW(OverlappingAllanDeviation(std::vector<double>(100, 0.0), kTau0_s, {10.0, 1}),
               std::invalid_argument);
}

TEST(Allan, WhiteNoiseHasSlopeMinusHalfAndGivesArw) {
  const double n = 2e-4;  // rate*sqrt(s), e.g. rad/sqrt(s)
  const std::vector<AllanPoint> curve = OverlappingAllanDeviation(WhiteRate(n, kHour, 11), kTau0_s);
  // Every point agrees with n / sqrt(tau) within 4 of its relative errors
  // 1/sqrt(2(K-1)) (IEEE 952's bound, conservative for the overlapping estimate).
  for (const AllanPoint& p : curve) {
    if (p.clusters < kMinFitClusters) continue;
    EXPECT_NEAR(p.adev / (n / std::sqrt(p.tau_s)), 1.0, 4.0 * AllanRelativeError(p.clusters)) << p.tau_s;
  }
  // Slope over points with >= 100 clusters (relative errors <= 7 %, over 2.6 decades of tau):
  // its standard error is about 0.01, so 0.05 is a 5-sigma band.
  EXPECT_NEAR(LogLogSlope(curve, 100), -0.5, 0.05);
  // The readout is dominated by tau = 0.01 .. 1 s, 3600 to 360000 clusters (relative errors
  // <= 1.2 %): 10 % is far outside the sampling error.
  const AllanNoiseFit fit = FitAllanNoise(curve);
  EXPECT_NEAR(fit.white_noise / n, 1.0, 0.10);
  // No flat part on a pure -1/2 line: bias instability is only an upper bound, and no
  // +1/2 region exists.
  EXPECT_TRUE(fit.bias_instability_is_bound);
  EXPECT_TRUE(std::isnan(fit.rate_random_walk));
}

TEST(Allan, RateRandomWalkHasSlopePlusHalfAndGivesRrw) {
  const double k = 3e-6;  // rate/sqrt(s)
  const std::vector<AllanPoint> curve = OverlappingAllanDeviation(RandomWalkRate(k, kHour, 12), kTau0_s);
  // Slope over points with >= 100 clusters: a random walk's Allan estimate scatters more
  // than white noise's, so a 0.1 band (about 5 standard errors for this record).
  EXPECT_NEAR(LogLogSlope(curve, 100), 0.5, 0.1);
  // The readout is dominated by the shortest cluster times (thousands of clusters,
  // relative errors of a few per cent): 10 %.
  const AllanNoiseFit fit = FitAllanNoise(curve);
  EXPECT_NEAR(fit.rate_random_walk / k, 1.0, 0.10);
  EXPECT_TRUE(std::isnan(fit.white_noise));
}

TEST(Allan, WhiteNoiseAndRandomWalkTogetherAreSeparated) {
  // N and K with the lines crossing at sqrt(3) N / K = 1 s. N is read at tau <= 0.4 s
  // (>= 9000 clusters): 10 % is far outside its sampling error. K is read at tau >= 2.6 s
  // (<= 1400 clusters); a random walk's Allan estimates are correlated across tau, and
  // over 40 seeds this readout scattered by 2.9 % (1 sigma) about 0.995: 10 % is 3.4 sigma.
  const double n = 1e-4, k = std::sqrt(3.0) * n / 1.0;
  std::vector<double> y = WhiteRate(n, kHour, 13);
  const std::vector<double> walk = RandomWalkRate(k, kHour, 14);
  for (std::size_t i = 0; i < y.size(); ++i) y[i] += walk[i];
  const AllanNoiseFit fit = FitAllanNoise(OverlappingAllanDeviation(y, kTau0_s));
  EXPECT_NEAR(fit.white_noise / n, 1.0, 0.10);
  EXPECT_NEAR(fit.rate_random_walk / k, 1.0, 0.10);
  // The bucket's flat bottom at tau = 1 s, sigma = sqrt(2) n / sqrt(1 s), is read as B; the
  // bottom has 3600 clusters (1.2 %) and scattered by 1.0 % over the 40 seeds: 5 %.
  EXPECT_FALSE(fit.bias_instability_is_bound);
  EXPECT_NEAR(fit.bias_instability * 0.6643 / (std::sqrt(2.0) * n), 1.0, 0.05);
}

TEST(Allan, RelativeErrorFollowsIeee952) {
  EXPECT_DOUBLE_EQ(AllanRelativeError(51), 0.1);
  EXPECT_TRUE(std::isinf(AllanRelativeError(1)));
}

TEST(Allan, ImuRatesUseTheMeanIntervalAndCountIrregularOnes) {
  // 10 samples at 100 Hz, one of them 30 ms late (a dropped pair of samples).
  std::vector<ImuSample> imu(10);
  double t_s = 100.0;
  for (std::size_t k = 0; k < imu.size(); ++k) {
    imu[k].dt_s = k == 4 ? 0.03 : 0.01;
    t_s += imu[k].dt_s;
    imu[k].t_s = t_s;
    imu[k].dtheta_b_rad = Eigen::Vector3d(1e-4, 2e-4, 3e-4) * static_cast<double>(k);
    imu[k].dv_b_mps = Eigen::Vector3d(0.1, -0.2, -0.098) * static_cast<double>(k + 1);
  }
  const ImuRateRecord r = ImuRates(imu, {2, 3});
  EXPECT_EQ(r.samples, 10u);
  EXPECT_NEAR(r.duration_s, 0.12, 1e-12);
  EXPECT_NEAR(r.tau0_s, 0.012, 1e-12);
  // |0.01 - 0.012| = 0.002 > 10 % of tau0 for every interval; |0.03 - 0.012| too.
  EXPECT_EQ(r.irregular_intervals, 10u);
  ASSERT_EQ(r.rates.size(), 2u);
  // Increment / tau0: the rates integrate back to the recorded increments.
  double angle_rad = 0.0, dv_mps = 0.0;
  for (std::size_t k = 0; k < imu.size(); ++k) {
    EXPECT_NEAR(r.rates[0][k], imu[k].dtheta_b_rad.z() / 0.012, 1e-12);
    angle_rad += r.rates[0][k] * r.tau0_s;
    dv_mps += r.rates[1][k] * r.tau0_s;
  }
  EXPECT_NEAR(angle_rad, 3e-4 * 45.0, 1e-12);
  EXPECT_NEAR(dv_mps, 0.1 * 55.0, 1e-12);
  // With a looser threshold only the late sample is irregular.
  EXPECT_EQ(ImuRates(imu, {0}, 0.5).irregular_intervals, 1u);
}

TEST(Allan, ImuRatesRejectBadInput) {
  std::vector<ImuSample> imu(10);
  for (std::size_t k = 0; k < imu.size(); ++k) {
    imu[k].dt_s = 0.01;
    imu[k].t_s = 0.01 * static_cast<double>(k + 1);
  }
  EXPECT_THROW(ImuRates(imu, {6}), std::invalid_argument);
  EXPECT_THROW(ImuRates(imu, {-1}), std::invalid_argument);
  imu.resize(3);
  EXPECT_THROW(ImuRates(imu, {0}), std::invalid_argument);
}

}  // namespace core_allan_test
}  // namespace navtwin
