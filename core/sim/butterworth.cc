#include "core/sim/butterworth.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace navtwin::sim {
namespace {

// Quality factors of the two pole pairs of the 4th-order Butterworth prototype: the poles
// lie on the unit circle at angles pi/8 and 3pi/8 from the negative real axis, and a pole
// pair at angle theta has Q = 1/(2 cos(theta)).
// Section i = 0, 1 has its poles at angle (2i + 1) pi / 8.
double ButterworthQ(int i) { return 1.0 / (2.0 * std::cos((2 * i + 1) * M_PI / 8.0)); }

template <typename Value>
Value ZeroLike();
template <>
double ZeroLike<double>() {
  return 0.0;
}
template <>
Eigen::Vector3d ZeroLike<Eigen::Vector3d>() {
  return Eigen::Vector3d::Zero();
}

}  // namespace

std::array<BiquadCoefficients, 2> DesignButterworth4(double cutoff_hz, double sample_rate_hz) {
  if (!(sample_rate_hz > 0.0) || !(cutoff_hz > 0.0) || !(cutoff_hz < 0.5 * sample_rate_hz)) {
    throw std::invalid_argument("Butterworth4: need 0 < cutoff (" + std::to_string(cutoff_hz) +
                                " Hz) < sample rate / 2 (" + std::to_string(sample_rate_hz) +
                                " Hz / 2)");
  }
  // Pre-warping: the analog cutoff tan(pi fc / fs) (in units of 2 fs) maps onto fc exactly.
  const double k = std::tan(M_PI * cutoff_hz / sample_rate_hz);
  std::array<BiquadCoefficients, 2> sections{};
  for (int i = 0; i < 2; ++i) {
    const double q = ButterworthQ(i);
    const double d = 1.0 + k / q + k * k;
    const double b0 = k * k / d;
    sections[i] = {b0, 2.0 * b0, b0, 2.0 * (k * k - 1.0) / d, (1.0 - k / q + k * k) / d};
  }
  return sections;
}

double AnalogButterworth4GroupDelay_s(double cutoff_hz) {
  const double omega_c = 2.0 * M_PI * cutoff_hz;
  return (1.0 / ButterworthQ(0) + 1.0 / ButterworthQ(1)) / omega_c;
}

template <typename Value>
Butterworth4<Value>::Butterworth4(double cutoff_hz, double sample_rate_hz)
    : cutoff_hz_(cutoff_hz),
      sample_rate_hz_(sample_rate_hz),
      sections_(DesignButterworth4(cutoff_hz, sample_rate_hz)) {
  Reset(ZeroLike<Value>());
}

template <typename Value>
Value Butterworth4<Value>::Filter(const Value& x) {
  Value u = x;
  for (int i = 0; i < 2; ++i) {
    const BiquadCoefficients& c = sections_[i];
    const Value y = c.b0 * u + s1_[i];
    s1_[i] = c.b1 * u - c.a1 * y + s2_[i];
    s2_[i] = c.b2 * u - c.a2 * y;
    u = y;
  }
  return u;
}

template <typename Value>
void Butterworth4<Value>::Reset(const Value& x) {
  // With y = x constant (unit DC gain per section): s2 = (b2 - a2) x, s1 = (b1 - a1) x + s2.
  for (int i = 0; i < 2; ++i) {
    const BiquadCoefficients& c = sections_[i];
    s2_[i] = (c.b2 - c.a2) * x;
    s1_[i] = (c.b1 - c.a1) * x + s2_[i];
  }
}

template <typename Value>
std::complex<double> Butterworth4<Value>::Response(double f_hz) const {
  const std::complex<double> z1 = std::polar(1.0, -2.0 * M_PI * f_hz / sample_rate_hz_);
  const std::complex<double> z2 = z1 * z1;
  std::complex<double> h = 1.0;
  for (const BiquadCoefficients& c : sections_) {
    h *= (c.b0 + c.b1 * z1 + c.b2 * z2) / (1.0 + c.a1 * z1 + c.a2 * z2);
  }
  return h;
}

template <typename Value>
double Butterworth4<Value>::GroupDelayAtDc_s() const {
  double samples = 0.0;
  for (const BiquadCoefficients& c : sections_) {
    samples += (c.b1 + 2.0 * c.b2) / (c.b0 + c.b1 + c.b2) - (c.a1 + 2.0 * c.a2) / (1.0 + c.a1 + c.a2);
  }
  return samples / sample_rate_hz_;
}

template class Butterworth4<double>;
template class Butterworth4<Eigen::Vector3d>;

AntiAliasConfig ParseAntiAliasConfig(const ConfigNode& node, double imu_rate_hz) {
  node.RequireKeys({"enabled", "cutoff_hz", "oversample"});
  AntiAliasConfig config;
  const bool given = node.yaml().IsDefined() && !node.yaml().IsNull();
  config.enabled = node.Bool("enabled", given);
  config.oversample = node.Int("oversample", 1, 1, 1000);
  config.cutoff_hz = node.Double("cutoff_hz", 0.0);
  if (config.enabled) {
    if (!node.Has("cutoff_hz")) node.Fail("cutoff_hz", "required when the filter is enabled");
    if (!(config.cutoff_hz > 0.0)) node.Fail("cutoff_hz", "must be > 0");
    const double nyquist_hz = 0.5 * imu_rate_hz * config.oversample;
    if (imu_rate_hz > 0.0 && !(config.cutoff_hz < nyquist_hz)) {
      node.Fail("cutoff_hz", "must be below the internal Nyquist frequency imu.rate_hz * "
                             "oversample / 2 = " + std::to_string(nyquist_hz) + " Hz");
    }
  }
  return config;
}

double AliasFrequencyHz(double f_hz, double sample_rate_hz) {
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz) || !std::isfinite(f_hz)) {
    throw std::invalid_argument("AliasFrequencyHz: need a finite frequency and a sample rate > 0");
  }
  return std::abs(f_hz - sample_rate_hz * std::round(f_hz / sample_rate_hz));
}

}  // namespace navtwin::sim
