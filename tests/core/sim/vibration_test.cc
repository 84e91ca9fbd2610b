#include "core/sim/vibration.h"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/input_error.h"
#include "core/rotation.h"

namespace navtwin::sim {
namespace sim_vibration_test {

// Two groups: a seed-000-like rotor tone on all axes with two harmonics, and a fixed
// angular tone on y and z whose second harmonic reaches 420 Hz.
VibrationConfig MixedConfig() {
  VibrationToneConfig rotor;
  rotor.axes = {{true, true, true}};
  rotor.frequency_hz = {22.0, 24.0};
  rotor.linear_mps2 = 1.0 * kStandardGravity_mps2;
  rotor.harmonic_gains = {1.0, 0.5};
  VibrationToneConfig angular;
  angular.axes = {{false, true, true}};
  angular.frequency_hz = {150.0, 210.0};
  angular.linear_mps2 = 0.2 * kStandardGravity_mps2;
  angular.angular_radps = 2.0 * kDegToRad;
  angular.random_amplitude = false;
  angular.harmonic_gains = {1.0, 0.3};
  VibrationConfig config;
  config.tones = {rotor, angular};
  return config;
}

// Composite 5-point Gauss-Legendre quadrature of the model's rate over (t0, t1].
void IntegrateRate(const VibrationModel& model, double t0, double t1, int pieces,
                   Eigen::Vector3d* dtheta, Eigen::Vector3d* dv) {
  const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                       0.9061798459386640};
  const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                       0.4786286704993665, 0.2369268850561891};
  dtheta->setZero();
  dv->setZero();
  const double h = (t1 - t0) / pieces;
  for (int p = 0; p < pieces; ++p) {
    const double mid = t0 + (p + 0.5) * h;
    for (int i = 0; i < 5; ++i) {
      Eigen::Vector3d omega, f;
      model.Rate(mid + 0.5 * h * x[i], &omega, &f);
      *dtheta += 0.5 * h * w[i] * omega;
      *dv += 0.5 * h * w[i] * f;
    }
  }
}

TEST(Vibration, IncrementIsTheExactIntegralOfTheRate) {
  const VibrationModel model(MixedConfig(), Rng(42), false);
  ASSERT_EQ(model.tones().size(), 3u * 2u + 2u * 2u * 2u);
  // One internal interval at 1.6 kHz, one of several periods, and one later in the run.
  const double intervals[3][2] = {{1.234, 1.234 + 1.0 / 1600.0}, {0.0, 0.1}, {10.0, 10.005}};
  for (const auto& interval : intervals) {
    Eigen::Vector3d dtheta, dv, dtheta_q, dv_q;
    model.Increment(interval[0], interval[1], &dtheta, &dv);
    // 4096 pieces put < 0.02 cycles of the fastest tone (420 Hz) in each piece, where the
    // 5-point rule is exact to ~1e-20: the comparison measures the closed form.
    IntegrateRate(model, interval[0], interval[1], 4096, &dtheta_q, &dv_q);
    ASSERT_GT(dtheta.norm(), 0.0);
    // The bound: 1e-12 relative.
    EXPECT_LT((dtheta - dtheta_q).norm(), 1e-12 * dtheta.norm()) << interval[0];
    EXPECT_LT((dv - dv_q).norm(), 1e-12 * dv.norm()) << interval[0];
  }
}

// After an hour the phase 2 pi f t of a 420 Hz tone is ~1e7 rad, where a plain double
// product loses ~1e-9 rad. The model keeps the cycle count exact; compare with a
// long-double evaluation of the same closed form (64-bit mantissa on x86-64: ~1e-12 rad).
TEST(Vibration, PhaseStaysExactAfterOneHour) {
  static_assert(std::numeric_limits<long double>::digits >= 64, "needs extended long double");
  const VibrationModel model(MixedConfig(), Rng(42), false);
  const double t0 = 3600.0 + 1.0 / 3.0, t1 = t0 + 1.0 / 1600.0;
  Eigen::Vector3d dtheta, dv;
  model.Increment(t0, t1, &dtheta, &dv);
  Eigen::Vector3d dtheta_ref = Eigen::Vector3d::Zero(), dv_ref = Eigen::Vector3d::Zero();
  for (const VibrationTone& tone : model.tones()) {
    const long double pi = 3.141592653589793238462643383279502884L;
    const long double f = tone.frequency_hz, dt = static_cast<long double>(t1) - t0;
    const long double mid = static_cast<long double>(t0) + dt / 2;
    const long double value = tone.amplitude / (pi * f) *
                              std::sin(2 * pi * f * mid + tone.phase_rad) * std::sin(pi * f * dt);
    (tone.angular ? dtheta_ref : dv_ref)[tone.axis] += static_cast<double>(value);
  }
  // 1e-10 relative: the long-double reference is good to ~1e-12, a plain double phase
  // would be off by ~1e-9.
  EXPECT_LT((dtheta - dtheta_ref).norm(), 1e-10 * dtheta.norm());
  EXPECT_LT((dv - dv_ref).norm(), 1e-10 * dv.norm());
}

TEST(Vibration, DrawnValuesHaveTheConfiguredDistributions) {
  VibrationToneConfig rotor;
  rotor.axes = {{true, true, true}};
  rotor.frequency_hz = {22.0, 24.0};
  rotor.linear_mps2 = 1.0 * kStandardGravity_mps2;
  VibrationConfig config;
  config.tones = {rotor};
  std::vector<double> amplitudes_g, frequencies_hz, phases_rad;
  for (std::uint64_t seed = 1; seed <= 2000; ++seed) {
    const VibrationModel model(config, Rng(seed), false);
    ASSERT_EQ(model.tones().size(), 3u);
    for (const VibrationTone& tone : model.tones()) {
      amplitudes_g.push_back(tone.amplitude / kStandardGravity_mps2);
      phases_rad.push_back(tone.phase_rad);
      EXPECT_GE(tone.frequency_hz, 22.0);
      EXPECT_LE(tone.frequency_hz, 24.0);
      EXPECT_GE(tone.phase_rad, 0.0);
      EXPECT_LT(tone.phase_rad, 2.0 * M_PI);
    }
    EXPECT_EQ(model.tones()[0].frequency_hz, model.tones()[2].frequency_hz);
    frequencies_hz.push_back(model.tones()[0].frequency_hz);
  }
  const auto mean = [](const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return s / static_cast<double>(v.size());
  };
  const double n = static_cast<double>(amplitudes_g.size());  // 6000 amplitudes
  double sum_sq = 0.0, within_sigma = 0.0;
  for (double a : amplitudes_g) {
    sum_sq += a * a;
    within_sigma += std::abs(a) < 1.0 ? 1.0 : 0.0;
  }
  // Tolerances are 4 standard errors of each estimate for the fixed seeds 1..2000:
  // mean of N(0, 1): 1/sqrt(n) = 0.013; rms: 1/sqrt(2n) = 0.0091; P(|a| < sigma) = 0.6827:
  // sqrt(p(1-p)/n) = 0.0060 (distinguishes a normal from e.g. a uniform draw, 0.577).
  EXPECT_NEAR(mean(amplitudes_g), 0.0, 4 * 0.013);
  EXPECT_NEAR(std::sqrt(sum_sq / n), 1.0, 4 * 0.0091);
  EXPECT_NEAR(within_sigma / n, 0.6827, 4 * 0.0060);
  // Uniform frequency in [22, 24]: sd 2/sqrt(12) = 0.577, mean's error 0.577/sqrt(2000).
  EXPECT_NEAR(mean(frequencies_hz), 23.0, 4 * 0.577 / std::sqrt(2000.0));
  // Uniform phase: sd 2 pi/sqrt(12) = 1.81, mean's error 1.81/sqrt(6000).
  EXPECT_NEAR(mean(phases_rad), M_PI, 4 * 1.81 / std::sqrt(n));
}

TEST(Vibration, FixedAmplitudesAndHarmonics) {
  VibrationToneConfig group;
  group.axes = {{true, false, true}};
  group.frequency_hz = {100.0, 110.0};
  group.linear_mps2 = 0.5 * kStandardGravity_mps2;
  group.angular_radps = 3.0 * kDegToRad;
  group.random_amplitude = false;
  group.harmonic_gains = {1.0, 1.0 / 2.0, 1.0 / 3.0};
  VibrationConfig config;
  config.tones = {group};
  const VibrationModel model(config, Rng(3), false);
  ASSERT_EQ(model.tones().size(), 2u * 2u * 3u);
  const double f1 = model.tones()[0].frequency_hz;
  for (const VibrationTone& tone : model.tones()) {
    EXPECT_EQ(tone.frequency_hz, tone.harmonic * f1);
    EXPECT_TRUE(tone.axis == 0 || tone.axis == 2);
    const double expected = tone.angular ? 3.0 * kDegToRad : 0.5 * kStandardGravity_mps2;
    EXPECT_NEAR(tone.amplitude, expected / tone.harmonic, 1e-15 * expected);
  }
}

TEST(Vibration, PerfectAndEmptyConfigurationsGiveNoVibration) {
  for (const VibrationModel& model :
       {VibrationModel(MixedConfig(), Rng(1), true), VibrationModel(VibrationConfig(), Rng(1), false),
        VibrationModel()}) {
    EXPECT_TRUE(model.tones().empty());
    Eigen::Vector3d dtheta = Eigen::Vector3d::Ones(), dv = Eigen::Vector3d::Ones();
    model.Increment(1.0, 1.01, &dtheta, &dv);
    EXPECT_EQ(dtheta, Eigen::Vector3d::Zero());
    EXPECT_EQ(dv, Eigen::Vector3d::Zero());
  }
}

TEST(Vibration, EachGroupAndKindDrawsFromItsOwnStream) {
  VibrationConfig linear_only = MixedConfig();
  linear_only.tones[1].angular_radps = 0.0 * kDegToRad;
  VibrationConfig first_only = MixedConfig();
  first_only.tones.pop_back();
  const VibrationModel full(MixedConfig(), Rng(5), false);
  const VibrationModel without_angular(linear_only, Rng(5), false);
  const VibrationModel without_second(first_only, Rng(5), false);
  // Removing the angular tones or the second group leaves the other draws unchanged.
  std::vector<VibrationTone> linear;
  for (const VibrationTone& t : full.tones()) {
    if (!t.angular) linear.push_back(t);
  }
  ASSERT_EQ(linear.size(), without_angular.tones().size());
  for (std::size_t i = 0; i < linear.size(); ++i) {
    EXPECT_EQ(linear[i].amplitude, without_angular.tones()[i].amplitude);
    EXPECT_EQ(linear[i].phase_rad, without_angular.tones()[i].phase_rad);
    EXPECT_EQ(linear[i].frequency_hz, without_angular.tones()[i].frequency_hz);
  }
  for (std::size_t i = 0; i < without_second.tones().size(); ++i) {
    EXPECT_EQ(full.tones()[i].amplitude, without_second.tones()[i].amplitude);
    EXPECT_EQ(full.tones()[i].phase_rad, without_second.tones()[i].phase_rad);
  }
  // A different seed draws different values.
  EXPECT_NE(VibrationModel(MixedConfig(), Rng(6), false).tones()[0].amplitude,
            full.tones()[0].amplitude);
}

// Seed 000's experiment: 1 g (1 sigma) vibration at 22-24 Hz on x, uniform phase, level
// IMU, plain average of 0.2 s. The mean of the 600 Hz increments is the integral over the
// window divided by 0.2 s; the published pitch RMS error of the plain average is 2.4957 deg.
TEST(Vibration, SeedZeroPlainAverageErrorMatchesThePublishedRms) {
  VibrationToneConfig rotor;
  rotor.axes = {{true, false, false}};
  rotor.frequency_hz = {22.0, 24.0};
  rotor.linear_mps2 = 1.0 * kStandardGravity_mps2;
  VibrationConfig config;
  config.tones = {rotor};
  double sum_sq = 0.0;
  constexpr int kRuns = 10000;
  for (int run = 0; run < kRuns; ++run) {
    const VibrationModel model(config, Rng(1000 + run), false);
    Eigen::Vector3d dtheta, dv;
    model.Increment(0.0, 0.2, &dtheta, &dv);
    // Level: f = (0, 0, -g) + vibration; pitch = atan2(f_x, sqrt(f_y^2 + f_z^2)).
    const double pitch = std::atan2(dv.x() / 0.2, kStandardGravity_mps2);
    sum_sq += pitch * pitch;
  }
  const double rms_deg = std::sqrt(sum_sq / kRuns) * kRadToDeg;
  // The model's expectation is 2.533 deg (average of (1 - cos x)/x^2, x = 2 pi f 0.2 s,
  // over f); each 10,000-run Monte Carlo has a 1 % standard error, and the published run
  // also had +-50 mg noise and irregularly varying frequency: 5 % around 2.4957 deg. An
  // amplitude read as peak-to-peak or RMS instead of 1 sigma would be off by 30-100 %.
  EXPECT_NEAR(rms_deg / 2.4957, 1.0, 0.05);
  RecordProperty("plain_average_pitch_rms_deg", ::testing::PrintToString(rms_deg));
}

ConfigNode VibrationNode(const std::string& yaml) {
  return ParseYaml(yaml, "scenario.yaml").Child("imu").Child("vibration");
}

TEST(VibrationConfig, ParsesTheSchema) {
  const VibrationConfig config = ParseVibrationConfig(VibrationNode(
      "imu:\n"
      "  vibration:\n"
      "    tones:\n"
      "      - axes: [x]\n"
      "        frequency_hz: [22, 24]\n"
      "        linear_g: 1.0\n"
      "      - axes: [z, y]\n"
      "        frequency_hz: [150, 160]\n"
      "        angular_deg_s: 2.5\n"
      "        amplitude: fixed\n"
      "        harmonics: 3\n"
      "      - axes: [y]\n"
      "        frequency_hz: [40, 40]\n"
      "        linear_g: 0.1\n"
      "        harmonic_gains: [1, 0.25]\n"));
  ASSERT_EQ(config.tones.size(), 3u);
  const VibrationToneConfig& a = config.tones[0];
  EXPECT_TRUE(a.axes[0] && !a.axes[1] && !a.axes[2]);
  EXPECT_EQ(a.frequency_hz, Eigen::Vector2d(22.0, 24.0));
  EXPECT_EQ(a.linear_mps2, 1.0 * kStandardGravity_mps2);
  EXPECT_EQ(a.angular_radps, 0.0);
  EXPECT_TRUE(a.random_amplitude);
  EXPECT_EQ(a.harmonic_gains, std::vector<double>{1.0});
  const VibrationToneConfig& b = config.tones[1];
  EXPECT_TRUE(!b.axes[0] && b.axes[1] && b.axes[2]);
  EXPECT_FALSE(b.random_amplitude);
  EXPECT_EQ(b.angular_radps, 2.5 * kDegPerSecond_radps);
  EXPECT_EQ(b.harmonic_gains, (std::vector<double>{1.0, 0.5, 1.0 / 3.0}));
  EXPECT_EQ(config.tones[2].harmonic_gains, (std::vector<double>{1.0, 0.25}));
  EXPECT_TRUE(ParseVibrationConfig(VibrationNode("imu: {}\n")).tones.empty());
}

TEST(VibrationConfig, RejectsBadTonesNamingLineAndKey) {
  const auto expect_error = [](const std::string& tone_lines, const std::string& field) {
    const std::string yaml = "imu:\n  vibration:\n    tones:\n      - axes: [x]\n" + tone_lines;
    try {
      ParseVibrationConfig(VibrationNode(yaml));
      ADD_FAILURE() << "no error for " << tone_lines;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "imu.vibration.tones[0]." + field) << e.what();
      EXPECT_GE(e.line(), 4) << e.what();
    }
  };
  const std::string range = "        frequency_hz: [22, 24]\n";
  expect_error("        frequency: [22, 24]\n", "frequency");
  expect_error("        linear_g: 1\n", "frequency_hz");
  expect_error("        frequency_hz: [0, 24]\n", "frequency_hz");
  expect_error("        frequency_hz: [24, 22]\n", "frequency_hz");
  expect_error(range + "        linear_g: -1\n", "linear_g");
  expect_error(range + "        amplitude: uniform\n", "amplitude");
  expect_error(range + "        harmonics: 0\n", "harmonics");
  expect_error(range + "        harmonics: 3\n        harmonic_gains: [1, 0.5]\n",
               "harmonic_gains");
  expect_error(range + "        harmonic_gains: [1, -0.5]\n", "harmonic_gains");
}

TEST(VibrationConfig, RejectsBadAxes) {
  for (const std::string axes : {"[w]", "[x, x]", "[]", "x"}) {
    const std::string yaml = "imu:\n  vibration:\n    tones:\n      - axes: " + axes +
                             "\n        frequency_hz: [1, 2]\n";
    try {
      ParseVibrationConfig(VibrationNode(yaml));
      ADD_FAILURE() << "no error for axes " << axes;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "imu.vibration.tones[0].axes") << e.what();
      EXPECT_EQ(e.line(), 4) << e.what();
    }
  }
}

TEST(Vibration, EmitDrawnListsEveryTone) {
  const VibrationModel model(MixedConfig(), Rng(9), false);
  YAML::Emitter out;
  model.EmitDrawn(out);
  ASSERT_TRUE(out.good()) << out.GetLastError();
  const YAML::Node drawn = YAML::Load(out.c_str());
  ASSERT_EQ(drawn["tones"].size(), model.tones().size());
  for (std::size_t i = 0; i < model.tones().size(); ++i) {
    const VibrationTone& tone = model.tones()[i];
    const YAML::Node node = drawn["tones"][i];
    EXPECT_EQ(node["group"].as<int>(), tone.group);
    EXPECT_EQ(node["harmonic"].as<int>(), tone.harmonic);
    EXPECT_EQ(node["axis"].as<std::string>(), std::string(1, "xyz"[tone.axis]));
    EXPECT_EQ(node["kind"].as<std::string>(), tone.angular ? "angular" : "linear");
    // yaml-cpp writes doubles with enough digits to round-trip; 1e-15 relative allows the
    // unit conversion.
    EXPECT_EQ(node["frequency_hz"].as<double>(), tone.frequency_hz);
    EXPECT_EQ(node["phase_rad"].as<double>(), tone.phase_rad);
    const double amplitude = tone.angular ? node["amplitude_deg_s"].as<double>() * kDegToRad
                                          : node["amplitude_g"].as<double>() * kStandardGravity_mps2;
    EXPECT_NEAR(amplitude, tone.amplitude, 1e-15 * std::abs(tone.amplitude));
  }
}

}  // namespace sim_vibration_test
}  // namespace navtwin::sim
