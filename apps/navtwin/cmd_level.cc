// navtwin level --imu F: roll and pitch, with 1-sigma, from one window of a recorded IMU
// file (any format, ULog included) by every leveling method of seed 000: the plain mean,
// the seed's period average, the online filter and the batch twin (problems/leveling).
// The window is checked first for saturated samples and for motion; docs/leveling.md
// lists the fallbacks.
#include <gflags/gflags.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/json_writer.h"
#include "core/rotation.h"
#include "problems/leveling/leveling.h"
#include "problems/leveling/window.h"

DEFINE_bool(allow_motion, false, "level: level even when the window shows motion (rotation or |f| != g)");

namespace navtwin::app {
namespace {

int Usage(const std::string& why) {
  const std::string usage = LevelCommand().usage;
  std::cerr << "navtwin level: " << why << "\nusage: " << usage.substr(0, usage.find('\n'))
            << "\n(navtwin level --help: flags and fallbacks)\n";
  return kExitUsage;
}

/// "x", "xz", "x,y,z", ...: which axes; false when the text names anything else or none.
bool ParseAxes(const std::string& text, std::array<bool, 3>* axes) {
  *axes = {{false, false, false}};
  for (const char c : text) {
    if (c == ',') continue;
    if (c < 'x' || c > 'z') return false;
    (*axes)[c - 'x'] = true;
  }
  return (*axes)[0] || (*axes)[1] || (*axes)[2];
}

/// The leveling options from the flags; an empty string, or why the flags are bad.
std::string OptionsFromFlags(leveling::LevelingOptions* options) {
  if (FlagGiven("noise_mg")) {
    if (!(FLAGS_noise_mg > 0.0) || !std::isfinite(FLAGS_noise_mg)) return "--noise_mg must be a number > 0";
    options->accel_noise_mps2 = FLAGS_noise_mg * kMilliG_mps2;
  }
  if (FlagGiven("vib_axes") && !ParseAxes(FLAGS_vib_axes, &options->vib_axes)) {
    return "--vib_axes must name some of x, y, z (e.g. x or xz), got '" + FLAGS_vib_axes + "'";
  }
  if (FLAGS_vib_tones < 1) return "--vib_tones must be >= 1";
  options->vib_tones = FLAGS_vib_tones;
  return "";
}

double StartFromFlag() { return std::isnan(FLAGS_start_s) ? 0.0 : FLAGS_start_s; }

/// Vibration frequency a method found: the batch's estimate, else rate / period.
double FrequencyHz(const leveling::LevelEstimate& e, double rate_hz) {
  if (e.vib_freq_hz > 0.0) return e.vib_freq_hz;
  return e.period_samples > 0.0 ? rate_hz / e.period_samples : 0.0;
}

void PrintText(const leveling::AccelWindow& w, double start_s, double window_s, const leveling::WindowCheck& check,
               const std::vector<leveling::LevelEstimate>& methods) {
  char line[512];
  std::snprintf(line, sizeof line, "%s: window %.4f..%.4f s after the first IMU sample, %d samples at %.2f Hz\n",
                w.source.c_str(), start_s, start_s + window_s, w.size(), w.rate_hz);
  std::cout << line;
  std::cout << "checks: " << (check.message.empty() ? "ok\n" : "see warnings on stderr\n");
  std::snprintf(line, sizeof line, "%-15s %10s %8s %10s %8s %10s %9s %7s  %s\n", "method", "roll_deg", "1sigma",
                "pitch_deg", "1sigma", "period_smp", "vib_hz", "samples", "note");
  std::cout << line;
  for (const leveling::LevelEstimate& e : methods) {
    std::snprintf(line, sizeof line, "%-15s %10.4f %8.4f %10.4f %8.4f %10.3f %9.2f %7d  %s\n", e.method.c_str(),
                  e.roll_rad * kRadToDeg, e.roll_sigma_rad * kRadToDeg, e.pitch_rad * kRadToDeg,
                  e.pitch_sigma_rad * kRadToDeg, e.period_samples, FrequencyHz(e, w.rate_hz), e.samples_used,
                  e.fallback.empty() ? "" : ("fallback: " + e.fallback).c_str());
    std::cout << line;
  }
}

void PrintJson(const leveling::AccelWindow& w, double start_s, double window_s, const leveling::WindowCheck& check,
               const std::vector<leveling::LevelEstimate>& methods) {
  JsonWriter j(std::cout);
  j.BeginObject()
      .Field("file", w.source)
      .Field("start_s", start_s)
      .Field("window_s", window_s)
      .Field("rate_hz", w.rate_hz)
      .Field("samples", w.size());
  j.Key("checks")
      .BeginObject()
      .Field("saturated_samples", check.saturated_samples)
      .Field("moving", check.moving)
      .Field("message", check.message)
      .EndObject();
  j.Key("methods").BeginObject();
  for (const leveling::LevelEstimate& e : methods) {
    j.Key(e.method)
        .BeginObject()
        .Field("roll_deg", e.roll_rad * kRadToDeg)
        .Field("pitch_deg", e.pitch_rad * kRadToDeg)
        .Field("roll_sigma_deg", e.roll_sigma_rad * kRadToDeg)
        .Field("pitch_sigma_deg", e.pitch_sigma_rad * kRadToDeg)
        .Field("period_samples", e.period_samples)
        .Field("vib_freq_hz", FrequencyHz(e, w.rate_hz))
        .Field("samples_used", e.samples_used)
        .Field("fallback", e.fallback)
        .EndObject();
  }
  j.EndObject().EndObject();
  std::cout << "\n";
}

/// Prints the check's lines on stderr as warnings (or errors, for refused motion).
void Report(const std::string& message, const char* kind) {
  std::size_t at = 0;
  while (at < message.size()) {
    const std::size_t end = message.find('\n', at);
    std::cerr << "navtwin level: " << kind << ": " << message.substr(at, end - at) << "\n";
    at = end == std::string::npos ? message.size() : end + 1;
  }
}

int RunLevel(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("unexpected argument '" + args.front() + "' (the file goes in --imu)");
  if (FLAGS_imu.empty()) return Usage("--imu FILE is required");
  const double start_s = StartFromFlag();
  if (!std::isfinite(start_s) || start_s < 0.0) return Usage("--start_s must be a number >= 0");
  if (!std::isfinite(FLAGS_window_s) || FLAGS_window_s <= 0.0) return Usage("--window_s must be a number > 0");
  leveling::LevelingOptions options;
  const std::string bad = OptionsFromFlags(&options);
  if (!bad.empty()) return Usage(bad);
  if (FLAGS_calibration.empty() && !std::isnan(FLAGS_imu_temperature_degC)) {
    return Usage("--imu_temperature_degC goes with --calibration");
  }

  const leveling::AccelWindow window = leveling::ReadAccelWindow(FLAGS_imu, start_s, FLAGS_window_s,
                                                                 FLAGS_calibration, FLAGS_imu_temperature_degC);
  const leveling::WindowCheck check = leveling::CheckWindow(window, options);
  if (check.moving && !FLAGS_allow_motion) {
    Report(check.message, "error");
    std::cerr << "navtwin level: the vehicle is not at rest in this window: leveling needs it at rest "
                 "(--allow_motion levels anyway)\n";
    return kExitFailure;
  }
  Report(check.message, "warning");
  if (check.saturated_samples > 0) {
    std::cerr << "navtwin level: warning: the batch leaves the saturated samples out of its fit; the "
                 "averaging methods and the filter keep them and may be biased\n";
  }
  const std::vector<leveling::LevelEstimate> methods = leveling::LevelAllMethods(window, options);
  if (FLAGS_format == "json") {
    PrintJson(window, start_s, FLAGS_window_s, check, methods);
  } else {
    PrintText(window, start_s, FLAGS_window_s, check, methods);
  }
  return kExitOk;
}

}  // namespace

Command LevelCommand() {
  return {"level", "Roll and pitch from a window of a recorded IMU file by every leveling method",
          "navtwin level --imu FILE [--start_s S] [--window_s W] [--noise_mg N] [--vib_axes xyz] "
          "[--vib_tones K] [--allow_motion] [--calibration FILE [--imu_temperature_degC T]] [--format=json]\n"
          "  --start_s counts from the first IMU sample (default 0), --window_s defaults to 0.2 s; without\n"
          "  --noise_mg the white noise is estimated from the data; without --vib_axes the batch models\n"
          "  vibration on all three axes. Methods: plain_mean, period_average, filter, batch.\n"
          "  Fallbacks (docs/leveling.md):\n"
          "  - window shorter than two vibration periods, or no autocorrelation peak: period_average and\n"
          "    filter level with the plain mean, the batch without tones, and each says so in its note;\n"
          "  - saturated samples (|f| >= 99.5 % of the accelerometer range, or clipping: >= 3 equal\n"
          "    extreme values in a row): a warning on stderr with their count, axes and times; the\n"
          "    batch leaves them out of its fit, the averaging methods keep them (biased);\n"
          "  - a moving vehicle (mean angular rate > 0.05 rad/s, or mean |f| more than 0.5 m/s^2 from g):\n"
          "    the reason on stderr and exit 1, unless --allow_motion;\n"
          "  - a window beyond the end of the record or with fewer than 8 samples: exit 1.",
          {"imu", "start_s", "window_s", "noise_mg", "vib_axes", "vib_tones", "allow_motion", "calibration",
           "imu_temperature_degC"},
          &RunLevel};
}

}  // namespace navtwin::app
