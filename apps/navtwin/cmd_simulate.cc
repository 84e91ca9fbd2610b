// navtwin simulate: runs a scenario (YAML file or preset) and writes the sensor files,
// the truth and every drawn error into --out.
#include <gflags/gflags.h>

#include <sys/stat.h>

#include <cstdio>
#include <iostream>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/json_writer.h"
#include "core/sim/presets.h"
#include "core/sim/simulator.h"

DEFINE_bool(perfect, false, "Turn every sensor error off (truth-consistent data)");
DEFINE_bool(list_presets, false, "List the preset scenarios and exit");
DEFINE_bool(print_scenario, false, "Print the YAML of --scenario (a preset) and exit");

namespace navtwin::app {
namespace {

int Usage(const std::string& why) {
  std::cerr << "navtwin simulate: " << why << "\nusage: " << SimulateCommand().usage << "\n";
  return kExitUsage;
}

bool IsDir(const std::string& dir) {
  struct stat st;
  return ::stat(dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

int RunSimulate(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("unexpected argument '" + args[0] + "'");
  if (FLAGS_list_presets) {
    for (const std::string& name : sim::PresetNames()) std::cout << name << "\n";
    return kExitOk;
  }
  if (FLAGS_scenario.empty()) return Usage("--scenario is required");
  if (FLAGS_print_scenario) {
    const auto yaml = sim::PresetYaml(FLAGS_scenario);
    if (!yaml) return Usage("'" + FLAGS_scenario + "' is not a preset (see --list_presets)");
    std::cout << *yaml;
    return kExitOk;
  }
  if (FLAGS_out.empty()) return Usage("--out is required");
  const sim::Scenario scenario = sim::LoadScenario(FLAGS_scenario);
  if (::mkdir(FLAGS_out.c_str(), 0755) != 0 && !IsDir(FLAGS_out)) {
    return Usage("cannot create the output folder " + FLAGS_out);
  }
  sim::SimulationOptions options;
  options.seed = FLAGS_seed;
  options.perfect = FLAGS_perfect;
  options.progress = [&](double fraction) {
    std::fprintf(stderr, "\rsimulate %s: %3.0f %%", scenario.name.c_str(), 100.0 * fraction);
    if (fraction >= 1.0) std::fprintf(stderr, "\n");
  };
  const sim::SimulationReport r = sim::Simulate(scenario, options, FLAGS_out);
  if (FLAGS_format == "json") {
    JsonWriter w(std::cout);
    w.BeginObject()
        .Field("scenario", scenario.name)
        .Field("seed", static_cast<long long>(FLAGS_seed))
        .Field("perfect", FLAGS_perfect)
        .Field("duration_s", scenario.duration_s)
        .Field("imu_samples", r.imu_samples)
        .Field("gnss_samples", r.gnss_samples)
        .Field("mag_samples", r.mag_samples)
        .Field("baro_samples", r.baro_samples)
        .Field("master_samples", r.master_samples)
        .Field("run_time_s", r.run_time_s);
    w.Key("files").BeginArray();
    for (const std::string& f : r.files) w.Value(f);
    w.EndArray().EndObject();
    std::cout << "\n";
  } else {
    std::printf("simulated %s (seed %llu%s): %.1f s, %zu IMU, %zu GNSS, %zu mag, %zu baro, "
                "%zu master samples in %.2f s\n",
                scenario.name.c_str(), static_cast<unsigned long long>(FLAGS_seed),
                FLAGS_perfect ? ", perfect sensors" : "", scenario.duration_s, r.imu_samples,
                r.gnss_samples, r.mag_samples, r.baro_samples, r.master_samples, r.run_time_s);
    for (const std::string& f : r.files) std::printf("  %s\n", f.c_str());
  }
  return kExitOk;
}

}  // namespace

Command SimulateCommand() {
  return {"simulate",
          "Simulate a scenario: IMU, GNSS, magnetometer, barometer, master INS, truth, errors",
          "navtwin simulate --scenario FILE|PRESET --out DIR [--seed N] [--perfect] "
          "[--format=json]\n       navtwin simulate --list_presets | --print_scenario --scenario PRESET",
          {"scenario", "out", "seed", "perfect", "list_presets", "print_scenario"},
          &RunSimulate};
}

}  // namespace navtwin::app
