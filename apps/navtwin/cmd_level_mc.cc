// navtwin level-mc: the Monte Carlo experiment of seed 000 (problems/leveling/monte_carlo.h)
// — many short windows of a resting accelerometer triad under rotor vibration, levelled by
// plain_mean, period_average, filter and batch; per method the roll and pitch RMS and
// largest errors, the mean reported sigma, fallbacks and CPU time. The defaults are the
// seed's experiment.
#include <gflags/gflags.h>

#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/atomic_file.h"
#include "core/io/folder.h"
#include "core/io/json_writer.h"
#include "problems/leveling/monte_carlo.h"

// Shared with `navtwin level` (defined in cmd_level.cc): window_s 0.2, noise_mg 50,
// vib_axes "x", vib_tones 1 by default, the seed's values.
DEFINE_double(rate_hz, 600.0, "level-mc: accelerometer sample rate, Hz");
DEFINE_string(vib_freq_hz, "22:24", "level-mc: vibration fundamental, LO:HI (drawn uniformly per run) or one value, Hz");
DEFINE_double(vib_amp_g, 1.0, "level-mc: 1 sigma of the zero-mean normal vibration amplitude, g");
DEFINE_double(true_roll_deg, 0.0, "level-mc: true roll, deg");
DEFINE_double(true_pitch_deg, 0.0, "level-mc: true pitch, deg");
DEFINE_bool(batch_covariance, false, "level-mc: batch standard deviations from ceres::Covariance in every run (slower)");

namespace navtwin::app {
namespace {

using leveling::MethodStatistics;
using leveling::MonteCarloConfig;
using leveling::MonteCarloResult;

int Usage(const std::string& why) {
  std::cerr << "navtwin level-mc: " << why << "\nusage: " << LevelMcCommand().usage << "\n";
  return kExitUsage;
}

/// "x", "xyz", "x,y,z" (any order, case-insensitive) -> axes; empty string on success,
/// else what is wrong.
std::string ParseAxes(const std::string& text, std::array<bool, 3>* axes) {
  *axes = {{false, false, false}};
  for (const char c : text) {
    const char l = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (l == ',') continue;
    if (l < 'x' || l > 'z') return "--vib_axes takes the letters x, y, z (got '" + text + "')";
    (*axes)[l - 'x'] = true;
  }
  if (!(*axes)[0] && !(*axes)[1] && !(*axes)[2]) return "--vib_axes names no axis (use x, y and/or z)";
  return "";
}

bool ParseNumber(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  return *end == '\0';
}

/// "LO:HI" or "F" -> the frequency range; false when malformed.
bool ParseRange(const std::string& text, double* lo, double* hi) {
  const std::size_t colon = text.find(':');
  if (colon == std::string::npos) return ParseNumber(text, lo) && ParseNumber(text, hi);
  return ParseNumber(text.substr(0, colon), lo) && ParseNumber(text.substr(colon + 1), hi);
}

std::string AxesText(const std::array<bool, 3>& axes) {
  std::string s;
  for (int i = 0; i < 3; ++i) {
    if (axes[i]) s += static_cast<char>('x' + i);
  }
  return s;
}

void WriteErrorsCsv(const std::string& path, const MonteCarloResult& r) {
  AtomicFile f(path);
  std::ostream& o = f.stream();
  o << "run";
  for (const MethodStatistics& m : r.methods) o << "," << m.method << "_pitch_deg," << m.method << "_roll_deg";
  o << "\n";
  for (int run = 0; run < r.runs; ++run) {
    o << run;
    for (const MethodStatistics& m : r.methods) o << "," << m.pitch_error_deg[run] << "," << m.roll_error_deg[run];
    o << "\n";
  }
  f.Commit();
}

/// A table cell: `x` printed with `format`, or "-" when it is NaN (nothing to report).
std::string Cell(double x, const char* format) {
  if (std::isnan(x)) return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

void PrintText(const MonteCarloConfig& c, const MonteCarloResult& r) {
  char line[320];
  std::snprintf(line, sizeof line,
                "level-mc: %d runs of %d samples at %g Hz (%g s); vibration on %s, %g-%g Hz, %g g (1 sigma), "
                "%d tone%s; noise %g mg; truth roll %g deg, pitch %g deg; seed %llu; %d thread%s\n",
                r.runs, leveling::MonteCarloWindowSamples(c), c.rate_hz, c.window_s, AxesText(c.vib_axes).c_str(),
                c.vib_freq_lo_hz, c.vib_freq_hi_hz, c.vib_amp_g, c.vib_tones, c.vib_tones == 1 ? "" : "s",
                c.noise_mg, c.true_roll_deg, c.true_pitch_deg, static_cast<unsigned long long>(c.seed), r.threads,
                r.threads == 1 ? "" : "s");
  std::cout << line;
  std::snprintf(line, sizeof line, "%-15s %10s %10s %10s %10s %12s %11s %10s %9s %8s\n", "method", "pitch_rms",
                "pitch_max", "roll_rms", "roll_max", "pitch_sigma", "roll_sigma", "err/sigma", "fallbacks", "cpu_s");
  std::cout << line;
  std::snprintf(line, sizeof line, "%-15s %10s %10s %10s %10s %12s %11s %10s %9s %8s\n", "", "(deg)", "(deg)",
                "(deg)", "(deg)", "(mean,deg)", "(mean,deg)", "(rms)", "(runs)", "(s)");
  std::cout << line;
  for (const MethodStatistics& m : r.methods) {
    std::snprintf(line, sizeof line, "%-15s %10.4f %10.4f %10.4f %10.4f %12s %11s %10s %9d %8.3f\n",
                  m.method.c_str(), m.pitch_rms_deg, m.pitch_max_deg, m.roll_rms_deg, m.roll_max_deg,
                  Cell(m.pitch_sigma_mean_deg, "%.4f").c_str(), Cell(m.roll_sigma_mean_deg, "%.4f").c_str(),
                  Cell(m.pitch_error_over_sigma_rms, "%.3f").c_str(), m.fallbacks, m.cpu_time_s);
    std::cout << line;
  }
  std::snprintf(line, sizeof line, "run time %.3f s (wall)\n", r.run_time_s);
  std::cout << line;
  std::cout << "err/sigma: RMS of pitch error / reported sigma (1 when the sigma is right)";
  for (const MethodStatistics& m : r.methods) {
    if (!std::isnan(m.pitch_sigma_mean_deg)) continue;
    std::cout << "; '-': " << m.method << " reported no sigma"
              << (m.method == "batch" && !FLAGS_batch_covariance ? " (see --batch_covariance)" : "");
  }
  std::cout << "\n";
  for (const MethodStatistics& m : r.methods) {
    if (m.fallbacks > 0) {
      std::cout << "fallback (" << m.method << ", " << m.fallbacks << (m.fallbacks == 1 ? " run" : " runs")
                << "; the first): " << m.first_fallback << "\n";
    }
  }
}

/// The --format=json object; in a run folder's summary.json led by "command".
void WriteResultJson(std::ostream& out, const MonteCarloResult& r, bool with_command) {
  JsonWriter w(out);
  w.BeginObject();
  if (with_command) w.Field("command", "level-mc");
  w.Field("runs", r.runs).Field("run_time_s", r.run_time_s);
  w.Key("methods").BeginObject();
  for (const MethodStatistics& m : r.methods) {
    w.Key(m.method)
        .BeginObject()
        .Field("pitch_rms_deg", m.pitch_rms_deg)
        .Field("pitch_max_deg", m.pitch_max_deg)
        .Field("roll_rms_deg", m.roll_rms_deg)
        .Field("roll_max_deg", m.roll_max_deg)
        .Field("pitch_sigma_mean_deg", m.pitch_sigma_mean_deg)
        .Field("roll_sigma_mean_deg", m.roll_sigma_mean_deg)
        .Field("pitch_error_over_sigma_rms", m.pitch_error_over_sigma_rms)
        .Field("fallbacks", m.fallbacks)
        .Field("cpu_time_s", m.cpu_time_s)
        .EndObject();
  }
  w.EndObject().EndObject();
  out << "\n";
}

/// --out DIR (docs/run-folder.md): DIR/summary.json and DIR/errors.csv (every run's errors).
void WriteRunFolder(const MonteCarloResult& r) {
  EnsureFolder(FLAGS_out);
  WriteErrorsCsv(FLAGS_out + "/errors.csv", r);
  AtomicFile summary(FLAGS_out + "/summary.json");
  WriteResultJson(summary.stream(), r, true);
  summary.Commit();
  std::cerr << "level-mc: run folder " << FLAGS_out << " (summary.json, errors.csv)\n";
}

/// Progress on stderr in tenths of the runs (long experiments only).
MonteCarloProgress TenthsProgress(int runs) {
  if (runs < 2000) return nullptr;
  return [](int done, int total) {
    if (done % (total / 10) == 0 || done == total) {
      std::fprintf(stderr, "level-mc: %d/%d runs\n", done, total);
    }
  };
}

int RunLevelMc(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("unexpected argument '" + args[0] + "'");
  MonteCarloConfig c;
  c.runs = FLAGS_runs;
  c.rate_hz = FLAGS_rate_hz;
  c.window_s = FLAGS_window_s;
  const std::string axes_error = ParseAxes(FLAGS_vib_axes, &c.vib_axes);
  if (!axes_error.empty()) return Usage(axes_error);
  if (!ParseRange(FLAGS_vib_freq_hz, &c.vib_freq_lo_hz, &c.vib_freq_hi_hz)) {
    return Usage("--vib_freq_hz takes LO:HI or one frequency in Hz (got '" + FLAGS_vib_freq_hz + "')");
  }
  c.vib_amp_g = FLAGS_vib_amp_g;
  c.vib_tones = FLAGS_vib_tones;
  c.noise_mg = FLAGS_noise_mg;
  c.true_roll_deg = FLAGS_true_roll_deg;
  c.true_pitch_deg = FLAGS_true_pitch_deg;
  c.seed = FLAGS_seed;
  if (FLAGS_threads < 0) return Usage("--threads must be 0 (all cores) or positive");
  if (FLAGS_report && FLAGS_out.empty()) return Usage("--report needs --out DIR (it writes DIR/report.html)");
  c.threads = FLAGS_threads;
  const std::string invalid = leveling::ValidateMonteCarloConfig(c);
  if (!invalid.empty()) return Usage(invalid);

  leveling::LevelingOptions options;
  options.batch_covariance = FLAGS_batch_covariance;
  leveling::MonteCarloRunOptions run_options;
  run_options.keep_errors = !FLAGS_errors_csv.empty() || !FLAGS_out.empty();
  run_options.progress = TenthsProgress(c.runs);
  const MonteCarloResult result = leveling::RunLevelingMonteCarlo(c, options, run_options);
  if (!FLAGS_errors_csv.empty()) WriteErrorsCsv(FLAGS_errors_csv, result);
  if (!FLAGS_out.empty()) WriteRunFolder(result);
  if (!FLAGS_out.empty() && FLAGS_report) WriteRunReport("level-mc", FLAGS_out);
  if (FLAGS_format == "json") {
    WriteResultJson(std::cout, result, false);
  } else {
    PrintText(c, result);
  }
  return kExitOk;
}

}  // namespace

Command LevelMcCommand() {
  return {"level-mc",
          "Monte Carlo of leveling under rotor vibration (seed 000): every method's roll/pitch errors",
          "navtwin level-mc [--runs N] [--rate_hz 600] [--window_s 0.2] [--vib_axes x|xyz|x,y,z] "
          "[--vib_freq_hz 22:24] [--vib_amp_g 1] [--vib_tones 1] [--noise_mg 50] [--true_roll_deg 0] "
          "[--true_pitch_deg 0] [--seed S] [--threads 2] [--errors_csv FILE] [--out DIR [--report]] [--batch_covariance] "
          "[--format=json]",
          {"runs", "rate_hz", "window_s", "vib_axes", "vib_freq_hz", "vib_amp_g", "vib_tones", "noise_mg",
           "true_roll_deg", "true_pitch_deg", "seed", "threads", "errors_csv", "out", "report", "batch_covariance"},
          &RunLevelMc};
}

}  // namespace navtwin::app
