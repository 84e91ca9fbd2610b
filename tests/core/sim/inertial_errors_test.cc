// Inertial sensor error models: the YAML schema and its errors, the statistics of the
// drawn constants, regression recovery of scale factor, misalignment, g-sensitivity and
// temperature coefficients, the noise processes through their Allan deviation, the
// quantiser, the perfect switch and byte-for-byte determinism.
#include "core/sim/inertial_errors.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "core/allan.h"
#include "core/io/input_error.h"
#include "core/rotation.h"
#include "core/units.h"

namespace navtwin::sim {
namespace sim_inertial_errors_test {


InertialErrorConfig Parse(const std::string& yaml) {
  return ParseInertialErrorConfig(ParseYaml(yaml, "errors.yaml"));
}

/// Parsing `yaml` throws an InputError about `field` on `line`.
void ExpectInputError(const std::string& yaml, const std::string& field, long line) {
  try {
    Parse(yaml);
    ADD_FAILURE() << "no error for:\n" << yaml;
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.file(), "errors.yaml");
  }
}

/// Every error source of both triads switched on (used where all must be present).
InertialErrorConfig FullConfig() {
  return Parse(R"(
gyro:
  bias_deg_h: 10
  bias_instability_deg_h: 1
  correlation_time_s: 50
  rate_random_walk_deg_h_sqrt_h: 0.5
  arw_deg_sqrt_h: 0.2
  scale_factor_ppm: 300
  misalignment_arcsec: 20
  quantization_rad: 1e-6
  temperature: {bias_deg_h_per_degC: 0.1, bias_deg_h_per_degC2: 0.01, scale_factor_ppm_per_degC: 3,
                scale_factor_ppm_per_degC2: 0.1}
accel:
  bias_ug: 500
  bias_instability_ug: 20
  correlation_time_s: 30
  acceleration_random_walk_ug_sqrt_h: 5
  vrw_m_s_sqrt_h: 0.05
  scale_factor_ppm: 200
  misalignment_arcsec: 30
  quantization_m_s: 1e-5
  temperature: {bias_ug_per_degC: 5, bias_ug_per_degC2: 0.2, scale_factor_ppm_per_degC: 2,
                scale_factor_ppm_per_degC2: 0.05}
g_sensitivity_deg_h_per_g: 2
temperature_profile: {reference_degC: 20, initial_degC: 10, final_degC: 40, time_constant_s: 300}
)");
}

std::string Emitted(const InertialErrorModel& model) {
  YAML::Emitter out;
  model.EmitDrawn(out);
  return out.c_str();
}

TEST(InertialErrorConfig, ParsesEveryKeyIntoSiUnits) {
  const InertialErrorConfig c = Parse(R"(
gyro:
  bias_deg_h: 1.5
  bias_instability_deg_h: 0.5
  correlation_time_s: 100
  rate_random_walk_deg_h_sqrt_h: 0.1
  arw_deg_sqrt_h: 0.05
  scale_factor_ppm: 100
  misalignment_arcsec: 5
  quantization_rad: 1e-6
  temperature: {bias_deg_h_per_degC: 0.01, bias_fixed_deg_h_per_degC2: [1, 2, 3],
                scale_factor_ppm_per_degC: 2, scale_factor_fixed_ppm_per_degC2: [4, 5, 6]}
accel:
  bias_fixed_ug: [100, -50, 25]
  vrw_m_s_sqrt_h: 0.06
  acceleration_random_walk_ug_sqrt_h: 3
  scale_factor_fixed_ppm: [10, 20, 30]
  misalignment_fixed_arcsec: [[0, 1, 2], [3, 0, 4], [5, 6, 0]]
  quantization_m_s: 1e-4
g_sensitivity_fixed_deg_h_per_g: [[1, 2, 3], [4, 5, 6], [7, 8, 9]]
temperature_profile: {reference_degC: 20, initial_degC: 10, final_degC: 40, time_constant_s: 300}
)");
  // Conversions are exact products, so 1e-15 relative covers their rounding.
  const auto near = [](double a, double b) { EXPECT_NEAR(a, b, 1e-15 * std::abs(b)); };
  near(c.gyro.bias.sigma, 1.5 * kDegPerHour_radps);
  EXPECT_FALSE(c.gyro.bias.fixed.has_value());
  near(c.gyro.bias_instability, 0.5 * kDegPerHour_radps);
  near(c.gyro.correlation_time_s, 100.0);
  near(c.gyro.random_walk, 0.1 * kDegPerHour_radps / 60.0);  // (deg/h)/sqrt(h) -> (rad/s)/sqrt(s)
  near(c.gyro.white_noise, 0.05 * kDegToRad / 60.0);  // deg/sqrt(h) -> rad/sqrt(s)
  near(c.gyro.scale_factor.sigma, 100e-6);
  near(c.gyro.misalignment.sigma, 5.0 * kArcsec_rad);
  near(c.gyro.quantum, 1e-6);
  near(c.gyro.bias_per_degC.sigma, 0.01 * kDegPerHour_radps);
  near((*c.gyro.bias_per_degC2.fixed)[2], 3.0 * kDegPerHour_radps);
  near(c.gyro.scale_factor_per_degC.sigma, 2e-6);
  near((*c.gyro.scale_factor_per_degC2.fixed)[1], 5e-6);
  near((*c.accel.bias.fixed)[1], -50.0 * kMicroG_mps2);
  near(c.accel.white_noise, 0.06 / 60.0);  // m/s/sqrt(h) -> m/s/sqrt(s)
  near(c.accel.random_walk, 3.0 * kMicroG_mps2 / 60.0);
  near((*c.accel.scale_factor.fixed)[2], 30e-6);
  near((*c.accel.misalignment.fixed)(1, 0), 3.0 * kArcsec_rad);
  near(c.accel.quantum, 1e-4);
  near((*c.g_sensitivity.fixed)(2, 1), 8.0 * kDegPerHour_radps / 9.80665);
  near(c.temperature.reference_degC, 20.0);
  near(c.temperature.At(0.0), 10.0);
  near(c.temperature.At(300.0), 40.0 - 30.0 / std::exp(1.0));
  near(c.temperature.At(1e6), 40.0);
}

TEST(InertialErrorConfig, EmptySectionMeansNoError) {
  const InertialErrorConfig c = Parse("{}");
  EXPECT_EQ(c.gyro.white_noise, 0.0);
  EXPECT_EQ(c.accel.bias.sigma, 0.0);
  EXPECT_EQ(c.temperature.At(1000.0), c.temperature.reference_degC);
}

TEST(InertialErrorConfig, BadInputNamesFileLineAndKey) {
  ExpectInputError("gyro:\n  bias_deg_hr: 1\n", "gyro.bias_deg_hr", 2);
  ExpectInputError("gyro:\n  bias_deg_h: 1\n  bias_fixed_deg_h: [1, 2, 3]\n", "gyro.bias_fixed_deg_h", 3);
  ExpectInputError("accel:\n  vrw_m_s_sqrt_h: -1\n", "accel.vrw_m_s_sqrt_h", 2);
  ExpectInputError("gyro:\n  bias_instability_deg_h: 0.1\n", "gyro.correlation_time_s", 2);
  ExpectInputError("accel:\n  misalignment_fixed_arcsec: [[1, 0, 0], [0, 0, 0], [0, 0, 0]]\n",
                   "accel.misalignment_fixed_arcsec", 2);
  ExpectInputError("g_sensitivity_fixed_deg_h_per_g: [[0, 1], [0, 0, 0], [0, 0, 0]]\n",
                   "g_sensitivity_fixed_deg_h_per_g", 1);
  ExpectInputError("gyro:\n  temperature:\n    bias_deg_h_per_K: 1\n", "gyro.temperature.bias_deg_h_per_K", 3);
  ExpectInputError("temperature_profile: {initial_degC: 10, final_degC: 40}\n",
                   "temperature_profile.time_constant_s", 1);
  ExpectInputError("accel:\n  bias_ug: .nan\n", "accel.bias_ug", 2);
}

/// Mean and standard deviation of `x` against N(0, sigma^2): the mean within 4 of its
/// standard errors sigma/sqrt(n), the standard deviation within 4 of its relative
/// standard errors 1/sqrt(2n).
void ExpectNormalSample(const std::vector<double>& x, double sigma, const char* what) {
  const double n = static_cast<double>(x.size());
  double mean = 0.0, sq = 0.0;
  for (const double v : x) mean += v;
  mean /= n;
  for (const double v : x) sq += (v - mean) * (v - mean);
  const double sd = std::sqrt(sq / (n - 1.0));
  EXPECT_NEAR(mean, 0.0, 4.0 * sigma / std::sqrt(n)) << what;
  EXPECT_NEAR(sd / sigma, 1.0, 4.0 / std::sqrt(2.0 * n)) << what;
}

TEST(InertialErrorModel, DrawnConstantsAreZeroMeanWithTheConfiguredSigma) {
  const InertialErrorConfig c = FullConfig();
  std::vector<double> bias, scale, misalignment, accel_bias, g_sens, temp_coef;
  for (std::uint64_t seed = 0; seed < 2000; ++seed) {
    const InertialErrorModel m(c, Rng(seed).Stream("imu"), false);
    for (int i = 0; i < 3; ++i) {
      bias.push_back(m.gyro().drawn().bias[i]);
      scale.push_back(m.gyro().drawn().scale_factor[i]);
      accel_bias.push_back(m.accel().drawn().bias[i]);
      temp_coef.push_back(m.gyro().drawn().bias_per_degC[i]);
      for (int j = 0; j < 3; ++j) {
        g_sens.push_back(m.g_sensitivity()(i, j));
        if (i == j) {
          ASSERT_EQ(m.gyro().drawn().misalignment(i, j), 0.0);  // the diagonal is the scale factor's
        } else {
          misalignment.push_back(m.gyro().drawn().misalignment(i, j));
        }
      }
    }
  }
  ExpectNormalSample(bias, c.gyro.bias.sigma, "gyro bias");
  ExpectNormalSample(scale, c.gyro.scale_factor.sigma, "gyro scale factor");
  ExpectNormalSample(misalignment, c.gyro.misalignment.sigma, "gyro misalignment");
  ExpectNormalSample(accel_bias, c.accel.bias.sigma, "accelerometer bias");
  ExpectNormalSample(g_sens, c.g_sensitivity.sigma, "g-sensitivity");
  ExpectNormalSample(temp_coef, c.gyro.bias_per_degC.sigma, "gyro bias per degC");
}

TEST(InertialErrorModel, FixedValuesAreUsedAsGiven) {
  const InertialErrorConfig c = Parse(R"(
gyro: {bias_fixed_deg_h: [1, -2, 3], misalignment_fixed_arcsec: [[0, 1, 2], [3, 0, 4], [5, 6, 0]]}
accel: {scale_factor_fixed_ppm: [10, 20, 30]}
)");
  const InertialErrorModel m(c, Rng(1), false);
  EXPECT_EQ(m.gyro().drawn().bias, *c.gyro.bias.fixed);
  EXPECT_EQ(m.gyro().drawn().misalignment, *c.gyro.misalignment.fixed);
  EXPECT_EQ(m.accel().drawn().scale_factor, *c.accel.scale_factor.fixed);
}

/// Least squares y = X b with known noise sigma: coefficients and standard errors.
class Regression {
 public:
  explicit Regression(int n) : xtx_(Eigen::MatrixXd::Zero(n, n)), xty_(Eigen::MatrixXd::Zero(n, 3)) {}
  void Add(const Eigen::VectorXd& x, const Eigen::Vector3d& y) {
    xtx_ += x * x.transpose();
    xty_ += x * y.transpose();
  }
  Eigen::MatrixXd Coefficients() const { return xtx_.ldlt().solve(xty_); }  ///< one column per output
  double StandardError(int j, double noise_sigma) const {
    return noise_sigma * std::sqrt(xtx_.inverse()(j, j));
  }

 private:
  Eigen::MatrixXd xtx_, xty_;
};

TEST(InertialErrorModel, RegressionRecoversScaleFactorMisalignmentGSensitivityAndBias) {
  // Large constants, white noise only as the disturbance, so every estimate has a small
  // standard error; each is checked within 5 standard errors (known noise sigma).
  const InertialErrorConfig c = Parse(R"(
gyro: {bias_deg_h: 100, scale_factor_ppm: 1000, misalignment_arcsec: 200, arw_deg_sqrt_h: 0.05}
accel: {bias_ug: 1000, scale_factor_ppm: 1000, misalignment_arcsec: 200, vrw_m_s_sqrt_h: 0.05}
g_sensitivity_deg_h_per_g: 50
)");
  InertialErrorModel m(c, Rng(7).Stream("imu"), false);
  const double dt = 0.01;
  Regression gyro(7), accel(4);
  for (int k = 1; k <= 60000; ++k) {  // 600 s at 100 Hz, three rates and forces at unrelated frequencies
    const double t = k * dt;
    const Eigen::Vector3d w(std::sin(0.61 * t), std::cos(0.37 * t + 1.0), std::sin(0.23 * t + 2.0));
    const Eigen::Vector3d f(5.0 * std::sin(0.29 * t), 5.0 * std::cos(0.53 * t), -9.8 + 5.0 * std::sin(0.71 * t));
    Eigen::Vector3d dtheta, dv;
    m.Apply(t, dt, 25.0, w * dt, f * dt, &dtheta, &dv);
    Eigen::VectorXd xg(7), xa(4);
    xg << w * dt, f * dt, dt;
    xa << f * dt, dt;
    gyro.Add(xg, dtheta);
    accel.Add(xa, dv);
  }
  const Eigen::MatrixXd bg = gyro.Coefficients(), ba = accel.Coefficients();
  const double gyro_noise = c.gyro.white_noise * std::sqrt(dt), accel_noise = c.accel.white_noise * std::sqrt(dt);
  const DrawnTriadErrors& g = m.gyro().drawn();
  const DrawnTriadErrors& a = m.accel().drawn();
  const Eigen::Matrix3d ag = Eigen::Matrix3d::Identity() + Eigen::Matrix3d(g.scale_factor.asDiagonal()) + g.misalignment;
  const Eigen::Matrix3d aa = Eigen::Matrix3d::Identity() + Eigen::Matrix3d(a.scale_factor.asDiagonal()) + a.misalignment;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      EXPECT_NEAR(bg(j, i), ag(i, j), 5.0 * gyro.StandardError(j, gyro_noise)) << "gyro A " << i << j;
      EXPECT_NEAR(bg(3 + j, i), m.g_sensitivity()(i, j), 5.0 * gyro.StandardError(3 + j, gyro_noise))
          << "G " << i << j;
      EXPECT_NEAR(ba(j, i), aa(i, j), 5.0 * accel.StandardError(j, accel_noise)) << "accel A " << i << j;
    }
    EXPECT_NEAR(bg(6, i), g.bias[i], 5.0 * gyro.StandardError(6, gyro_noise)) << "gyro bias " << i;
    EXPECT_NEAR(ba(3, i), a.bias[i], 5.0 * accel.StandardError(3, accel_noise)) << "accel bias " << i;
  }
  // The test can tell: the standard errors are small against the drawn sizes.
  EXPECT_LT(gyro.StandardError(1, gyro_noise), 0.05 * c.gyro.misalignment.sigma);
  EXPECT_LT(gyro.StandardError(3, gyro_noise), 0.05 * c.g_sensitivity.sigma);
  EXPECT_LT(accel.StandardError(0, accel_noise), 0.05 * c.accel.scale_factor.sigma);
}

TEST(InertialErrorModel, BiasAndScaleFactorAreQuadraticInTemperature) {
  // At each temperature, +w and -w along all axes (no misalignment, no noise), as in the
  // +1 g / -1 g chamber method of seed 001: the half sum is the bias, the half difference
  // the scale factor. A quadratic fit over -20 .. 60 degC recovers the drawn
  // coefficients; without noise only rounding remains (1e-6 of each coefficient's sigma).
  const InertialErrorConfig c = Parse(R"(
gyro:
  bias_deg_h: 100
  scale_factor_ppm: 500
  temperature: {bias_deg_h_per_degC: 2, bias_deg_h_per_degC2: 0.05, scale_factor_ppm_per_degC: 20,
                scale_factor_ppm_per_degC2: 0.5}
temperature_profile: {reference_degC: 20}
)");
  InertialErrorModel m(c, Rng(3).Stream("imu"), false);
  const double dt = 0.01, w = 1.0;
  Eigen::MatrixXd x(17, 3);
  Eigen::MatrixXd bias(17, 3), scale(17, 3);
  double t = 0.0;
  for (int k = 0; k < 17; ++k) {
    const double temp = -20.0 + 5.0 * k, dT = temp - 20.0;
    x.row(k) << 1.0, dT, dT * dT;
    Eigen::Vector3d plus, minus, dv;
    m.Apply(t += dt, dt, temp, Eigen::Vector3d::Constant(w * dt), Eigen::Vector3d::Zero(), &plus, &dv);
    m.Apply(t += dt, dt, temp, Eigen::Vector3d::Constant(-w * dt), Eigen::Vector3d::Zero(), &minus, &dv);
    bias.row(k) = (plus + minus) / (2.0 * dt);
    scale.row(k) = (plus - minus) / (2.0 * w * dt) - Eigen::Vector3d::Ones();
  }
  const Eigen::MatrixXd cb = x.colPivHouseholderQr().solve(bias), cs = x.colPivHouseholderQr().solve(scale);
  const DrawnTriadErrors& d = m.gyro().drawn();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(cb(0, i), d.bias[i], 1e-6 * c.gyro.bias.sigma);
    EXPECT_NEAR(cb(1, i), d.bias_per_degC[i], 1e-6 * c.gyro.bias_per_degC.sigma);
    EXPECT_NEAR(cb(2, i), d.bias_per_degC2[i], 1e-6 * c.gyro.bias_per_degC2.sigma);
    EXPECT_NEAR(cs(0, i), d.scale_factor[i], 1e-6 * c.gyro.scale_factor.sigma);
    EXPECT_NEAR(cs(1, i), d.scale_factor_per_degC[i], 1e-6 * c.gyro.scale_factor_per_degC.sigma);
    EXPECT_NEAR(cs(2, i), d.scale_factor_per_degC2[i], 1e-6 * c.gyro.scale_factor_per_degC2.sigma);
  }
}

/// Rates dtheta/dt of a motionless IMU (gyro, or accelerometer when `accel`) over
/// `count` intervals of dt.
std::vector<double> StaticRates(InertialErrorModel* m, double dt, std::size_t count, bool accel) {
  std::vector<double> y(count);
  for (std::size_t k = 0; k < count; ++k) {
    Eigen::Vector3d dtheta, dv;
    m->Apply((k + 1) * dt, dt, 25.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), &dtheta, &dv);
    y[k] = (accel ? dv : dtheta)[0] / dt;
  }
  return y;
}

TEST(InertialErrorModel, WhiteNoiseGivesConfiguredArwAndVrw) {
  // 1 h at 100 Hz; the Allan readout at tau <= 1 s rests on >= 3600 clusters (relative
  // error <= 1.2 %), so 10 % is far beyond the sampling error.
  const InertialErrorConfig c = Parse("gyro: {arw_deg_sqrt_h: 0.1}\naccel: {vrw_m_s_sqrt_h: 0.03}\n");
  InertialErrorModel gyro(c, Rng(21).Stream("imu"), false), accel(c, Rng(22).Stream("imu"), false);
  const double dt = 0.01;
  const AllanNoiseFit fg = FitAllanNoise(OverlappingAllanDeviation(StaticRates(&gyro, dt, 360000, false), dt));
  const AllanNoiseFit fa = FitAllanNoise(OverlappingAllanDeviation(StaticRates(&accel, dt, 360000, true), dt));
  EXPECT_NEAR(fg.white_noise / c.gyro.white_noise, 1.0, 0.10);
  EXPECT_NEAR(fa.white_noise / c.accel.white_noise, 1.0, 0.10);
}

TEST(InertialErrorModel, GaussMarkovBiasFollowsItsAllanCurveAndReadsAsBiasInstability) {
  // 4 h at 10 Hz of a Gauss–Markov bias (sigma 1 deg/h, tau_c 10 s). Its Allan variance
  // is sigma^2 (tau_c/tau)^2 (2 tau/tau_c - 3 + 4 e^(-tau/tau_c) - e^(-2 tau/tau_c)); every
  // point with >= 9 clusters must match within 5 relative errors (the increments are
  // exact averages, so this holds down to tau = 0.1 s).
  const InertialErrorConfig c = Parse("gyro: {bias_instability_deg_h: 1, correlation_time_s: 10}\n");
  InertialErrorModel m(c, Rng(31).Stream("imu"), false);
  const double dt = 0.1, sigma = c.gyro.bias_instability, tc = 10.0;
  const std::vector<AllanPoint> curve = OverlappingAllanDeviation(StaticRates(&m, dt, 144000, false), dt);
  for (const AllanPoint& p : curve) {
    if (p.clusters < kMinFitClusters) continue;
    const double u = p.tau_s / tc;
    const double theory = sigma / u * std::sqrt(2.0 * u - 3.0 + 4.0 * std::exp(-u) - std::exp(-2.0 * u));
    EXPECT_NEAR(p.adev / theory, 1.0, 5.0 * AllanRelativeError(p.clusters)) << p.tau_s;
  }
  // The hump (0.617 sigma at 1.89 tau_c) over 0.664 reads 0.93 sigma; the hump points
  // have ~760 clusters (2.6 %): within 20 % of the configured bias instability.
  const AllanNoiseFit fit = FitAllanNoise(curve);
  EXPECT_FALSE(fit.bias_instability_is_bound);
  EXPECT_NEAR(fit.bias_instability / sigma, 1.0, 0.20);
}

TEST(InertialErrorModel, GaussMarkovStaysStationaryWithJitteredIntervals) {
  // Intervals alternate 10 ms / 13 ms (coefficients recomputed each time). The bias
  // variance over 1 h with tau_c = 1 s rests on ~1800 independent values (relative standard
  // error of the variance 3.3 %): within 15 % of sigma^2.
  const InertialErrorConfig c = Parse("accel: {bias_instability_ug: 50, correlation_time_s: 1}\n");
  InertialErrorModel m(c, Rng(41).Stream("imu"), false);
  double t = 0.0, sum_sq = 0.0;
  int n = 0;
  for (int k = 0; t < 3600.0; ++k) {
    const double dt = k % 2 == 0 ? 0.010 : 0.013;
    Eigen::Vector3d dtheta, dv;
    m.Apply(t += dt, dt, 25.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), &dtheta, &dv);
    sum_sq += m.accel().Bias(0.0).squaredNorm() / 3.0;
    ++n;
  }
  EXPECT_NEAR(sum_sq / n / (c.accel.bias_instability * c.accel.bias_instability), 1.0, 0.15);
}

TEST(InertialErrorModel, RateRandomWalkHasSlopePlusHalf) {
  // 1 h at 100 Hz of a rate random walk of 1 (deg/h)/sqrt(h): the Allan slope is +1/2 and
  // the readout at 3 s rests on the short cluster times (thousands of clusters): 10 %.
  const InertialErrorConfig c = Parse("gyro: {rate_random_walk_deg_h_sqrt_h: 1}\n");
  InertialErrorModel m(c, Rng(51).Stream("imu"), false);
  const double dt = 0.01;
  const std::vector<AllanPoint> curve = OverlappingAllanDeviation(StaticRates(&m, dt, 360000, false), dt);
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (const AllanPoint& p : curve) {
    if (p.clusters < 100) continue;
    const double x = std::log(p.tau_s), y = std::log(p.adev);
    sx += x, sy += y, sxx += x * x, sxy += x * y;
    ++n;
  }
  EXPECT_NEAR((n * sxy - sx * sy) / (n * sxx - sx * sx), 0.5, 0.1);  // ~5 standard errors
  EXPECT_NEAR(FitAllanNoise(curve).rate_random_walk / c.gyro.random_walk, 1.0, 0.10);
}

TEST(InertialErrorModel, PerfectAndEmptyConfigsReturnTheTruthExactly) {
  sim::Rng truth_rng(5);
  InertialErrorModel perfect(FullConfig(), Rng(9), true), empty(InertialErrorConfig{}, Rng(9), false);
  for (int k = 1; k <= 1000; ++k) {
    const Eigen::Vector3d dtheta_true = truth_rng.Normal3(0.01), dv_true = truth_rng.Normal3(0.1);
    Eigen::Vector3d a, b, c, d;
    perfect.Apply(k * 0.005, 0.005, 60.0, dtheta_true, dv_true, &a, &b);
    empty.Apply(k * 0.005, 0.005, 60.0, dtheta_true, dv_true, &c, &d);
    ASSERT_EQ(a, dtheta_true);
    ASSERT_EQ(b, dv_true);
    ASSERT_EQ(c, dtheta_true);
    ASSERT_EQ(d, dv_true);
  }
  EXPECT_EQ(perfect.gyro().drawn().bias, Eigen::Vector3d::Zero());
  EXPECT_EQ(perfect.gyro_quantum(), 0.0);
  // errors.yaml of a perfect IMU says so and lists no error, not the configured ones.
  const YAML::Node y = YAML::Load(Emitted(perfect));
  EXPECT_TRUE(y["perfect"].as<bool>());
  EXPECT_EQ(y["gyro"]["arw_deg_sqrt_h"].as<double>(), 0.0);
  EXPECT_EQ(y["accel"]["bias_ug"][0].as<double>(), 0.0);
}

TEST(InertialErrorModel, RejectsTimeThatDoesNotIncrease) {
  InertialErrorModel m(FullConfig(), Rng(1), false);
  Eigen::Vector3d a, b;
  m.Apply(1.0, 0.01, 25.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), &a, &b);
  EXPECT_THROW(m.Apply(1.0, 0.01, 25.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), &a, &b),
               std::invalid_argument);
  EXPECT_THROW(m.Apply(2.0, 0.0, 25.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), &a, &b),
               std::invalid_argument);
}

/// errors.yaml text and 500 steps of output of a model of FullConfig on `rng`.
std::string RunAndRecord(const Rng& rng) {
  InertialErrorModel m(FullConfig(), rng, false);
  std::string out = Emitted(m);
  for (int k = 1; k <= 500; ++k) {
    Eigen::Vector3d a, b;
    m.Apply(k * 0.01, 0.01, 30.0, Eigen::Vector3d(0.01, 0.0, 0.0), Eigen::Vector3d(0.0, 0.0, -0.098), &a, &b);
    out.append(reinterpret_cast<const char*>(a.data()), sizeof(double) * 3);
    out.append(reinterpret_cast<const char*>(b.data()), sizeof(double) * 3);
  }
  return out;
}

TEST(InertialErrorModel, SameSeedSameBytesOtherStreamOtherDraws) {
  const std::string imu = RunAndRecord(Rng(42).Stream("imu"));
  EXPECT_EQ(imu, RunAndRecord(Rng(42).Stream("imu")));
  EXPECT_NE(imu, RunAndRecord(Rng(42).Stream("master")));
  EXPECT_NE(imu, RunAndRecord(Rng(43).Stream("imu")));
  const InertialErrorModel a(FullConfig(), Rng(42).Stream("imu"), false);
  const InertialErrorModel b(FullConfig(), Rng(42).Stream("master"), false);
  for (int i = 0; i < 3; ++i) EXPECT_NE(a.gyro().drawn().bias[i], b.gyro().drawn().bias[i]);
}

TEST(InertialErrorModel, SwitchingOneSourceOffLeavesTheOtherDraws) {
  InertialErrorConfig without_bias = FullConfig();
  without_bias.gyro.bias.sigma = 0.0;
  const InertialErrorModel a(FullConfig(), Rng(8), false), b(without_bias, Rng(8), false);
  EXPECT_EQ(b.gyro().drawn().bias, Eigen::Vector3d::Zero());
  EXPECT_EQ(a.gyro().drawn().scale_factor, b.gyro().drawn().scale_factor);
  EXPECT_EQ(a.gyro().drawn().misalignment, b.gyro().drawn().misalignment);
  EXPECT_EQ(a.gyro().drawn().bias_instability_initial, b.gyro().drawn().bias_instability_initial);
  EXPECT_EQ(a.accel().drawn().bias, b.accel().drawn().bias);
  EXPECT_EQ(a.g_sensitivity(), b.g_sensitivity());
}

TEST(InertialErrorModel, ErrorsYamlListsTheDrawnValuesInTheirUnits) {
  const InertialErrorModel m(FullConfig(), Rng(4).Stream("imu"), false);
  const YAML::Node y = YAML::Load(Emitted(m));
  // The emitter writes 17 significant digits; 1e-12 relative is plenty.
  const auto near = [](double a, double b) { EXPECT_NEAR(a, b, 1e-12 * std::abs(b)); };
  EXPECT_FALSE(y["perfect"].as<bool>());
  near(y["gyro"]["bias_deg_h"][1].as<double>(), m.gyro().drawn().bias[1] / kDegPerHour_radps);
  near(y["gyro"]["misalignment_arcsec"][0][2].as<double>(), m.gyro().drawn().misalignment(0, 2) / kArcsec_rad);
  EXPECT_EQ(y["gyro"]["misalignment_arcsec"][1][1].as<double>(), 0.0);
  near(y["gyro"]["scale_factor_ppm"][2].as<double>(), m.gyro().drawn().scale_factor[2] / 1e-6);
  near(y["gyro"]["arw_deg_sqrt_h"].as<double>(), 0.2);
  near(y["gyro"]["bias_instability_initial_deg_h"][0].as<double>(),
       m.gyro().drawn().bias_instability_initial[0] / kDegPerHour_radps);
  near(y["gyro"]["temperature"]["bias_deg_h_per_degC2"][0].as<double>(), m.gyro().drawn().bias_per_degC2[0] / kDegPerHour_radps);
  near(y["accel"]["bias_ug"][0].as<double>(), m.accel().drawn().bias[0] / kMicroG_mps2);
  near(y["accel"]["vrw_m_s_sqrt_h"].as<double>(), 0.05);
  near(y["accel"]["acceleration_random_walk_ug_sqrt_h"].as<double>(), 5.0);
  near(y["g_sensitivity_deg_h_per_g"][2][1].as<double>(), m.g_sensitivity()(2, 1) / (kDegPerHour_radps / 9.80665));
  near(y["temperature_profile"]["final_degC"].as<double>(), 40.0);
}

TEST(Quantizer, ErrorIsWithinOneQuantumAndDoesNotAccumulate) {
  const double q = 1e-4;
  Quantizer quantizer(q);
  sim::Rng rng(77);
  Eigen::Vector3d sum_in = Eigen::Vector3d::Zero(), sum_out = Eigen::Vector3d::Zero();
  for (int k = 0; k < 100000; ++k) {
    const Eigen::Vector3d in(rng.Uniform(-0.005, 0.005), rng.Uniform(0.0, 3e-4), 2.3e-5);
    const Eigen::Vector3d out = quantizer.Apply(in);
    sum_in += in;
    sum_out += out;
    for (int i = 0; i < 3; ++i) {
      // Whole quanta, each output within one quantum of its input, and the carried
      // residual (sum of inputs - sum of outputs) within half a quantum; 1e-9 q allows for
      // rounding.
      ASSERT_NEAR(out[i] / q, std::round(out[i] / q), 1e-6);
      ASSERT_LE(std::abs(out[i] - in[i]), q * (1.0 + 1e-9));
      ASSERT_LE(std::abs(quantizer.residual()[i]), q * (0.5 + 1e-9));
    }
  }
  // The residual is what the sums differ by (1e-9 covers the rounding of these sums of
  // 1e5 terms of at most 5e-3), so the error does not grow with time.
  EXPECT_LT((sum_in - sum_out - quantizer.residual()).cwiseAbs().maxCoeff(), 1e-9);
  // A constant input of 0.23 quanta comes out as whole quanta at the right mean rate.
  EXPECT_NEAR(sum_out[2] / 100000, 2.3e-5, q / 100000);
  EXPECT_EQ(Quantizer(0.0).Apply(Eigen::Vector3d(1e-9, 2e-9, 3e-9)), Eigen::Vector3d(1e-9, 2e-9, 3e-9));
}

}  // namespace sim_inertial_errors_test
}  // namespace navtwin::sim
