#include "apps/navtwin/common_flags.h"

#include "problems/report/report.h"

#include <cmath>
#include <iostream>

DEFINE_string(format, "text", "Output format of printed results: text or json");
DEFINE_string(out, "",
              "Output: a folder (ins, navigate, smooth, simulate; created if missing) or a file (convert, "
              "allan: the curve as CSV; calibrate-imu, calibrate-mag: the calibration file)");
DEFINE_string(run_dir, "",
              "calibrate-imu, calibrate-mag: also write the run folder (summary.json, calibration.yaml, residuals "
              "before and after) that navtwin report draws; created if missing");
DEFINE_uint64(seed, 1, "Random seed of the simulation: the same seed gives the same data, byte for byte "
                       "(Monte Carlo: the first run's seed, run r uses seed + r)");
DEFINE_int32(runs, 10000, "Number of Monte Carlo runs (level-mc: default 10000; inflight-mc: 50 when not given)");
DEFINE_int32(threads, 2, "Monte Carlo worker threads (0: all cores); the results do not depend on it");
DEFINE_string(errors_csv, "", "Monte Carlo: write every run's errors of every method to this CSV");
DEFINE_string(method, "",
              "Estimation method: inflight-align distance, kalman, batch or all; transfer-align order1, order2, "
              "history, batch or all; transfer-align-ansfl order2, history or batch; calibrate-imu batch or recursive; calibrate-mag "
              "ellipsoid, planar, bidirectional or recursive");
DEFINE_bool(demo, false,
            "Simulate a built-in demo into --out and run on it with truth (ins: a 10-min flight; smooth: "
            "--demo_scenario)");

DEFINE_string(imu, "", "IMU file (any format `navtwin info` knows)");
DEFINE_string(gnss, "", "GNSS file: KF-GINS GNSS text, RTKLIB .pos or ULog");
DEFINE_string(mag, "", "Magnetometer file (navtwin CSV, Xsens DOT raw, ULog)");
DEFINE_string(baro, "", "Barometer file (navtwin CSV, ULog)");
DEFINE_string(truth, "", "Reference trajectory (navigation file) to compute errors against");
DEFINE_string(init_from, "", "Navigation file whose record at --start_s sets the initial state");
DEFINE_string(data, "",
              "Recorded data set: calibrate-imu the rig's record YAML; transfer-align-ansfl the "
              "ansfl-quadrotor folder (with StraightLine/ and Horizontal/)");
DEFINE_string(config, "",
              "YAML configuration of the method (navigate, smooth: docs/gnss-ins.md; inflight-align, inflight-mc: "
              "data/configs/inflight-mach07-south.yaml; transfer-align, transfer-align-ansfl: "
              "data/configs/transfer-alignment-high-maneuver.yaml)");
DEFINE_string(scenario, "", "Simulated scenario: a preset name (see simulate --list_presets) or a scenario YAML");
DEFINE_string(calibration, "",
              "Calibration file (docs/calibration-file.md) applied as the IMU (its imu section) and the "
              "magnetometer (its mag section) are read");
DEFINE_double(imu_temperature_degC, NAN,
              "IMU temperature at which the calibration's temperature terms are evaluated, degC "
              "(default: the calibration file's reference temperature)");

DEFINE_double(start_s, NAN,
              "Start time, s (ins, navigate, smooth, inflight-align, transfer-align: default the initial "
              "record, or the first IMU interval; level: seconds after the first IMU sample, default 0)");
DEFINE_double(end_s, INFINITY, "Stop after this time, s");
DEFINE_double(output_rate_hz, 0.0, "Solution output rate, Hz (0: every IMU epoch)");
DEFINE_double(std_rate_hz, 1.0,
              "navigate, smooth: rate of std.csv and imu_errors.csv among the output epochs, Hz (0: every output "
              "epoch; default 1, or the configuration's std_rate_hz)");

DEFINE_double(window_s, 0.2, "Leveling window length, s");
DEFINE_double(noise_mg, 50.0,
              "Accelerometer white noise, 1 sigma per axis, mg (level-mc: simulated; level: assumed by the "
              "methods, estimated from the data when not given)");
DEFINE_string(vib_axes, "x",
              "Body axes with vibration, any of x, y, z (level-mc: simulated; level: modelled by the batch, "
              "all three when not given)");
DEFINE_int32(vib_tones, 1, "Vibration tones per axis: the fundamental and harmonics up to this multiple");

namespace navtwin::app {

bool FlagGiven(const char* name) {
  const gflags::CommandLineFlagInfo info = gflags::GetCommandLineFlagInfoOrDie(name);
  if (info.current_value != info.default_value) return true;
  // Set on the command line to its default value (e.g. --variance_components=true over a
  // configuration that turns it off): gflags marks it modified, so it is not is_default.
  // An unset flag whose default is NaN is not is_default either (NaN != NaN): its text
  // equals the default's, "nan".
  return !info.is_default && info.default_value != "nan";
}

void WriteRunReport(const std::string& command, const std::string& dir) {
  report::ReportOptions options;
  options.run_dirs = {dir};
  options.out_path = dir + "/report.html";
  options.progress = &std::cerr;
  const report::ReportSummary summary = report::WriteReport(options);
  std::cerr << command << ": report " << options.out_path << " (" << summary.figures << " figures, "
            << summary.run_time_s << " s)\n";
}

}  // namespace navtwin::app
