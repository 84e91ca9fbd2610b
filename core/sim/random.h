// Deterministic random numbers for the simulator: the same seed gives the same files,
// byte for byte, on every platform (the standard library's distributions are
// implementation-defined, so uniform and normal variates are made here from the raw
// 64-bit output of std::mt19937_64, whose sequence the standard fixes).
//
// Every error source draws from its own stream, Rng(seed).Stream("gyro.bias"), so that
// switching one source on or off does not change the values drawn by the others.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include <Eigen/Core>

namespace navtwin::sim {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : seed_(seed), engine_(seed) {}

  /// An independent stream named `name` (FNV-1a hash of the name mixed with the seed).
  Rng Stream(const std::string& name) const {
    std::uint64_t h = 1469598103934665603ull;
    for (const unsigned char c : name) {
      h ^= c;
      h *= 1099511628211ull;
    }
    return Rng(Mix(seed_ ^ h));
  }

  /// Uniform in [0, 1) with 53 random bits.
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }

  /// Standard normal by the Marsaglia polar method.
  double Normal() {
    if (have_spare_) {
      have_spare_ = false;
      return spare_;
    }
    double u, v, s;
    do {
      u = 2.0 * Uniform() - 1.0;
      v = 2.0 * Uniform() - 1.0;
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double m = std::sqrt(-2.0 * std::log(s) / s);
    spare_ = v * m;
    have_spare_ = true;
    return u * m;
  }
  double Normal(double sigma) { return sigma * Normal(); }
  Eigen::Vector3d Normal3(double sigma) {
    const double x = Normal(sigma), y = Normal(sigma), z = Normal(sigma);
    return Eigen::Vector3d(x, y, z);
  }

 private:
  // SplitMix64 finaliser: spreads similar seeds over the whole state space.
  static std::uint64_t Mix(std::uint64_t z) {
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }

  std::uint64_t seed_;
  std::mt19937_64 engine_;
  bool have_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace navtwin::sim
