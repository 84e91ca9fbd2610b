// The IMU's anti-alias filter: a 4th-order Butterworth low-pass made of two cascaded
// second-order sections (biquads), designed by the bilinear transform with the cutoff
// pre-warped, so the digital filter has exactly -3.01 dB at the cutoff. The simulator runs
// it at the internal rate (IMU rate x oversample) before decimation; docs/vibration-and-
// aliasing.md gives the design equations and the figures.
//
// Analog prototype (cutoff omega_c = 2 pi f_c), poles at angles pi/8 and 3pi/8 from the
// negative real axis:
//   H(s) = prod_{i=1,2} 1 / (s^2/omega_c^2 + s/(Q_i omega_c) + 1),
//   Q_1 = 1/(2 cos(pi/8)) = 0.5412,  Q_2 = 1/(2 cos(3pi/8)) = 1.3066,
//   |H(j omega)| = 1/sqrt(1 + (omega/omega_c)^8).
// Bilinear transform s = (2/T)(1 - z^-1)/(1 + z^-1) with K = tan(pi f_c T) gives per section
//   b = (K^2, 2K^2, K^2)/d,  a = (1, 2(K^2 - 1)/d, (1 - K/Q + K^2)/d),  d = 1 + K/Q + K^2,
// and the digital response at f is the analog one at tan(pi f T)/K times omega_c.
#pragma once

#include <array>
#include <complex>

#include <Eigen/Core>

#include "core/config/yaml_config.h"

namespace navtwin::sim {

/// One second-order section y = (b0 + b1 z^-1 + b2 z^-2)/(1 + a1 z^-1 + a2 z^-2) x.
struct BiquadCoefficients {
  double b0, b1, b2, a1, a2;
};

/// The two sections of the 4th-order Butterworth low-pass (cutoff_hz at sample_rate_hz).
/// Throws std::invalid_argument unless 0 < cutoff_hz < sample_rate_hz / 2.
std::array<BiquadCoefficients, 2> DesignButterworth4(double cutoff_hz, double sample_rate_hz);

/// Low-frequency group delay of the analog 4th-order Butterworth prototype:
/// sum_i 1/(Q_i omega_c) = 2 (cos(pi/8) + cos(3pi/8)) / omega_c = 2.6131 / omega_c (s).
double AnalogButterworth4GroupDelay_s(double cutoff_hz);

/// A 4th-order Butterworth low-pass filter on a stream of Value (double for one channel,
/// Eigen::Vector3d for the three axes of a sensor triad at once), direct form II
/// transposed. `Butterworth4 f(50.0, 1600.0)` is the three-axis filter.
template <typename Value = Eigen::Vector3d>
class Butterworth4 {
 public:
  Butterworth4(double cutoff_hz, double sample_rate_hz);

  /// Filters one sample; the samples must be equally spaced at sample_rate_hz.
  Value Filter(const Value& x);
  /// Sets the state to the steady state of a constant input x (the next outputs equal x
  /// while x stays constant), so the filter starts without a transient. The default
  /// state is the steady state of a zero input.
  void Reset(const Value& x);

  /// Frequency response H(exp(j 2 pi f / fs)) of the digital filter at f_hz.
  std::complex<double> Response(double f_hz) const;
  /// Group delay at 0 Hz of the digital filter (s): for H = B/A,
  /// tau(0) = (sum k b_k / sum b_k - sum k a_k / sum a_k) / fs, summed over the sections.
  double GroupDelayAtDc_s() const;

  double cutoff_hz() const { return cutoff_hz_; }
  double sample_rate_hz() const { return sample_rate_hz_; }

 private:
  double cutoff_hz_;
  double sample_rate_hz_;
  std::array<BiquadCoefficients, 2> sections_;
  // Direct form II transposed state (s1, s2) of each section.
  std::array<Value, 2> s1_;
  std::array<Value, 2> s2_;
};

extern template class Butterworth4<double>;
extern template class Butterworth4<Eigen::Vector3d>;

/// The IMU's high-rate sampling and anti-alias filtering, from `imu.anti_alias`:
///   anti_alias: {cutoff_hz: 50, oversample: 8}            # filter on, 8x internal rate
///   anti_alias: {enabled: false, oversample: 8}           # high rate, no filter (aliasing)
/// The internal rate is imu.rate_hz x oversample; the IMU output sums `oversample` internal
/// increments. An absent section means oversample 1 and no filter.
struct AntiAliasConfig {
  bool enabled = false;   ///< filter on
  double cutoff_hz = 0.0;
  int oversample = 1;     ///< internal samples per IMU output sample
};

/// Parses imu.anti_alias (keys enabled, cutoff_hz, oversample). `enabled` defaults to true
/// when the section is given; an enabled filter needs cutoff_hz > 0. When imu_rate_hz > 0
/// the cutoff must also lie below the internal Nyquist frequency imu_rate_hz*oversample/2.
AntiAliasConfig ParseAntiAliasConfig(const ConfigNode& node, double imu_rate_hz = 0.0);

/// The frequency (Hz, in [0, fs/2]) at which a tone at f_hz appears after sampling at
/// sample_rate_hz: |f - fs * round(f / fs)|. Throws std::invalid_argument unless fs > 0
/// and f is finite.
double AliasFrequencyHz(double f_hz, double sample_rate_hz);

}  // namespace navtwin::sim
