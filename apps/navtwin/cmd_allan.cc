// navtwin allan FILE: the overlapping Allan deviation of each IMU axis of a (static)
// record, with angle/velocity random walk, bias instability and rate random walk read off
// the curve (IEEE Std 952 slopes, core/allan.h). Gyros in deg/h, accelerometers in ug.
#include <gflags/gflags.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/allan.h"
#include "core/calibration_file.h"
#include "core/io/atomic_file.h"
#include "core/io/input_error.h"
#include "core/io/json_writer.h"
#include "core/io/open.h"
#include "core/rotation.h"
#include "core/units.h"

DEFINE_string(axis, "all", "allan: axis to analyse: gx, gy, gz (gyros), ax, ay, az (accelerometers) or all");

namespace navtwin::app {
namespace {

constexpr double kIrregularFraction = 0.1;   // an interval this far from tau0 is reported

/// One IMU axis. Its Allan deviation and bias instability are shown in deg/h (gyros) or
/// ug (accelerometers); N and K in the units of the simulator's YAML keys.
struct Axis {
  const char* name;
  int index;   // 0..2 within its triad
  bool gyro;
  const char* unit_key;  // for CSV/JSON keys: "deg_h" or "ug"
};

constexpr Axis kAxes[] = {{"gx", 0, true, "deg_h"}, {"gy", 1, true, "deg_h"}, {"gz", 2, true, "deg_h"},
                          {"ax", 0, false, "ug"},   {"ay", 1, false, "ug"},   {"az", 2, false, "ug"}};

double RateScale(const Axis& a) { return a.gyro ? 1.0 / kDegPerHour_radps : 1.0 / kMicroG_mps2; }
/// N: rad/sqrt(s) -> deg/sqrt(h); m/s/sqrt(s) -> m/s/sqrt(h).
double WhiteScale(const Axis& a) { return (a.gyro ? kRadToDeg : 1.0) * kSqrtHour_sqrts; }
/// K: rad/s/sqrt(s) -> deg/h/sqrt(h); m/s^2/sqrt(s) -> ug/sqrt(h).
double WalkScale(const Axis& a) { return RateScale(a) * kSqrtHour_sqrts; }

struct AxisResult {
  Axis axis;
  std::vector<AllanPoint> curve;  // SI
  AllanNoiseFit fit;              // SI
};

/// The IMU file's rate series of the chosen axes; a record too short names the file.
ImuRateRecord ReadRates(const std::string& path, const std::vector<Axis>& axes) {
  const std::vector<ImuSample> imu = ReadAll<ImuSample>(*OpenImu(path, FLAGS_calibration, FLAGS_imu_temperature_degC));
  std::vector<int> indices;
  for (const Axis& a : axes) indices.push_back(a.index + (a.gyro ? 0 : 3));
  try {
    return ImuRates(imu, indices, kIrregularFraction);
  } catch (const std::invalid_argument& e) {
    throw InputError(path, 0, "", e.what());
  }
}

std::vector<AxisResult> Analyse(const ImuRateRecord& r, const std::vector<Axis>& axes) {
  std::vector<AxisResult> out;
  for (std::size_t i = 0; i < axes.size(); ++i) {
    AxisResult a{axes[i], OverlappingAllanDeviation(r.rates[i], r.tau0_s), {}};
    a.fit = FitAllanNoise(a.curve);
    out.push_back(std::move(a));
  }
  return out;
}

void WriteCsv(const std::string& path, const std::vector<AxisResult>& results) {
  AtomicFile f(path);
  std::ostream& o = f.stream();
  o << "tau_s,clusters";
  for (const AxisResult& a : results) o << "," << a.axis.name << "_" << a.axis.unit_key;
  o << "\n";
  for (std::size_t k = 0; k < results.front().curve.size(); ++k) {
    o << results.front().curve[k].tau_s << "," << results.front().curve[k].clusters;
    for (const AxisResult& a : results) o << "," << a.curve[k].adev * RateScale(a.axis);
    o << "\n";
  }
  f.Commit();
}

std::string Number(double x, const char* fmt) {
  if (std::isnan(x)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, x);
  return buf;
}

void PrintFitLine(const AxisResult& a) {
  const AllanNoiseFit& f = a.fit;
  const bool g = a.axis.gyro;
  const std::string bias = Number(f.bias_instability * RateScale(a.axis), "%.4g");
  std::cout << "  " << a.axis.name << ": " << (g ? "ARW " : "VRW ") << Number(f.white_noise * WhiteScale(a.axis), "%.4g")
            << (g ? " deg/sqrt(h)" : " m/s/sqrt(h)") << "   bias instability "
            << (f.bias_instability_is_bound ? "< " + bias : bias) << (g ? " deg/h" : " ug")
            << (f.bias_instability_is_bound ? " (no flat region: upper bound)" : "") << "   "
            << (g ? "RRW " : "acceleration RW ") << Number(f.rate_random_walk * WalkScale(a.axis), "%.4g")
            << (g ? " deg/h/sqrt(h)" : " ug/sqrt(h)") << "\n";
}

void PrintText(const std::string& path, const ImuRateRecord& r, const std::vector<AxisResult>& results) {
  char line[256];
  std::snprintf(line, sizeof line, "%s: %zu IMU samples, tau0 %.6f s (%.3f Hz), %.3f s\n", path.c_str(),
                r.samples, r.tau0_s, 1.0 / r.tau0_s, r.duration_s);
  std::cout << line;
  if (r.irregular_intervals > 0) {
    std::cout << "note: " << r.irregular_intervals << " intervals differ from tau0 by more than 10 % (gaps or jitter); "
              << "the Allan deviation assumes uniform sampling\n";
  }
  std::cout << "Overlapping Allan deviation: gyros in deg/h, accelerometers in ug; clusters = "
               "independent clusters of length tau (relative error ~ 1/sqrt(2 (clusters - 1)))\n";
  std::snprintf(line, sizeof line, "%12s %9s", "tau_s", "clusters");
  std::cout << line;
  for (const AxisResult& a : results) {
    std::snprintf(line, sizeof line, " %12s", (std::string(a.axis.name) + "_" + a.axis.unit_key).c_str());
    std::cout << line;
  }
  std::cout << "\n";
  for (std::size_t k = 0; k < results.front().curve.size(); ++k) {
    const AllanPoint& p = results.front().curve[k];
    std::snprintf(line, sizeof line, "%12.6g %9zu", p.tau_s, p.clusters);
    std::cout << line;
    for (const AxisResult& a : results) {
      std::snprintf(line, sizeof line, " %12.5g", a.curve[k].adev * RateScale(a.axis));
      std::cout << line;
    }
    std::cout << "\n";
  }
  std::cout << "Noise read off the curve (IEEE Std 952 slopes; '-' where the curve shows no such region):\n";
  for (const AxisResult& a : results) PrintFitLine(a);
}

void PrintJson(const std::string& path, const ImuRateRecord& r, const std::vector<AxisResult>& results) {
  JsonWriter w(std::cout);
  w.BeginObject()
      .Field("path", path)
      .Field("samples", r.samples)
      .Field("tau0_s", r.tau0_s)
      .Field("duration_s", r.duration_s)
      .Field("irregular_intervals", r.irregular_intervals);
  w.Key("axes").BeginArray();
  for (const AxisResult& a : results) {
    const bool g = a.axis.gyro;
    const std::string unit = a.axis.unit_key;
    w.BeginObject().Field("axis", a.axis.name);
    w.Key("tau_s").BeginArray();
    for (const AllanPoint& p : a.curve) w.Value(p.tau_s);
    w.EndArray().Key("clusters").BeginArray();
    for (const AllanPoint& p : a.curve) w.Value(p.clusters);
    w.EndArray().Key("adev_" + unit).BeginArray();
    for (const AllanPoint& p : a.curve) w.Value(p.adev * RateScale(a.axis));
    w.EndArray();
    w.Key("fit")
        .BeginObject()
        .Field(g ? "arw_deg_sqrt_h" : "vrw_m_s_sqrt_h", a.fit.white_noise * WhiteScale(a.axis))
        .Field("bias_instability_" + unit, a.fit.bias_instability * RateScale(a.axis))
        .Field("bias_instability_is_upper_bound", a.fit.bias_instability_is_bound)
        .Field(g ? "rate_random_walk_deg_h_sqrt_h" : "acceleration_random_walk_ug_sqrt_h",
               a.fit.rate_random_walk * WalkScale(a.axis))
        .EndObject();
    w.EndObject();
  }
  w.EndArray().EndObject();
  std::cout << "\n";
}

int Usage(const std::string& why) {
  std::cerr << "navtwin allan: " << why << "\nusage: " << AllanCommand().usage << "\n";
  return kExitUsage;
}

int RunAllan(const std::vector<std::string>& args) {
  if (args.size() != 1) return Usage("expected one IMU file");
  std::vector<Axis> axes;
  for (const Axis& a : kAxes) {
    if (FLAGS_axis == "all" || FLAGS_axis == a.name) axes.push_back(a);
  }
  if (axes.empty()) return Usage("--axis must be gx, gy, gz, ax, ay, az or all");
  if (FLAGS_calibration.empty() && !std::isnan(FLAGS_imu_temperature_degC)) {
    return Usage("--imu_temperature_degC goes with --calibration");
  }
  const ImuRateRecord record = ReadRates(args[0], axes);
  const std::vector<AxisResult> results = Analyse(record, axes);
  if (!FLAGS_out.empty()) WriteCsv(FLAGS_out, results);
  if (FLAGS_format == "json") {
    PrintJson(args[0], record, results);
  } else {
    PrintText(args[0], record, results);
  }
  return kExitOk;
}

}  // namespace

Command AllanCommand() {
  return {"allan", "Allan deviation of IMU axes with ARW, bias instability and rate random walk",
          "navtwin allan FILE [--axis gx|gy|gz|ax|ay|az|all] [--out CSV] "
          "[--calibration FILE [--imu_temperature_degC T]] [--format=json]",
          {"axis", "out", "calibration", "imu_temperature_degC"},
          &RunAllan};
}

}  // namespace navtwin::app
