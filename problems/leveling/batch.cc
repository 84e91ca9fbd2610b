#include "problems/leveling/batch.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <ceres/covariance.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <Eigen/Cholesky>

#include "problems/leveling/leveling_vibration.h"
#include "factors/state_prior.h"
#include "core/leveling_model.h"
#include "core/rotation.h"

namespace navtwin::leveling {
namespace {

/// Start scan: candidates f0 (1 + kScanStep i), |i| <= kScanHalfSteps (+-8 % in 2 % steps;
/// the least-squares fit of a 0.2 s window changes over ~1/T = 5 Hz, far wider than a step).
constexpr double kScanStep = 0.02;
constexpr int kScanHalfSteps = 4;
/// A fundamental below kSignificance sigma / sqrt(N) on every modelled axis is noise (pure
/// noise gives an amplitude of rms 2 sigma / sqrt(N); 2.5 times that: 0.2 % per axis).
constexpr double kSignificance = 5.0;
/// Harmonics at or above this fraction of the sample rate alias: they are not modelled.
constexpr double kMaxToneRateFraction = 0.45;
/// With harmonics, f0 / 2 replaces the autocorrelation's f0 when its fit explains this many
/// sigma^2 more (ChooseModel).
constexpr double kHalfFundamentalMargin = 25.0;
/// Floor of an estimated noise (m/s^2), so that a noise-free window still has weights.
constexpr double kMinNoise_mps2 = 1e-6;
constexpr int kMaxIterations = 30;

void RequireTwoSamples(const AccelWindow& window) {
  if (window.size() < 2) {
    throw std::invalid_argument("batch leveling: the window from " + window.source + " holds " +
                                std::to_string(window.size()) + " samples, at least 2 are needed");
  }
}

/// Sample times relative to the window centre (decorrelates frequency and phase) and the
/// sample rate.
struct Timebase {
  std::vector<double> t_s;
  double rate_hz = 0.0;
};

Timebase CentredTimes(const AccelWindow& window) {
  const int n = window.size();
  Timebase out;
  if (static_cast<int>(window.t_s.size()) == n) {
    out.t_s = window.t_s;
  } else if (window.rate_hz > 0.0) {
    out.t_s.resize(n);
    for (int k = 0; k < n; ++k) out.t_s[k] = k / window.rate_hz;
  } else {
    throw std::invalid_argument("batch leveling: the window from " + window.source +
                                " has neither one time per sample nor a sample rate");
  }
  const double span_s = out.t_s.back() - out.t_s.front();
  out.rate_hz = window.rate_hz > 0.0 ? window.rate_hz : (n - 1) / span_s;
  if (!(span_s > 0.0) || !std::isfinite(out.rate_hz)) {
    throw std::invalid_argument("batch leveling: the sample times of " + window.source + " do not increase");
  }
  const double centre_s = 0.5 * (out.t_s.front() + out.t_s.back());
  for (double& t : out.t_s) t -= centre_s;
  return out;
}

/// The tone model at a fixed frequency is linear: per axis, mean + sum_h c_h cos + s_h sin.
struct ToneFit {
  double f_hz = 0.0;
  Eigen::Vector3d mean_mps2 = Eigen::Vector3d::Zero();
  std::vector<double> tones;  ///< per harmonic c_x, s_x, c_y, s_y, c_z, s_z (0 off the modelled axes)
  double explained = 0.0;     ///< squared residual the tones remove, summed over the modelled axes
};

/// Normal equations of the linear tone model at one frequency. All axes share the design
/// matrix [1, cos w, sin w, ..., cos H w, sin H w], so one normal matrix serves three axes.
class ToneNormalEquations {
 public:
  explicit ToneNormalEquations(int harmonics)
      : harmonics_(harmonics),
        normal_(Eigen::MatrixXd::Zero(1 + 2 * harmonics, 1 + 2 * harmonics)),
        rhs_(Eigen::MatrixXd::Zero(1 + 2 * harmonics, 3)),
        row_(1 + 2 * harmonics) {
    row_[0] = 1.0;
  }

  /// One sample: cos w, sin w of its phase and its specific force minus the sample mean.
  void Add(double c1, double s1, const Eigen::Vector3d& y) {
    double ch = c1, sh = s1;
    for (int h = 1; h <= harmonics_; ++h) {
      row_[2 * h - 1] = ch;
      row_[2 * h] = sh;
      const double next_c = ch * c1 - sh * s1;
      sh = sh * c1 + ch * s1;
      ch = next_c;
    }
    const int p = static_cast<int>(row_.size());
    for (int i = 0; i < p; ++i) {
      for (int j = 0; j <= i; ++j) normal_(i, j) += row_[i] * row_[j];
      for (int a = 0; a < 3; ++a) rhs_(i, a) += row_[i] * y[a];
    }
  }

  /// The least-squares tones on the modelled axes (the others keep the sample mean).
  ToneFit Solve(double f_hz, const Eigen::Vector3d& sample_mean, const std::array<bool, 3>& axes) const {
    const Eigen::MatrixXd x = normal_.selfadjointView<Eigen::Lower>().ldlt().solve(rhs_);
    ToneFit fit;
    fit.f_hz = f_hz;
    fit.mean_mps2 = sample_mean;
    fit.tones.assign(6 * harmonics_, 0.0);
    for (int a = 0; a < 3; ++a) {
      if (!axes[a]) continue;
      fit.mean_mps2[a] += x(0, a);
      fit.explained += rhs_.col(a).dot(x.col(a));  // y^T A (A^T A)^-1 A^T y
      for (int h = 1; h <= harmonics_; ++h) {
        fit.tones[6 * (h - 1) + 2 * a] = x(2 * h - 1, a);
        fit.tones[6 * (h - 1) + 2 * a + 1] = x(2 * h, a);
      }
    }
    return fit;
  }

 private:
  int harmonics_;
  Eigen::MatrixXd normal_;  ///< lower triangle of A^T A
  Eigen::MatrixXd rhs_;     ///< A^T Y
  Eigen::VectorXd row_;
};

/// Linear tone fits of a window at given frequencies.
class ToneFitter {
 public:
  ToneFitter(const std::vector<double>& t_s, const std::vector<Eigen::Vector3d>& f_b_mps2, int harmonics,
             const std::array<bool, 3>& axes)
      : t_s_(t_s), harmonics_(harmonics), axes_(axes), centred_(f_b_mps2.size()) {
    for (const Eigen::Vector3d& f : f_b_mps2) sample_mean_ += f;
    sample_mean_ /= static_cast<double>(f_b_mps2.size());
    for (size_t k = 0; k < f_b_mps2.size(); ++k) centred_[k] = f_b_mps2[k] - sample_mean_;
  }

  /// The constant model (no tones): the sample mean.
  ToneFit Mean() const {
    ToneFit fit;
    fit.mean_mps2 = sample_mean_;
    return fit;
  }

  ToneFit Fit(double f_hz) const {
    ToneNormalEquations equations(harmonics_);
    for (size_t k = 0; k < t_s_.size(); ++k) {
      const double w = kTwoPi * f_hz * t_s_[k];
      equations.Add(std::cos(w), std::sin(w), centred_[k]);
    }
    return equations.Solve(f_hz, sample_mean_, axes_);
  }

  /// Fits at f0 (1 + step i), i = -half_steps..half_steps, in one pass over the samples:
  /// the phase of candidate i + 1 is that of candidate i rotated by step w0 (two sin/cos
  /// per sample instead of one per candidate).
  std::vector<ToneFit> Scan(double f0_hz, double step, int half_steps) const {
    std::vector<ToneNormalEquations> equations(2 * half_steps + 1, ToneNormalEquations(harmonics_));
    for (size_t k = 0; k < t_s_.size(); ++k) {
      const double w0 = kTwoPi * f0_hz * t_s_[k];
      double c = std::cos(w0 * (1.0 - step * half_steps)), s = std::sin(w0 * (1.0 - step * half_steps));
      const double cd = std::cos(w0 * step), sd = std::sin(w0 * step);
      for (ToneNormalEquations& e : equations) {
        e.Add(c, s, centred_[k]);
        const double next_c = c * cd - s * sd;
        s = s * cd + c * sd;
        c = next_c;
      }
    }
    std::vector<ToneFit> fits;
    for (int i = -half_steps; i <= half_steps; ++i) {
      fits.push_back(equations[i + half_steps].Solve(f0_hz * (1.0 + step * i), sample_mean_, axes_));
    }
    return fits;
  }

 private:
  const std::vector<double>& t_s_;
  int harmonics_;
  std::array<bool, 3> axes_;
  std::vector<Eigen::Vector3d> centred_;  ///< f - sample mean: keeps g out of the normal equations
  Eigen::Vector3d sample_mean_ = Eigen::Vector3d::Zero();
};

/// The best fit over the scan around f0, refined by a parabola through the best candidate
/// and its neighbours (a better start saves Ceres iterations).
ToneFit ScanFrequency(const ToneFitter& fitter, double f0_hz) {
  const std::vector<ToneFit> fits = fitter.Scan(f0_hz, kScanStep, kScanHalfSteps);
  const auto best = std::max_element(fits.begin(), fits.end(),
                                     [](const ToneFit& a, const ToneFit& b) { return a.explained < b.explained; });
  if (best == fits.begin() || best + 1 == fits.end()) return *best;
  const double y0 = (best - 1)->explained, y1 = best->explained, y2 = (best + 1)->explained;
  const double curvature = y0 - 2.0 * y1 + y2;  // < 0 at an interior maximum
  if (!(curvature < 0.0)) return *best;
  const double offset = 0.5 * (y0 - y2) / curvature;  // in steps, within [-0.5, 0.5]
  const ToneFit refined = fitter.Fit(best->f_hz + offset * kScanStep * f0_hz);
  return refined.explained > best->explained ? refined : *best;
}

/// Number of harmonics of a fundamental up to f_max_hz that stay below the aliasing limit
/// and leave the linear fit more samples than unknowns.
int UsableHarmonics(int requested, double f_max_hz, double rate_hz, int n) {
  int h = 0;
  while (h < requested && (h + 1) * f_max_hz < kMaxToneRateFraction * rate_hz && 2 * (h + 1) + 2 <= n) ++h;
  return h;
}

bool VibrationSignificant(const ToneFit& fit, const std::array<bool, 3>& axes, double sigma_mps2, int n) {
  const double threshold = kSignificance * sigma_mps2 / std::sqrt(static_cast<double>(n));
  for (int a = 0; a < 3; ++a) {
    if (axes[a] && std::hypot(fit.tones[2 * a], fit.tones[2 * a + 1]) >= threshold) return true;
  }
  return false;
}

std::string Join(const std::string& a, const std::string& b) {
  if (a.empty()) return b;
  return b.empty() ? a : a + "; " + b;
}

/// The model the solve uses: harmonics (0: constant), frequency start, whether it is free.
struct ModelChoice {
  int harmonics = 0;
  bool frequency_free = false;
  ToneFit start;
  std::string fallback;  ///< LevelEstimate::fallback
  std::string note;      ///< for covariance_note
};

ModelChoice ChooseModel(const AccelWindow& window, const LevelingOptions& options, const signal::PeriodEstimate& period,
                        const Timebase& time, double sigma_mps2) {
  const int n = window.size();
  const int modelled_axes = static_cast<int>(std::count(options.vib_axes.begin(), options.vib_axes.end(), true));
  ModelChoice choice;
  const bool tones_wanted = options.vib_tones > 0 && modelled_axes > 0;
  if (!tones_wanted || !period.found || !(period.refined_period_samples > 0.0)) {
    if (tones_wanted) choice.fallback = "no autocorrelation period: batch without vibration tones";
    choice.start = ToneFitter(time.t_s, window.f_b_mps2, 0, options.vib_axes).Mean();
    return choice;
  }
  const double f0_hz = time.rate_hz / period.refined_period_samples;
  const double f_max_hz = f0_hz * (1.0 + kScanStep * kScanHalfSteps);
  choice.harmonics = UsableHarmonics(options.vib_tones, f_max_hz, time.rate_hz, n);
  const ToneFitter fitter(time.t_s, window.f_b_mps2, choice.harmonics, options.vib_axes);
  if (choice.harmonics == 0) {
    char text[96];
    std::snprintf(text, sizeof(text), "vibration at or above %g x the sample rate: batch without vibration tones",
                  kMaxToneRateFraction);
    choice.fallback = text;
    choice.start = fitter.Mean();
    return choice;
  }
  if (choice.harmonics < options.vib_tones) {
    choice.fallback = "only " + std::to_string(choice.harmonics) + " of " + std::to_string(options.vib_tones) +
                      " harmonics modelled (higher ones alias)";
  }
  choice.start = ScanFrequency(fitter, f0_hz);
  if (choice.harmonics >= 2) {
    // A second harmonic stronger than the fundamental puts the first autocorrelation peak
    // at half the period. Harmonics of f0 / 2 then include f0: same parameter count, so
    // the half fundamental wins only when it explains clearly more than noise could
    // (kHalfFundamentalMargin sigma^2 of sum of squares, a ~5-sigma margin).
    const ToneFit half = ScanFrequency(fitter, 0.5 * f0_hz);
    if (half.explained > choice.start.explained + kHalfFundamentalMargin * sigma_mps2 * sigma_mps2) {
      choice.start = half;
    }
  }
  choice.frequency_free = VibrationSignificant(choice.start, options.vib_axes, sigma_mps2, n);
  if (!choice.frequency_free) {
    choice.note = "vibration not significant (fundamental below 5 sigma/sqrt(N) on every modelled axis): "
                  "frequency held constant, no frequency sigma";
  }
  return choice;
}

/// The parameter blocks of the Ceres problem (start values from the linear fit).
struct Parameters {
  double attitude[2] = {0.0, 0.0};  ///< roll_rad, pitch_rad
  double f_hz[1] = {0.0};
  std::vector<double> tones;        ///< 6 per harmonic, block h at 6 (h - 1)
  double bias[3] = {0.0, 0.0, 0.0};
  std::vector<double*> blocks;      ///< in LevelingVibration's order

  Parameters(const ModelChoice& model, bool with_bias) : tones(model.start.tones) {
    const RollPitch rp = LevelFromSpecificForce(model.start.mean_mps2);
    attitude[0] = rp.roll_rad;
    attitude[1] = rp.pitch_rad;
    f_hz[0] = model.start.f_hz;
    blocks.push_back(attitude);
    if (model.harmonics > 0) blocks.push_back(f_hz);
    for (int h = 0; h < model.harmonics; ++h) blocks.push_back(tones.data() + 6 * h);
    if (with_bias) blocks.push_back(bias);
  }
  Parameters(const Parameters&) = delete;  // blocks point into this object
  Parameters& operator=(const Parameters&) = delete;
};

std::vector<int> UnmodelledCoordinates(const std::array<bool, 3>& axes) {
  std::vector<int> out;
  for (int a = 0; a < 3; ++a) {
    if (axes[a]) continue;
    out.push_back(2 * a);      // c
    out.push_back(2 * a + 1);  // s
  }
  return out;
}

ceres::Solver::Options SolverOptions() {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;  // ~10 parameters: faster than DENSE_QR
  o.max_num_iterations = kMaxIterations;
  // Ceres' default relative cost change 1e-6: from the linear start two or three steps; a
  // tolerance of 1e-10 costs one more step and moves the angles by < 0.3 % of their sigma
  // (seed experiment, 2000 windows).
  o.function_tolerance = 1e-6;
  o.parameter_tolerance = 1e-10;
  o.gradient_tolerance = 1e-12;
  o.num_threads = 1;
  o.logging_type = ceres::SILENT;
  o.minimizer_progress_to_stdout = false;
  return o;
}

/// Joint covariance of attitude and (when free) frequency in whitened units; empty
/// with a note when ceres::Covariance fails.
struct Covariances {
  bool ok = false;
  Eigen::Matrix2d attitude = Eigen::Matrix2d::Zero();
  double f_hz2 = 0.0;
};

Covariances ComputeCovariances(ceres::Problem& problem, const Parameters& params, bool frequency_free) {
  ceres::Covariance::Options o;
  o.algorithm_type = ceres::DENSE_SVD;
  o.num_threads = 1;
  ceres::Covariance covariance(o);
  std::vector<std::pair<const double*, const double*>> pairs = {{params.attitude, params.attitude}};
  if (frequency_free) pairs.emplace_back(params.f_hz, params.f_hz);
  Covariances out;
  if (!covariance.Compute(pairs, &problem)) return out;
  Eigen::Matrix<double, 2, 2, Eigen::RowMajor> att;
  out.ok = covariance.GetCovarianceBlock(params.attitude, params.attitude, att.data());
  out.attitude = att;
  if (frequency_free) out.ok = out.ok && covariance.GetCovarianceBlock(params.f_hz, params.f_hz, &out.f_hz2);
  return out;
}

std::vector<VibrationToneEstimate> Tones(const std::vector<double>& tones, const std::array<bool, 3>& axes) {
  std::vector<VibrationToneEstimate> out;
  const int harmonics = static_cast<int>(tones.size() / 6);
  for (int a = 0; a < 3; ++a) {
    if (!axes[a]) continue;
    for (int h = 1; h <= harmonics; ++h) {
      const double c = tones[6 * (h - 1) + 2 * a], s = tones[6 * (h - 1) + 2 * a + 1];
      out.push_back({a, h, std::hypot(c, s), std::atan2(c, s)});  // c cos + s sin = A sin(. + phi)
    }
  }
  return out;
}

}  // namespace

BatchLevelingResult SolveLevelingBatch(const AccelWindow& window, const LevelingOptions& options,
                                       const signal::PeriodEstimate& period) {
  RequireTwoSamples(window);
  const int n = window.size();
  const Timebase time = CentredTimes(window);
  const bool noise_known = options.accel_noise_mps2 > 0.0;
  const double sigma_mps2 =
      noise_known ? options.accel_noise_mps2
                  : std::max(kMinNoise_mps2, EstimateAccelNoise(window, period.found ? period.refined_period_samples : 0.0));
  const ModelChoice model = ChooseModel(window, options, period, time, sigma_mps2);
  const double g_mps2 = options.gravity_mps2 > 0.0 ? options.gravity_mps2 : model.start.mean_mps2.norm();
  const bool with_bias = options.accel_bias_prior_mps2 > 0.0;

  Parameters params(model, with_bias);
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // one manifold on the stack
  problem_options.disable_all_safety_checks = true;                   // blocks are distinct arrays
  ceres::Problem problem(problem_options);
  // One residual block for the whole window (the samples' residuals stacked): 0.13 ms per
  // solve where one block per sample takes 0.33 ms (seed experiment, H = 1, no covariance).
  problem.AddResidualBlock(
      LevelingVibration::Create(time.t_s, window.f_b_mps2, g_mps2, sigma_mps2, model.harmonics, with_bias), nullptr,
      params.blocks);
  if (with_bias) {
    problem.AddResidualBlock(VectorPrior3::Create(Eigen::Vector3d::Zero(), options.accel_bias_prior_mps2), nullptr,
                             params.bias);
  }
  const std::vector<int> held = UnmodelledCoordinates(options.vib_axes);
  ceres::SubsetManifold modelled_axes_only(LevelingVibration::kHarmonicSize, held);
  for (int h = 0; h < model.harmonics && !held.empty(); ++h) {
    problem.SetManifold(params.blocks[LevelingVibration::HarmonicBlock(h + 1)], &modelled_axes_only);
  }
  if (model.harmonics > 0 && !model.frequency_free) problem.SetParameterBlockConstant(params.f_hz);

  ceres::Solver::Summary summary;
  ceres::Solve(SolverOptions(), &problem, &summary);

  BatchLevelingResult result;
  result.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  if (with_bias) result.accel_bias_mps2 = Eigen::Map<const Eigen::Vector3d>(params.bias);
  // Chi-square of the samples alone (the bias prior brings as many residuals as parameters).
  const double prior_chi2 = with_bias ? result.accel_bias_mps2.squaredNorm() /
                                            (options.accel_bias_prior_mps2 * options.accel_bias_prior_mps2)
                                      : 0.0;
  const double chi2 = std::max(0.0, 2.0 * summary.final_cost - prior_chi2);
  const int modelled = static_cast<int>(6 - held.size()) / 2;
  const int free_parameters = 2 + (model.frequency_free ? 1 : 0) + 2 * model.harmonics * modelled;
  const int dof = 3 * n - free_parameters;
  result.residual_rms_mps2 = sigma_mps2 * std::sqrt(chi2 / (3.0 * n));
  // An estimated noise only sets the weights: the residuals give the variance scale (with a
  // bias prior it scales the prior's share too; the scale is near 1 when the estimate is right).
  const double variance_scale = noise_known || dof <= 0 ? 1.0 : chi2 / dof;

  LevelEstimate& e = result.estimate;
  e.method = "batch";
  // The start is equation 1 (roll in [-pi, pi]); upside down a step may cross +-pi.
  e.roll_rad = WrapPi(params.attitude[0]);
  e.pitch_rad = params.attitude[1];
  e.samples_used = n;
  e.fallback = model.fallback;
  if (model.harmonics > 0) {
    e.vib_freq_hz = params.f_hz[0];
    e.period_samples = time.rate_hz / params.f_hz[0];
    result.tones = Tones(params.tones, options.vib_axes);
  }
  result.covariance_note = model.note;
  if (!options.batch_covariance) {
    result.covariance_note = Join(result.covariance_note, "covariance not computed (batch_covariance off)");
  } else if (const Covariances cov = ComputeCovariances(problem, params, model.frequency_free); cov.ok) {
    e.roll_sigma_rad = std::sqrt(variance_scale * cov.attitude(0, 0));
    e.pitch_sigma_rad = std::sqrt(variance_scale * cov.attitude(1, 1));
    result.vib_freq_sigma_hz = std::sqrt(variance_scale * cov.f_hz2);
  } else {
    result.covariance_note = Join(result.covariance_note,
                                  "ceres::Covariance (DENSE_SVD) failed: the Jacobian is rank deficient or too "
                                  "ill-conditioned at the solution; sigmas left 0");
  }
  return result;
}

LevelEstimate RunBatch(const AccelWindow& window, const LevelingOptions& options) {
  RequireTwoSamples(window);
  // The period comes from the whole window; the fit leaves saturated samples out.
  const signal::PeriodEstimate period = EstimateWindowPeriod(window, options);
  int removed = 0;
  const AccelWindow usable = WithoutSaturatedSamples(window, options, &removed);
  LevelEstimate estimate = SolveLevelingBatch(usable, options, period).estimate;
  if (removed > 0) {
    const std::string note = std::to_string(removed) + " saturated samples left out of the fit";
    estimate.fallback = estimate.fallback.empty() ? note : estimate.fallback + "; " + note;
  }
  return estimate;
}

}  // namespace navtwin::leveling
