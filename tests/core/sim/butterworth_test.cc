#include "core/sim/butterworth.h"

#include <cmath>
#include <complex>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/input_error.h"
#include "core/sim/random.h"
#include "core/sim/vibration.h"

namespace navtwin::sim {
namespace sim_butterworth_test {

// Seed 001: 4th-order Butterworth at 50 Hz sampled at 1.6 kHz.
constexpr double kCutoffHz = 50.0;
constexpr double kInternalHz = 1600.0;

double Db(double gain) { return 20.0 * std::log10(gain); }

// The magnitude the bilinear transform predicts: the analog Butterworth response at the
// warped frequency tan(pi f / fs) / tan(pi fc / fs) (in units of the cutoff).
double WarpedMagnitude(double f_hz) {
  const double r = std::tan(M_PI * f_hz / kInternalHz) / std::tan(M_PI * kCutoffHz / kInternalHz);
  return 1.0 / std::sqrt(1.0 + std::pow(r, 8));
}

double AnalogMagnitude(double f_hz) { return 1.0 / std::sqrt(1.0 + std::pow(f_hz / kCutoffHz, 8)); }

// Complex DFT coefficient of x at `cycles` cycles per record (amplitude scaling 2/N).
std::complex<double> DftAmplitude(const std::vector<double>& x, double cycles) {
  std::complex<double> sum = 0.0;
  const double n = static_cast<double>(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    sum += x[k] * std::polar(1.0, -2.0 * M_PI * cycles * static_cast<double>(k) / n);
  }
  return 2.0 * sum / n;
}

TEST(Butterworth4, MinusThreeDbAtTheCutoff) {
  const Butterworth4<double> filter(kCutoffHz, kInternalHz);
  // Pre-warping maps the cutoff exactly: |H(fc)| = 1/sqrt(2) up to rounding (1e-9 dB).
  EXPECT_NEAR(Db(std::abs(filter.Response(kCutoffHz))), -3.0103, 1e-4);
  EXPECT_NEAR(std::abs(filter.Response(kCutoffHz)), std::sqrt(0.5), 1e-12);
}

TEST(Butterworth4, UnitGainAndZeroPhaseAtDc) {
  const Butterworth4<double> filter(kCutoffHz, kInternalHz);
  // Exact in exact arithmetic (b0 + b1 + b2 = 1 + a1 + a2); 1e-12 allows rounding.
  EXPECT_NEAR(std::abs(filter.Response(0.0)), 1.0, 1e-12);
  EXPECT_NEAR(std::arg(filter.Response(0.0)), 0.0, 1e-12);
}

TEST(Butterworth4, ResponseIsTheWarpedButterworthMagnitude) {
  const Butterworth4<double> filter(kCutoffHz, kInternalHz);
  // At 2 fc the analog filter has 1/sqrt(1 + 2^8) = -24.10 dB; bilinear warping compresses
  // the frequency axis near Nyquist, so the digital filter has -24.44 dB (0.34 dB more).
  EXPECT_NEAR(Db(AnalogMagnitude(2.0 * kCutoffHz)), -24.10, 0.01);
  EXPECT_NEAR(Db(std::abs(filter.Response(2.0 * kCutoffHz))), -24.44, 0.01);
  EXPECT_LT(std::abs(filter.Response(2.0 * kCutoffHz)), AnalogMagnitude(2.0 * kCutoffHz));
  // The whole band 0..fs/2 follows the warped formula (1e-10 relative: rounding only).
  for (double f_hz = 1.0; f_hz < 0.5 * kInternalHz; f_hz += 7.0) {
    const double gain = std::abs(filter.Response(f_hz));
    EXPECT_NEAR(gain / WarpedMagnitude(f_hz), 1.0, 1e-10) << f_hz << " Hz";
  }
}

TEST(Butterworth4, FilteredSinusoidsHaveThePredictedGainAndPhase) {
  for (const double f_hz : {5.0, 30.0, 50.0, 190.0}) {
    Butterworth4<double> filter(kCutoffHz, kInternalHz);
    std::vector<double> in, out;
    // 1 s to let the transient die (slowest pole decays as exp(-120 t)), then 1 s analysed,
    // a whole number of periods for every test frequency.
    for (int n = 0; n < 3200; ++n) {
      const double x = std::sin(2.0 * M_PI * f_hz * n / kInternalHz + 0.3);
      const double y = filter.Filter(x);
      if (n >= 1600) {
        in.push_back(x);
        out.push_back(y);
      }
    }
    const std::complex<double> measured = DftAmplitude(out, f_hz) / DftAmplitude(in, f_hz);
    // The steady-state output equals the response at f up to rounding and the transient
    // left after 1 s (exp(-120) ~ 1e-52): 1e-9 absolute on the complex gain.
    EXPECT_NEAR(std::abs(measured - filter.Response(f_hz)), 0.0, 1e-9) << f_hz << " Hz";
  }
}

TEST(Butterworth4, StepResponseOvershootsLikeAButterworthAndSettles) {
  Butterworth4<double> filter(kCutoffHz, kInternalHz);
  double peak = 0.0, late_error = 0.0;
  for (int n = 0; n < 1600; ++n) {
    const double y = filter.Filter(1.0);
    peak = std::max(peak, y);
    if (n >= 400) late_error = std::max(late_error, std::abs(y - 1.0));
  }
  // The analog 4th-order Butterworth overshoots by 10.8 %; warping at fc = fs/32 changes
  // it by a fraction of a percent, so [9 %, 12.5 %].
  EXPECT_GT(peak, 1.09);
  EXPECT_LT(peak, 1.125);
  // After 0.25 s the slowest pole (decay 2 pi fc cos(3 pi / 8) = 120 /s) has shrunk by
  // exp(-30): settled to 1e-9.
  EXPECT_LT(late_error, 1e-9);
}

TEST(Butterworth4, ResetStartsInTheSteadyStateOfAConstant) {
  Butterworth4 filter(kCutoffHz, kInternalHz);  // three axes by default
  const Eigen::Vector3d x(0.01, -0.2, -9.8);
  filter.Reset(x);
  for (int n = 0; n < 100; ++n) {
    // No transient at all (a wrong start state leaves one of order |x|): equal up to rounding.
    // At the fixed point each update rounds the same way, terms up to ~2 |x|, and that constant
    // error passes each section's recursion with its DC gain d / (4 k^2) ~ 30 (k = tan(pi fc /
    // fs) = 0.098): at most some hundred eps |x| (eps |x| = 2.2e-15 m/s^2). Measured: 4.9e-15
    // m/s^2 (Release), 1.01e-13 with fused multiply-adds (-march=native). Bound 1e-12, ~460 eps |x|.
    EXPECT_NEAR((filter.Filter(x) - x).norm(), 0.0, 1e-12);
  }
}

TEST(Butterworth4, VectorFilterEqualsThreeScalarFilters) {
  Butterworth4<Eigen::Vector3d> vector_filter(kCutoffHz, kInternalHz);
  std::vector<Butterworth4<double>> scalar(3, Butterworth4<double>(kCutoffHz, kInternalHz));
  Rng rng(7);
  for (int n = 0; n < 500; ++n) {
    const Eigen::Vector3d x = rng.Normal3(1.0);
    const Eigen::Vector3d y = vector_filter.Filter(x);
    // Same arithmetic per channel; 1e-14 allows a different contraction into fma.
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(y[i], scalar[i].Filter(x[i]), 1e-14);
  }
}

TEST(Butterworth4, GroupDelayAtDc) {
  const Butterworth4<double> filter(kCutoffHz, kInternalHz);
  const double tau_s = filter.GroupDelayAtDc_s();
  // Phase is -omega tau (1 + O((f/fc)^2)) near DC: at 1 mHz the cubic term is ~5e-13 s
  // and rounding of the 5e-5 rad phase ~2e-13 s, so the slope matches to 1e-12 s.
  const double f_hz = 0.001;
  EXPECT_NEAR(-std::arg(filter.Response(f_hz)) / (2.0 * M_PI * f_hz), tau_s, 1e-12);
  // The bilinear map Omega = (omega_c / K) tan(omega T / 2) scales the analog delay by
  // dOmega/domega at 0, x / tan(x) with x = pi fc / fs (0.99679 here): 1e-12 relative.
  const double analog_s = AnalogButterworth4GroupDelay_s(kCutoffHz);
  const double x = M_PI * kCutoffHz / kInternalHz;
  EXPECT_NEAR(tau_s / (analog_s * x / std::tan(x)), 1.0, 1e-12);
  // 2.6131 / (2 pi 50 Hz) = 8.318 ms analog, 8.291 ms digital (0.001 ms: printed digits).
  EXPECT_NEAR(analog_s * 1e3, 8.318, 1e-3);
  EXPECT_NEAR(tau_s * 1e3, 8.291, 1e-3);
}

TEST(Butterworth4, RejectsACutoffOutsideTheBand) {
  EXPECT_THROW(Butterworth4<double>(800.0, 1600.0), std::invalid_argument);
  EXPECT_THROW(Butterworth4<double>(0.0, 1600.0), std::invalid_argument);
  EXPECT_THROW(Butterworth4<double>(50.0, 0.0), std::invalid_argument);
  EXPECT_NO_THROW(Butterworth4<double>(799.0, 1600.0));
}

TEST(AliasFrequency, FoldsIntoTheFirstNyquistZone) {
  EXPECT_DOUBLE_EQ(AliasFrequencyHz(190.0, 200.0), 10.0);
  EXPECT_DOUBLE_EQ(AliasFrequencyHz(210.0, 200.0), 10.0);
  EXPECT_DOUBLE_EQ(AliasFrequencyHz(390.0, 200.0), 10.0);
  EXPECT_DOUBLE_EQ(AliasFrequencyHz(23.0, 600.0), 23.0);
  EXPECT_DOUBLE_EQ(AliasFrequencyHz(100.0, 200.0), 100.0);
  EXPECT_DOUBLE_EQ(AliasFrequencyHz(400.0, 200.0), 0.0);
  EXPECT_DOUBLE_EQ(AliasFrequencyHz(-170.0, 200.0), 30.0);
  EXPECT_THROW(AliasFrequencyHz(10.0, 0.0), std::invalid_argument);
  EXPECT_THROW(AliasFrequencyHz(NAN, 200.0), std::invalid_argument);
}

ConfigNode AntiAliasNode(const std::string& yaml) {
  return ParseYaml(yaml, "scenario.yaml").Child("imu").Child("anti_alias");
}

TEST(AntiAliasConfig, ParsesTheSection) {
  const AntiAliasConfig none = ParseAntiAliasConfig(AntiAliasNode("imu: {rate_hz: 200}\n"), 200.0);
  EXPECT_FALSE(none.enabled);
  EXPECT_EQ(none.oversample, 1);

  const AntiAliasConfig on = ParseAntiAliasConfig(
      AntiAliasNode("imu:\n  anti_alias: {cutoff_hz: 50, oversample: 8}\n"), 200.0);
  EXPECT_TRUE(on.enabled);
  EXPECT_EQ(on.cutoff_hz, 50.0);
  EXPECT_EQ(on.oversample, 8);

  const AntiAliasConfig off = ParseAntiAliasConfig(
      AntiAliasNode("imu:\n  anti_alias: {enabled: false, oversample: 8}\n"), 200.0);
  EXPECT_FALSE(off.enabled);
  EXPECT_EQ(off.oversample, 8);
}

TEST(AntiAliasConfig, RejectsBadSections) {
  const auto expect_error = [](const std::string& yaml, const std::string& field) {
    try {
      ParseAntiAliasConfig(AntiAliasNode(yaml), 200.0);
      ADD_FAILURE() << "no error for " << yaml;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "scenario.yaml");
      EXPECT_EQ(e.line(), 3) << e.what();
      EXPECT_EQ(e.field(), field) << e.what();
    }
  };
  const std::string head = "imu:\n  anti_alias:\n";
  expect_error(head + "    oversample: 8\n", "imu.anti_alias.cutoff_hz");
  expect_error(head + "    cutoff_hz: 0\n", "imu.anti_alias.cutoff_hz");
  // 200 Hz x 8 = 1600 Hz internal: the cutoff must be below 800 Hz.
  expect_error(head + "    cutoff_hz: 800\n    oversample: 8\n", "imu.anti_alias.cutoff_hz");
  expect_error(head + "    oversample: 0\n", "imu.anti_alias.oversample");
  expect_error(head + "    cutoff: 50\n", "imu.anti_alias.cutoff");
}

// The aliasing demonstration. A 190 Hz, 1 g specific-force tone (plus a 2 Hz, 0.1 g
// "motion" tone) is integrated exactly over 1600 Hz internal intervals, then either
// (a) summed 8 at a time into 200 Hz IMU increments, or (b) low-pass filtered at 50 Hz
// first. Summing the exact internal increments gives the exact integral over the 5 ms output
// interval, a boxcar whose response is sinc(f T) = sin(pi f T)/(pi f T); the output, sampled
// at 200 Hz, shows the 190 Hz tone at AliasFrequencyHz(190, 200) = 10 Hz with amplitude
// A |sinc(0.95)| = 0.0524 A. The filter multiplies that by |H(190 Hz)| (-47.9 dB).
struct AliasRun {
  std::vector<double> unfiltered_mps2;  // mean specific force per 5 ms output interval
  std::vector<double> filtered_mps2;
};

AliasRun RunAliasDemonstration(double tone_hz, double seconds) {
  VibrationConfig config;
  VibrationToneConfig tone;
  tone.axes = {{true, false, false}};
  tone.frequency_hz = {tone_hz, tone_hz};
  tone.linear_mps2 = 1.0 * kStandardGravity_mps2;
  tone.random_amplitude = false;
  VibrationToneConfig motion = tone;
  motion.frequency_hz = {2.0, 2.0};
  motion.linear_mps2 = 0.1 * kStandardGravity_mps2;
  config.tones = {tone, motion};
  const VibrationModel vibration(config, Rng(1), false);

  constexpr int kOversample = 8;
  constexpr double kOutputHz = kInternalHz / kOversample;
  Butterworth4 filter(kCutoffHz, kInternalHz);
  AliasRun run;
  Eigen::Vector3d sum_a = Eigen::Vector3d::Zero(), sum_b = Eigen::Vector3d::Zero();
  const int internal_steps = static_cast<int>(seconds * kInternalHz);
  for (int n = 0; n < internal_steps; ++n) {
    Eigen::Vector3d dtheta_rad, dv_mps;
    vibration.Increment(n / kInternalHz, (n + 1) / kInternalHz, &dtheta_rad, &dv_mps);
    sum_a += dv_mps;
    sum_b += filter.Filter(dv_mps);
    if ((n + 1) % kOversample == 0) {
      run.unfiltered_mps2.push_back(sum_a.x() * kOutputHz);
      run.filtered_mps2.push_back(sum_b.x() * kOutputHz);
      sum_a.setZero();
      sum_b.setZero();
    }
  }
  return run;
}

TEST(AntiAliasDemonstration, ToneAboveNyquistAliasesWithoutTheFilterAndIsAttenuatedWithIt) {
  constexpr double kOutputHz = 200.0, kRecordS = 2.0, kMotionHz = 2.0;
  const Butterworth4<double> filter(kCutoffHz, kInternalHz);
  for (const double tone_hz : {190.0, 170.0, 230.0, 390.0}) {
    SCOPED_TRACE(tone_hz);
    const AliasRun run = RunAliasDemonstration(tone_hz, 1.0 + kRecordS);
    // The last 2 s (400 outputs, 0.5 Hz bins): the first second holds the filter's start
    // transient. Both tones complete whole cycles in the record, so there is no leakage.
    const std::vector<double> a(run.unfiltered_mps2.end() - 400, run.unfiltered_mps2.end());
    const std::vector<double> b(run.filtered_mps2.end() - 400, run.filtered_mps2.end());
    const double alias_hz = AliasFrequencyHz(tone_hz, kOutputHz);
    const int alias_bin = static_cast<int>(std::lround(alias_hz * kRecordS));
    const int motion_bin = static_cast<int>(kMotionHz * kRecordS);

    // (a) The spectrum holds the alias and the motion tone and nothing else (1e-9 m/s^2:
    // rounding of the sums; a wrong alias frequency leaves ~0.5 m/s^2 in another bin).
    for (int m = 0; m <= 200; ++m) {
      if (m != alias_bin && m != motion_bin) {
        EXPECT_LT(std::abs(DftAmplitude(a, m)), 1e-9) << "bin " << m * 0.5 << " Hz";
      }
    }
    // Its amplitude is A |sinc(f T)| with A = 1 g, T = 5 ms (1e-9 relative: rounding).
    const double x = M_PI * tone_hz / kOutputHz;
    const double alias_a = std::abs(DftAmplitude(a, alias_bin));
    EXPECT_NEAR(alias_a / (kStandardGravity_mps2 * std::abs(std::sin(x) / x)), 1.0, 1e-9);

    // (b) The filter scales the alias by |H(f)| at the internal rate (1e-6 relative: the
    // start transient after 1 s is below 1e-50) and meets at least the analog
    // Butterworth's stop-band attenuation at f.
    const double alias_b = std::abs(DftAmplitude(b, alias_bin));
    EXPECT_NEAR(alias_b / alias_a / std::abs(filter.Response(tone_hz)), 1.0, 1e-6);
    EXPECT_LT(alias_b / alias_a, AnalogMagnitude(tone_hz));
    // The 2 Hz motion passes: |H(2 Hz)| = 1 - 4e-12.
    EXPECT_NEAR(std::abs(DftAmplitude(b, motion_bin)) / std::abs(DftAmplitude(a, motion_bin)),
                1.0, 1e-9);
    const std::string name = "alias_" + std::to_string(static_cast<int>(tone_hz));
    RecordProperty(name + "_unfiltered_mps2", ::testing::PrintToString(alias_a));
    RecordProperty(name + "_filtered_mps2", ::testing::PrintToString(alias_b));
  }
}

}  // namespace sim_butterworth_test
}  // namespace navtwin::sim
