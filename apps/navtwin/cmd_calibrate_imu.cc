// navtwin calibrate-imu --data RECORD --rig multiposition|pendulum|temperature: the IMU error
// model (scale factor, misalignment, bias, gyro g-sensitivity; temperature polynomials)
// from a calibration record (problems/calibration/imu_calibration.h, docs/calibration-imu.md),
// printed with one sigma per parameter and written as a calibration file (--out) that every
// IMU reader applies with --calibration.
#include <gflags/gflags.h>

#include <cmath>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/calibration_file.h"
#include "core/io/open.h"
#include "core/units.h"
#include "problems/calibration/calibration_run_folder.h"
#include "problems/calibration/handheld.h"
#include "problems/calibration/imu_calibration.h"

DEFINE_string(rig, "",
              "calibrate-imu: multiposition, pendulum or temperature (what --data records), or handheld (--imu)");
DEFINE_double(latitude_deg, NAN, "calibrate-imu --rig handheld: latitude of the place, deg (local gravity)");
DEFINE_double(height_m, 0.0, "calibrate-imu --rig handheld: ellipsoidal height of the place, m (local gravity)");
DEFINE_double(initial_still_s, 30.0, "calibrate-imu --rig handheld: the still period at the start of the record, s");

namespace navtwin::app {

Command CalibrateImuCommand();
namespace {

int Usage(const std::string& why) {
  const std::string usage = CalibrateImuCommand().usage;
  std::cerr << "navtwin calibrate-imu: " << why << "\nusage: " << usage.substr(0, usage.find('\n'))
            << "\n(navtwin calibrate-imu --help: the record files)\n";
  return kExitUsage;
}

/// The command line as one string, for the file's created_by.
std::string CommandLine() {
  std::ostringstream s;
  s << "navtwin calibrate-imu --rig " << FLAGS_rig;
  if (FLAGS_rig == "handheld" && FLAGS_data.empty()) {
    s << " --imu " << FLAGS_imu << " --latitude_deg " << FLAGS_latitude_deg << " --height_m " << FLAGS_height_m;
  } else {
    s << " --data " << FLAGS_data;
  }
  if (FLAGS_method == "recursive") s << " --method recursive";
  return s.str();
}

/// The rig's calibration; the recursive multi-position form prints each position's
/// estimate (text format) and keeps them in *steps.
calibration::ImuCalibrationResult Calibrate(bool recursive, std::vector<calibration::ImuCalibrationResult>* steps) {
  if (recursive) {
    return calibration::CalibrateMultiPositionRecordRecursive(
        FLAGS_data, [steps](const calibration::ImuCalibrationResult& estimate) {
          if (FLAGS_format == "text") std::cout << calibration::RecursiveStepText(estimate, steps->empty());
          steps->push_back(estimate);
        });
  }
  if (FLAGS_rig == "handheld") {
    calibration::HandheldOptions options;
    options.initial_still_s = FLAGS_initial_still_s;
    if (!FLAGS_data.empty()) {
      const calibration::HandheldData data = calibration::ReadHandheldRecord(FLAGS_data, &options);
      return calibration::CalibrateHandheld(data, options);
    }
    calibration::HandheldData data;
    data.imu_path = FLAGS_imu;
    data.imu = ReadAll(*OpenImu(FLAGS_imu, FLAGS_calibration, FLAGS_imu_temperature_degC));
    data.latitude_rad = FLAGS_latitude_deg * kDegToRad;
    data.height_m = FLAGS_height_m;
    return calibration::CalibrateHandheld(data, options);
  }
  if (FLAGS_rig == "multiposition") return calibration::CalibrateMultiPositionRecord(FLAGS_data);
  if (FLAGS_rig == "pendulum") return calibration::CalibratePendulumRecord(FLAGS_data);
  return calibration::CalibrateTemperatureRecord(FLAGS_data);
}

/// --run_dir: the folder (docs/run-folder.md) and with --report its page.
void WriteRunFolder(const calibration::ImuCalibrationResult& result, const CalibrationFile& file,
                    const std::vector<calibration::ImuCalibrationResult>& steps) {
  std::vector<calibration::RunFolderFile> files = {
      {"parameters.csv", [&result](std::ostream& o) { calibration::WriteImuParametersCsv(o, result); }},
      {"residuals.csv", [&result](std::ostream& o) { calibration::WriteImuResidualsCsv(o, result); }}};
  if (!steps.empty()) {
    files.push_back({"convergence.csv", [&steps](std::ostream& o) { calibration::WriteImuConvergenceCsv(o, steps); }});
  }
  calibration::WriteCalibrationRunFolder(FLAGS_run_dir, calibration::ImuCalibrationJson(result, FLAGS_rig, "calibrate-imu"),
                                         file, files);
  std::cerr << "calibrate-imu: run folder " << FLAGS_run_dir << " (summary.json, calibration.yaml, parameters.csv, "
            << "residuals.csv" << (steps.empty() ? "" : ", convergence.csv") << ")\n";
  if (FLAGS_report) WriteRunReport("calibrate-imu", FLAGS_run_dir);
}

int RunCalibrateImu(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("unexpected argument '" + args.front() + "' (the record goes in --data)");
  if (FLAGS_rig == "handheld" && !FLAGS_data.empty()) {
    if (!FLAGS_imu.empty()) return Usage("--rig handheld: give --data RECORD or --imu FILE, not both");
  } else if (FLAGS_rig == "handheld") {
    if (FLAGS_imu.empty()) return Usage("--rig handheld reads --imu FILE (or a record: --data RECORD)");
    if (!std::isfinite(FLAGS_latitude_deg) || std::abs(FLAGS_latitude_deg) > 90.0) {
      return Usage("--rig handheld needs --latitude_deg (the place's latitude, for the local gravity)");
    }
    if (!(FLAGS_initial_still_s > 0.0)) return Usage("--initial_still_s must be > 0");
  } else if (FLAGS_data.empty()) {
    return Usage("--data RECORD is required");
  }
  if (FLAGS_format != "text" && FLAGS_format != "json") return Usage("--format must be text or json");
  if (FLAGS_report && FLAGS_run_dir.empty()) return Usage("--report needs --run_dir DIR (it writes DIR/report.html)");
  if (FLAGS_rig.empty()) return Usage("--rig is required: multiposition, pendulum, temperature or handheld");
  if (FLAGS_rig != "multiposition" && FLAGS_rig != "pendulum" && FLAGS_rig != "temperature" && FLAGS_rig != "handheld") {
    return Usage("unknown --rig '" + FLAGS_rig + "': multiposition, pendulum, temperature or handheld");
  }
  const std::string method = FLAGS_method.empty() ? "batch" : FLAGS_method;
  if (method != "batch" && method != "recursive") return Usage("--method must be batch or recursive");
  if (method == "recursive" && FLAGS_rig != "multiposition") {
    return Usage("--method recursive is the multi-position rig's recursive form (--rig multiposition)");
  }
  std::vector<calibration::ImuCalibrationResult> steps;
  const calibration::ImuCalibrationResult result = Calibrate(method == "recursive", &steps);
  CalibrationFile file;
  file.created_by = CommandLine();
  file.imu = result.calibration;
  if (!FLAGS_run_dir.empty()) WriteRunFolder(result, file, steps);
  if (!FLAGS_out.empty()) WriteCalibrationFile(FLAGS_out, file);
  if (FLAGS_format == "json") {
    std::cout << calibration::ImuCalibrationJson(result, FLAGS_rig) << "\n";
  } else {
    std::cout << calibration::ImuCalibrationText(result, FLAGS_rig);
    if (!FLAGS_out.empty()) std::cout << "calibration file: " << FLAGS_out << "\n";
  }
  return kExitOk;
}

}  // namespace

Command CalibrateImuCommand() {
  return {"calibrate-imu",
          "IMU scale factor, misalignment, bias and g-sensitivity (with sigma) from a calibration record",
          "navtwin calibrate-imu --data RECORD --rig multiposition|pendulum|temperature [--method batch|recursive] "
          "[--out FILE] [--run_dir DIR [--report]] [--format=json]\n"
          "  RECORD is a YAML file naming the IMU files and what the rig did (docs/calibration-imu.md):\n"
          "  - multiposition: {imu, latitude_deg, height_m, trajectory: {kind: multiposition, ...}}, the\n"
          "    table schedule in the simulator's schema, on the IMU's time scale;\n"
          "  - pendulum: {latitude_deg, height_m, runs: [{imu, angle, length_m, mounting}, ...]}, the\n"
          "    angle files t_s,theta_rad from the pivot encoder (docs/calibration-pendulum.md);\n"
          "  - temperature: {order, latitude_deg, height_m, runs: [{temperature_degC, imu, trajectory}]},\n"
          "    one multi-position schedule per chamber temperature, or warm-up runs with\n"
          "    temperature: FILE (t_s,temperature_degC) instead (docs/calibration-temperature.md).\n"
          "  - handheld (no rig; --imu FILE --latitude_deg L [--height_m H] [--initial_still_s 30], or a\n"
          "    record --data RECORD: {imu, latitude_deg, height_m, initial_still_s, counts:\n"
          "    {gyro_rad_s_per_count, accel_mps2_per_count}} for a CSV of raw counts): the sensor put\n"
          "    down by hand in 10 or more orientations, still 2 s or more each, after a still period at\n"
          "    the start (docs/calibration-imu.md \"Without a rig\").\n"
          "  Prints every parameter with one sigma and the parameters the data cannot observe (held\n"
          "  at 0); --out writes the calibration file that --calibration applies to IMU readers; --run_dir\n"
          "  the run folder (docs/run-folder.md: summary, calibration file, parameters, residuals before\n"
          "  and after) and with --report its page (navtwin report DIR).\n"
          "  --method recursive (multiposition): the recursive form, position by position; prints the\n"
          "  estimate after each position (biases and scale factors with sigma) and the final one as\n"
          "  the batch does; --run_dir adds convergence.csv, which the report draws.\n"
          "  Exit 1 for records that cannot calibrate (too few positions, a temperature span too\n"
          "  small for the order, ...), with what is missing; nothing is written then.",
          {"data", "rig", "method", "imu", "calibration", "latitude_deg", "height_m", "initial_still_s", "out", "run_dir",
           "report"},
          &RunCalibrateImu};
}

}  // namespace navtwin::app
