#include "problems/leveling/monte_carlo.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/rotation.h"
#include "core/sim/random.h"
#include "problems/leveling/batch.h"
#include "problems/leveling/filter.h"
#include "core/leveling_model.h"
#include "core/units.h"

namespace navtwin::leveling {
namespace {

constexpr int kMethods = 4;
const char* const kMethodNames[kMethods] = {"plain_mean", "period_average", "filter", "batch"};

bool AllFinite(const MonteCarloConfig& c) {
  for (const double v : {c.rate_hz, c.window_s, c.vib_freq_lo_hz, c.vib_freq_hi_hz, c.vib_amp_g, c.noise_mg,
                         c.true_roll_deg, c.true_pitch_deg}) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

/// The arguments streamed into one message.
template <typename... Args>
std::string Text(const Args&... args) {
  std::ostringstream s;
  (s << ... << args);
  return s.str();
}

/// One method's outcome on one run.
struct RunOutcome {
  double roll_error_rad = 0.0;
  double pitch_error_rad = 0.0;
  double roll_sigma_rad = 0.0;
  double pitch_sigma_rad = 0.0;
  std::string fallback;
};

using Method = LevelEstimate (*)(const AccelWindow&, const LevelingOptions&);
const Method kMethodFunctions[kMethods] = {&PlainMean, &PeriodAverage, &RunFilter, &RunBatch};

RunOutcome Outcome(const LevelEstimate& e, double roll_rad, double pitch_rad) {
  RunOutcome o;
  o.roll_error_rad = WrapPi(e.roll_rad - roll_rad);
  o.pitch_error_rad = e.pitch_rad - pitch_rad;
  o.roll_sigma_rad = e.roll_sigma_rad;
  o.pitch_sigma_rad = e.pitch_sigma_rad;
  o.fallback = e.fallback;
  return o;
}

/// Statistics of one method from its per-run outcomes, reduced in run order (so that the
/// figures are bit-identical for any thread count).
MethodStatistics Reduce(const std::string& name, const std::vector<RunOutcome>& outcomes, bool keep_errors) {
  MethodStatistics s;
  s.method = name;
  double roll2 = 0.0, pitch2 = 0.0, z2 = 0.0, roll_sigma = 0.0, pitch_sigma = 0.0;
  int roll_sigma_count = 0, z_count = 0;
  for (const RunOutcome& o : outcomes) {
    const double roll_deg = o.roll_error_rad * kRadToDeg, pitch_deg = o.pitch_error_rad * kRadToDeg;
    roll2 += roll_deg * roll_deg;
    pitch2 += pitch_deg * pitch_deg;
    s.roll_max_deg = std::max(s.roll_max_deg, std::abs(roll_deg));
    s.pitch_max_deg = std::max(s.pitch_max_deg, std::abs(pitch_deg));
    if (o.roll_sigma_rad > 0.0) {
      roll_sigma += o.roll_sigma_rad * kRadToDeg;
      ++roll_sigma_count;
    }
    if (o.pitch_sigma_rad > 0.0) {
      pitch_sigma += o.pitch_sigma_rad * kRadToDeg;
      const double z = o.pitch_error_rad / o.pitch_sigma_rad;
      z2 += z * z;
      ++z_count;
    }
    if (!o.fallback.empty() && s.fallbacks++ == 0) s.first_fallback = o.fallback;
    if (keep_errors) {
      s.roll_error_deg.push_back(roll_deg);
      s.pitch_error_deg.push_back(pitch_deg);
    }
  }
  const double n = static_cast<double>(outcomes.size());
  s.roll_rms_deg = std::sqrt(roll2 / n);
  s.pitch_rms_deg = std::sqrt(pitch2 / n);
  s.roll_sigma_mean_deg = roll_sigma_count > 0 ? roll_sigma / roll_sigma_count : NAN;
  s.pitch_sigma_mean_deg = z_count > 0 ? pitch_sigma / z_count : NAN;
  s.pitch_error_over_sigma_rms = z_count > 0 ? std::sqrt(z2 / z_count) : NAN;
  return s;
}

}  // namespace

std::string ValidateMonteCarloConfig(const MonteCarloConfig& c) {
  if (!AllFinite(c)) return "every value must be finite";
  if (c.runs < 1) return Text("runs must be at least 1 (got ", c.runs, ")");
  if (!(c.rate_hz > 0.0)) return Text("rate_hz must be positive (got ", c.rate_hz, ")");
  if (c.window_s <= 0.0 || MonteCarloWindowSamples(c) < 2) {
    return Text("window_s x rate_hz must give at least 2 samples (window_s ", c.window_s, " s gives ",
                MonteCarloWindowSamples(c), ")");
  }
  if (!(c.vib_freq_lo_hz > 0.0)) return Text("the vibration frequency must be positive (low end ", c.vib_freq_lo_hz, " Hz)");
  if (c.vib_freq_lo_hz > c.vib_freq_hi_hz) {
    return Text("the vibration frequency range needs low <= high (got ", c.vib_freq_lo_hz, " > ", c.vib_freq_hi_hz, " Hz)");
  }
  if (c.vib_tones < 1) return Text("vib_tones must be at least 1 (got ", c.vib_tones, ")");
  if (c.vib_tones * c.vib_freq_hi_hz >= 0.5 * c.rate_hz) {
    return Text("the highest harmonic, vib_tones x high frequency = ", c.vib_tones * c.vib_freq_hi_hz,
                " Hz, must be below Nyquist, rate_hz / 2 = ", 0.5 * c.rate_hz, " Hz");
  }
  if (c.vib_amp_g < 0.0) return Text("vib_amp_g must not be negative (got ", c.vib_amp_g, ")");
  if (c.noise_mg < 0.0) return Text("noise_mg must not be negative (got ", c.noise_mg, ")");
  if (std::abs(c.true_roll_deg) > 180.0) return Text("true_roll_deg must be within [-180, 180] (got ", c.true_roll_deg, ")");
  if (std::abs(c.true_pitch_deg) >= 90.0) return Text("true_pitch_deg must be within (-90, 90) (got ", c.true_pitch_deg, ")");
  return "";
}

int MonteCarloWindowSamples(const MonteCarloConfig& config) {
  return static_cast<int>(std::lround(config.window_s * config.rate_hz));
}

AccelWindow SimulateWindow(const MonteCarloConfig& config, int run, std::vector<SimulatedTone>* tones) {
  const std::string invalid = ValidateMonteCarloConfig(config);
  if (!invalid.empty()) throw std::invalid_argument("leveling Monte Carlo: " + invalid);
  // Separate streams: changing the noise leaves the vibration of every run unchanged.
  const sim::Rng run_rng = sim::Rng(config.seed).Stream("leveling.monte_carlo.run " + std::to_string(run));
  sim::Rng vib_rng = run_rng.Stream("vibration");
  sim::Rng noise_rng = run_rng.Stream("noise");

  const double f_hz = vib_rng.Uniform(config.vib_freq_lo_hz, config.vib_freq_hi_hz);
  std::vector<SimulatedTone> drawn;
  for (int axis = 0; axis < 3; ++axis) {
    if (!config.vib_axes[axis]) continue;
    for (int h = 1; h <= config.vib_tones; ++h) {
      SimulatedTone t;
      t.axis = axis;
      t.harmonic = h;
      t.frequency_hz = h * f_hz;
      t.amplitude_mps2 = vib_rng.Normal(config.vib_amp_g * kStandardGravity_mps2 / h);
      t.phase_rad = vib_rng.Uniform(0.0, kTwoPi);
      drawn.push_back(t);
    }
  }

  AccelWindow w;
  w.rate_hz = config.rate_hz;
  w.source = "simulation";
  const int n = MonteCarloWindowSamples(config);
  w.t_s.reserve(n);
  w.f_b_mps2.reserve(n);
  const Eigen::Vector3d f_rest = SpecificForceAtRest(config.true_roll_deg * kDegToRad,
                                                     config.true_pitch_deg * kDegToRad, kStandardGravity_mps2);
  const double noise_mps2 = config.noise_mg * kMilliG_mps2;
  for (int k = 0; k < n; ++k) {
    const double t = k / config.rate_hz;
    Eigen::Vector3d f = f_rest + noise_rng.Normal3(noise_mps2);
    for (const SimulatedTone& tone : drawn) {
      f[tone.axis] += tone.amplitude_mps2 * std::sin(kTwoPi * tone.frequency_hz * t + tone.phase_rad);
    }
    w.t_s.push_back(t);
    w.f_b_mps2.push_back(f);
  }
  if (tones != nullptr) *tones = std::move(drawn);
  return w;
}

namespace {

/// The options every method gets in the experiment: the configured noise and vibration.
LevelingOptions ExperimentOptions(const MonteCarloConfig& config, const LevelingOptions& options) {
  LevelingOptions method_options = options;
  method_options.accel_noise_mps2 = config.noise_mg * kMilliG_mps2;
  method_options.vib_axes = config.vib_axes;
  method_options.vib_tones = config.vib_tones;
  return method_options;
}

}  // namespace

mc::RunRecord LevelingMcRun(const MonteCarloConfig& config, const LevelingOptions& options, int run) {
  const LevelingOptions method_options = ExperimentOptions(config, options);
  const AccelWindow window = SimulateWindow(config, run);
  const double roll_rad = config.true_roll_deg * kDegToRad, pitch_rad = config.true_pitch_deg * kDegToRad;
  mc::RunRecord record;
  record.run = run;
  record.seed = config.seed;
  for (int m = 0; m < kMethods; ++m) {
    const double t0 = ThreadCpuTime_s();
    const RunOutcome o = Outcome(kMethodFunctions[m](window, method_options), roll_rad, pitch_rad);
    mc::MethodRecord mr;
    mr.method = kMethodNames[m];
    mr.run_time_s = ThreadCpuTime_s() - t0;
    mc::Quantity q = mc::Quantity::Empty("level", "deg", kRadToDeg, "final", {"roll", "pitch"}, {config.window_s});
    const double e[2] = {o.roll_error_rad, o.pitch_error_rad};
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double sigma[2] = {o.roll_sigma_rad > 0.0 ? o.roll_sigma_rad : nan, o.pitch_sigma_rad > 0.0 ? o.pitch_sigma_rad : nan};
    q.SetDiagonal(0, e, sigma);
    mr.quantities.push_back(std::move(q));
    record.methods.push_back(std::move(mr));
  }
  return record;
}

MonteCarloResult RunLevelingMonteCarlo(const MonteCarloConfig& config, const LevelingOptions& options,
                                       const MonteCarloRunOptions& run_options) {
  const std::string invalid = ValidateMonteCarloConfig(config);
  if (!invalid.empty()) throw std::invalid_argument("leveling Monte Carlo: " + invalid);
  const LevelingOptions method_options = ExperimentOptions(config, options);
  const double roll_rad = config.true_roll_deg * kDegToRad, pitch_rad = config.true_pitch_deg * kDegToRad;

  const int workers = MonteCarloWorkers(config.runs, config.threads);
  std::vector<std::vector<RunOutcome>> outcomes(kMethods, std::vector<RunOutcome>(config.runs));
  std::vector<std::array<double, kMethods>> cpu_s(workers, std::array<double, kMethods>{});  // per worker
  const auto body = [&](int run, int worker) {
    const AccelWindow window = SimulateWindow(config, run);
    // One clock reading between methods (it is a system call of ~1 us); the few
    // nanoseconds of Outcome count towards the next method.
    double t0 = ThreadCpuTime_s();
    for (int m = 0; m < kMethods; ++m) {
      const LevelEstimate estimate = kMethodFunctions[m](window, method_options);
      const double t1 = ThreadCpuTime_s();
      cpu_s[worker][m] += t1 - t0;
      t0 = t1;
      outcomes[m][run] = Outcome(estimate, roll_rad, pitch_rad);
    }
  };
  const auto start = std::chrono::steady_clock::now();
  RunParallel(config.runs, workers, body, run_options.progress);
  const std::chrono::duration<double> wall = std::chrono::steady_clock::now() - start;

  MonteCarloResult result;
  result.runs = config.runs;
  result.threads = workers;
  result.run_time_s = wall.count();
  for (int m = 0; m < kMethods; ++m) {
    result.methods.push_back(Reduce(kMethodNames[m], outcomes[m], run_options.keep_errors));
    for (const auto& per_worker : cpu_s) result.methods.back().cpu_time_s += per_worker[m];
  }
  return result;
}

}  // namespace navtwin::leveling
