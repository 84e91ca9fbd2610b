#include "problems/leveling/filter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/LU>

#include "core/leveling_model.h"
#include "core/rotation.h"

namespace navtwin::leveling {
namespace {


// Lower bound on the accelerometer noise (m/s^2, 0.1 ug): far below any real sensor, it
// only keeps R > 0 on noise-free data whose estimated noise is zero.
constexpr double kNoiseFloor_mps2 = 1e-6;

// Cost of a trial period P = w + f, f in [0, 1], from the differences one period apart
//   d_j = x_j - x(j - P) = (x_j - x_{j-w}) + f (x_{j-w} - x_{j-w-1}),   j = w+1 .. n-1,
// (the delayed sample linearly interpolated): anything of period P cancels in d_j. With
// white noise of variance s^2 per axis, E|d_j|^2 = 3 s^2 G(f), G(f) = 1 + f^2 + (1-f)^2,
// so mean |d_j|^2 / G(f) is flat in f for noise and smallest at the vibration period.
// Numerator and G are quadratics in f: N(f) = a + 2 b f + c f^2.
struct PeriodCost {
  double a = 0.0, b = 0.0, c = 0.0;
  int count = 0;
  double operator()(double f) const {
    return (a + 2.0 * b * f + c * f * f) / (count * (2.0 - 2.0 * f + 2.0 * f * f));
  }
};

PeriodCost MakePeriodCost(const std::vector<Eigen::Vector3d>& x, int w) {
  PeriodCost cost;
  const int n = static_cast<int>(x.size());
  for (int j = w + 1; j < n; ++j) {
    const Eigen::Vector3d d0 = x[j] - x[j - w];
    const Eigen::Vector3d d1 = x[j - w] - x[j - w - 1];
    cost.a += d0.squaredNorm();
    cost.b += d0.dot(d1);
    cost.c += d1.squaredNorm();
  }
  cost.count = n - w - 1;
  return cost;
}

// The period search range around a start p0: p0 +- min(2, p0 / 4) (the mean relative
// peak lag is within that of the period; the bound keeps half and double periods out).
double SearchHalfRange(double p0) { return std::min(2.0, p0 / 4.0); }

// The samples must hold this many periods for a period to be accepted. With exactly two,
// the estimate rests on the first period against the second, and it is taken at the first
// sample where the noisy estimate fits twice, i.e. from the short side of its spread; the
// first blocks (averaged at once, from sample 0) then leave vibration. In 10,000 runs of the
// seed's experiment: pitch RMS 0.51 deg, max 4.7 deg, RMS / sigma 1.8 with two; 0.30 deg,
// 1.2 deg, 1.05 with 2.5 (and with 3). Waiting costs no samples, only latency: blocks
// always start at sample 0.
constexpr double kMinPeriodsHeld = 2.5;

// The double of a period is taken only when the part of the variance that repeats only with
// the double is at least this fraction of the signal variance (UpdatePeriod): below it, a
// fundamental under a second harmonic of amplitude A is under 0.05 A, of which an unpaired
// half-period block keeps at most 2/pi, shared by all the blocks.
constexpr double kDoublePeriodMinPart = 0.01;

// The fractional period within SearchHalfRange of p0 (the mean relative lag of the
// autocorrelation peaks) that minimises the difference cost, and the cost there: an
// estimate of the variance that is not periodic (noise, summed over the axes).
// Why not signal::EstimatePeriod's interpolated period: equation 2 sums k - t products at
// lag t, so a sinusoid's r(t) carries the factor (k - t)/k; on the raw r it pulled each
// interpolated peak short by 0.14 samples on average over 120 samples (0.55 over 66, the
// 2.5 periods at which the filter starts) for the seed's 22-24 Hz at 600 Hz. EstimatePeriod
// now interpolates the lag-normalised values, which leaves about -0.02 samples at 120, but
// it still rests on three lags per peak. A block averaged over P + e samples leaves about
// A sin(phi) e / P of a vibration of amplitude A (up to 0.3 deg per 1 g at e = 0.14), so
// the filter refines on the differences, where the period is a direct minimum. The search
// is exact: within each whole-sample interval the minimum of N / G is at an end or where
// N' G - N G' = 0, a quadratic (the cubic terms cancel).
struct PeriodFit {
  double period_samples = 0.0;
  double residual_variance = std::numeric_limits<double>::infinity();
};
PeriodFit RefinePeriod(const std::vector<Eigen::Vector3d>& x, double p0) {
  const int n = static_cast<int>(x.size());
  const double lo = p0 - SearchHalfRange(p0), hi = p0 + SearchHalfRange(p0);
  PeriodFit best;
  const int w_last = std::min(static_cast<int>(std::floor(hi)), n - 2);
  for (int w = std::max(1, static_cast<int>(std::floor(lo))); w <= w_last; ++w) {
    const PeriodCost cost = MakePeriodCost(x, w);
    const double f_lo = std::max(0.0, lo - w), f_hi = std::min(1.0, hi - w);
    double candidates[4] = {f_lo, f_hi, -1.0, -1.0};
    // N' G - N G' = (4 b + 2 a) + (4 c - 4 a) f - (4 b + 2 c) f^2.
    const double q2 = -(4.0 * cost.b + 2.0 * cost.c);
    const double q1 = 4.0 * cost.c - 4.0 * cost.a;
    const double q0 = 4.0 * cost.b + 2.0 * cost.a;
    if (q2 != 0.0) {
      const double disc = q1 * q1 - 4.0 * q2 * q0;
      if (disc >= 0.0) {
        candidates[2] = (-q1 + std::sqrt(disc)) / (2.0 * q2);
        candidates[3] = (-q1 - std::sqrt(disc)) / (2.0 * q2);
      }
    } else if (q1 != 0.0) {
      candidates[2] = -q0 / q1;
    }
    for (const double f : candidates) {
      if (!(f >= f_lo && f <= f_hi)) continue;
      const double value = cost(f);
      if (value < best.residual_variance) best = {w + f, value};
    }
  }
  return best;
}

}  // namespace

OnlineLeveler::OnlineLeveler(const LevelingOptions& options, double rate_hz, int max_lag_samples)
    : options_(options), rate_hz_(rate_hz), autocorr_(max_lag_samples) {
  window_.rate_hz = rate_hz;
  window_.source = "online leveler";
}

// Period policy (online, nothing is re-processed): the period is re-estimated at every
// sample while none is known, and then whenever the next block is complete under the
// period in use, so that each block is averaged over the newest estimate (a longer one
// waits for its samples; a block that a shorter one would have completed a sample earlier
// is the same block, only averaged later). Blocks already used keep the period they had,
// and the next block starts where the last one ended, whatever the new period. When a
// later search finds no period, the one in use is kept (the earlier data showed it).
bool OnlineLeveler::Add(const Eigen::Vector3d& f_b_mps2) {
  window_.f_b_mps2.push_back(f_b_mps2);
  autocorr_.Add(f_b_mps2);
  sum_f_ += f_b_mps2;
  sum_f2_ += f_b_mps2.cwiseAbs2();
  const int last = window_.size() - 1;
  if (period_samples_ <= 0.0 || block_start_ + period_samples_ <= last) UpdatePeriod();
  bool updated = false;
  while (period_samples_ > 0.0 && block_start_ + period_samples_ <= last) {
    ProcessBlock();
    updated = true;
  }
  return updated;
}

// A period is accepted when the samples hold kMinPeriodsHeld of it, and when the part of
// the signal it explains reaches the peak threshold: 1 - (residual variance of the
// differences one period apart) / (variance of the samples) is the fraction that repeats
// with the period, signal / (signal + noise) for a sinusoid in noise, like the
// lag-normalised peak value. The check is on the refined period, which the peak threshold
// is not: it refuses half periods that leave much of a fundamental (5,000 runs with a
// second harmonic N(0, 0.7 g): pitch RMS 0.30 instead of 0.42 deg) and some short-lag
// peaks that noise makes on the first samples of a weak vibration.
// A vibration whose second harmonic is stronger than its fundamental has its highest
// autocorrelation peaks at half the period, and the mean relative lag follows them. Blocks
// of half the period then leave the fundamental (pairs of them cancel it, an unpaired one
// keeps up to 2/pi of it), so the double is tested: it is taken when the variance that
// repeats only with the double (the residual of the period less that of the double) is
// larger than what the double leaves (the noise) and than kDoublePeriodMinPart of the
// signal variance (on noise-free data both residuals are rounding). In 10,000 runs with two
// tones (the second N(0, 0.5 g)), pitch RMS 0.29 deg instead of 0.44 (max 1.1 instead of
// 4.9 deg, RMS / sigma 1.04 instead of 1.62); the one-tone experiment is unchanged.
// The start value is the seed's mean relative lag (last peak lag / number of peaks) from
// signal::FindPeaks. signal::EstimatePeriod is not called: its interpolated period is not
// used (see RefinePeriod), and formatting its reason text on every failed search was a
// quarter of the filter's run time.
void OnlineLeveler::UpdatePeriod() {
  const int n = window_.size();
  if (n < 2) return;
  const std::vector<int> peaks = signal::FindPeaks(autocorr_.Evaluate(), n, options_.peaks);
  if (peaks.empty()) return;
  const double p0 = static_cast<double>(peaks.back()) / static_cast<double>(peaks.size());
  if (kMinPeriodsHeld * (p0 - SearchHalfRange(p0)) > n) return;  // cannot fit yet
  PeriodFit fit = RefinePeriod(window_.f_b_mps2, p0);
  if (kMinPeriodsHeld * fit.period_samples > n) return;
  const Eigen::Vector3d mean = sum_f_ / n;
  const double variance = (sum_f2_ - n * mean.cwiseAbs2()).sum() / (n - 1);
  const PeriodFit twice = RefinePeriod(window_.f_b_mps2, 2.0 * fit.period_samples);
  const double only_twice = fit.residual_variance - twice.residual_variance;
  if (only_twice > twice.residual_variance && only_twice > kDoublePeriodMinPart * variance) {
    if (kMinPeriodsHeld * twice.period_samples > n) return;  // wait until the whole period fits
    fit = twice;
  }
  if (!(1.0 - fit.residual_variance / variance >= options_.peaks.threshold)) return;
  period_samples_ = fit.period_samples;
}

// One Kalman measurement update with the mean specific force over the block
// [block_start, block_start + P]: z = h(x) + v, h = SpecificForceAtRest(roll, pitch, g),
// R = sigma^2 / P I3 (the mean of ~P samples of white noise; the interpolated ends make it
// a few % smaller, which is ignored). The first block initialises x by equation 1 and P by
// its Jacobian (the posterior of a flat prior). Later updates are made in information form,
// P+ = (P^-1 + H^T H / r)^-1, x+ = x + P+ H^T (z - h(x)) / r, algebraically the Kalman
// update. One linearisation suffices: x is already within a block's error (~1 deg) of the
// answer, whose second-order term ~ g dx^2 / 2 is < 2e-4 g, against a block noise of
// sigma / sqrt(P) ~ 0.01 g. No process noise: the vehicle is at rest.
void OnlineLeveler::ProcessBlock() {
  const double length = period_samples_;
  const Eigen::Vector3d z = signal::AverageInterpolated(window_.f_b_mps2, block_start_, length);
  const double sigma =
      options_.accel_noise_mps2 > 0.0 ? options_.accel_noise_mps2 : EstimateAccelNoise(window_, length);
  const double r = std::pow(std::max(sigma, kNoiseFloor_mps2), 2) / length;
  block_sum_ += z;
  ++blocks_;
  block_start_ += length;
  if (blocks_ == 1) {
    const RollPitch rp = LevelFromSpecificForce(z);
    x_ << rp.roll_rad, rp.pitch_rad;
    const Eigen::Matrix<double, 2, 3> j = LevelJacobian(z);
    p_ = r * j * j.transpose();
    return;
  }
  // Gravity: the configured value, else the magnitude of the period-averaged specific force
  // (the mean |f| of the samples would count the vibration: +25 % for 1 g across gravity).
  const double g = options_.gravity_mps2 > 0.0 ? options_.gravity_mps2 : block_sum_.norm() / blocks_;
  const Eigen::Matrix<double, 3, 2> h = SpecificForceAtRestJacobian(x_(0), x_(1), g);
  const Eigen::Vector3d innovation = z - SpecificForceAtRest(x_(0), x_(1), g);
  const Eigen::Matrix2d information = p_.inverse() + h.transpose() * h / r;
  p_ = information.inverse();
  p_ = 0.5 * (p_ + p_.transpose());
  x_ += p_ * h.transpose() * innovation / r;
  x_(0) = WrapPi(x_(0));
}

bool OnlineLeveler::initialized() const { return blocks_ > 0; }

// Plain mean of the samples so far and its covariance from the sample spread (the
// vibration counts as noise); with one sample the spread is unknown: infinite covariance.
void OnlineLeveler::PlainMeanSoFar(Eigen::Vector3d* mean_f_b_mps2, Eigen::Matrix2d* covariance) const {
  const std::vector<Eigen::Vector3d>& x = window_.f_b_mps2;
  const int n = window_.size();
  if (n == 0) throw std::logic_error("OnlineLeveler: no samples yet, no estimate");
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& f : x) mean += f;
  mean /= n;
  *mean_f_b_mps2 = mean;
  if (n == 1) {
    *covariance = Eigen::Matrix2d::Identity() * std::numeric_limits<double>::infinity();
    return;
  }
  Eigen::Vector3d variance = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& f : x) variance += (f - mean).cwiseAbs2();
  variance /= static_cast<double>(n - 1) * n;  // of the mean
  const Eigen::Matrix<double, 2, 3> j = LevelJacobian(mean);
  *covariance = j * variance.asDiagonal() * j.transpose();
}

LevelEstimate OnlineLeveler::Estimate() const {
  LevelEstimate out;
  out.method = "filter";
  if (blocks_ == 0) {
    Eigen::Vector3d mean;
    Eigen::Matrix2d cov;
    PlainMeanSoFar(&mean, &cov);
    const RollPitch rp = LevelFromSpecificForce(mean);
    out.roll_rad = rp.roll_rad;
    out.pitch_rad = rp.pitch_rad;
    out.roll_sigma_rad = std::sqrt(cov(0, 0));
    out.pitch_sigma_rad = std::sqrt(cov(1, 1));
    out.samples_used = window_.size();
    out.fallback =
        "no vibration period found yet: plain mean of " + std::to_string(window_.size()) + " samples";
    return out;
  }
  out.roll_rad = x_(0);
  out.pitch_rad = x_(1);
  out.roll_sigma_rad = std::sqrt(p_(0, 0));
  out.pitch_sigma_rad = std::sqrt(p_(1, 1));
  out.samples_used = static_cast<int>(std::floor(block_start_)) + 1;  // indices 0 .. end of the last block
  out.period_samples = period_samples_;
  out.vib_freq_hz = rate_hz_ > 0.0 ? rate_hz_ / period_samples_ : 0.0;
  return out;
}

Eigen::Matrix2d OnlineLeveler::covariance() const {
  if (blocks_ > 0) return p_;
  Eigen::Vector3d mean;
  Eigen::Matrix2d cov;
  PlainMeanSoFar(&mean, &cov);
  return cov;
}

// Only a filter that has made an update can be converged: before that the sigmas come from
// a plain mean, which a vibration biases by more than its spread shows.
bool OnlineLeveler::Converged(double sigma_limit_rad) const {
  return blocks_ > 0 && std::sqrt(p_(0, 0)) < sigma_limit_rad && std::sqrt(p_(1, 1)) < sigma_limit_rad;
}

LevelEstimate RunFilter(const AccelWindow& window, const LevelingOptions& options) {
  if (window.size() < 2) {
    throw std::invalid_argument("filter: the window from " + window.source + " holds " +
                                std::to_string(window.size()) + " samples, at least 2 are needed");
  }
  const int max_lag = static_cast<int>(std::floor(options.max_lag_fraction * window.size()));
  OnlineLeveler filter(options, window.rate_hz, max_lag);
  for (const Eigen::Vector3d& f : window.f_b_mps2) filter.Add(f);
  return filter.Estimate();
}

}  // namespace navtwin::leveling
