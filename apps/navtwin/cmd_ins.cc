// navtwin ins: pure inertial navigation over an IMU record; writes OUT/nav.nav (KF-GINS
// navigation format) and, with --truth, prints the error table. --demo simulates the
// built-in flight into OUT first and navigates it against its own truth.
#include <gflags/gflags.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/calibration_file.h"
#include "core/io/folder.h"
#include "core/io/input_error.h"
#include "core/io/json_writer.h"
#include "core/io/kfgins.h"
#include "core/io/open.h"
#include "core/rotation.h"
#include "problems/ins/demo_flight.h"
#include "problems/ins/imu_gaps.h"
#include "problems/ins/pure_ins.h"

DEFINE_double(init_lat_deg, NAN, "Initial latitude, deg");
DEFINE_double(init_lon_deg, NAN, "Initial longitude, deg");
DEFINE_double(init_h_m, 0.0, "Initial ellipsoidal height, m");
DEFINE_double(init_vn_mps, 0.0, "Initial north velocity, m/s");
DEFINE_double(init_ve_mps, 0.0, "Initial east velocity, m/s");
DEFINE_double(init_vd_mps, 0.0, "Initial down velocity, m/s");
DEFINE_double(init_roll_deg, 0.0, "Initial roll, deg");
DEFINE_double(init_pitch_deg, 0.0, "Initial pitch, deg");
DEFINE_double(init_yaw_deg, NAN, "Initial yaw (heading), deg");
DEFINE_double(hold_height_m, NAN, "Hold the height at this value (damps the unstable vertical channel)");
DEFINE_double(max_bridge_gap_s, 0.1,
              "IMU gaps (intervals over 1.5 nominal) up to this are bridged by spreading the next sample's "
              "increments, longer ones stop the run, s");
DEFINE_double(demo_rate_hz, 100.0, "IMU rate of the demo flight, Hz");
DEFINE_double(demo_duration_s, 600.0, "Length of the demo flight, s");

namespace navtwin::app {
namespace {

std::optional<double> Optional(double x) { return std::isnan(x) ? std::nullopt : std::optional<double>(x); }

/// The initial state from the flags (--init_lat_deg ... --init_yaw_deg), at start_s.
NavState StateFromFlags(double t_s) {
  NavState s;
  s.t_s = t_s;
  s.lat_rad = FLAGS_init_lat_deg * kDegToRad;
  s.lon_rad = FLAGS_init_lon_deg * kDegToRad;
  s.h_m = FLAGS_init_h_m;
  s.v_n_mps = Eigen::Vector3d(FLAGS_init_vn_mps, FLAGS_init_ve_mps, FLAGS_init_vd_mps);
  s.q_n_b = QuatFromEuler(FLAGS_init_roll_deg * kDegToRad, FLAGS_init_pitch_deg * kDegToRad,
                          FLAGS_init_yaw_deg * kDegToRad);
  return s;
}

/// Start of the first IMU interval of a file (t - dt of its first sample).
double FirstImuEpoch(const std::string& imu_path) {
  auto reader = OpenImu(imu_path);
  ImuSample s;
  if (!reader->Next(&s)) throw InputError(imu_path, 0, "", "the file holds no IMU sample");
  return s.t_s - s.dt_s;
}

struct Row {
  const char* label;
  int component;
  double scale;
};
constexpr Row kRows[] = {{"pos N [m]", 0, 1.0},         {"pos E [m]", 1, 1.0},
                         {"pos D [m]", 2, 1.0},         {"vel N [m/s]", 3, 1.0},
                         {"vel E [m/s]", 4, 1.0},       {"vel D [m/s]", 5, 1.0},
                         {"roll [deg]", 6, kRadToDeg},  {"pitch [deg]", 7, kRadToDeg},
                         {"yaw [deg]", 8, kRadToDeg}};
constexpr const char* kJsonKeys[] = {"pos_n_m", "pos_e_m", "pos_d_m",   "vel_n_mps", "vel_e_mps",
                                     "vel_d_mps", "roll_deg", "pitch_deg", "yaw_deg"};

void PrintText(const PureInsResult& r, const NavState& initial, const std::string& nav_path) {
  std::printf("pure inertial navigation: %zu IMU samples, %.3f .. %.3f s, run time %.3f s\n",
              r.imu_samples, initial.t_s, r.final_state.t_s, r.run_time_s);
  std::printf("solution: %s\n", nav_path.c_str());
  if (!r.errors) return;
  const NavErrorStats& e = *r.errors;
  std::printf("errors against truth (%zu epochs), estimate minus truth:\n", e.count());
  std::printf("  %-12s %14s %14s %14s\n", "", "RMS", "max |.|", "final");
  for (const Row& row : kRows) {
    std::printf("  %-12s %14.6g %14.6g %14.6g\n", row.label, e.Rms(row.component) * row.scale,
                e.Max(row.component) * row.scale, e.Final(row.component) * row.scale);
  }
  std::printf("  %-12s %14.6g %14.6g\n", "horiz. [m]", e.HorizontalRms_m(), e.HorizontalMax_m());
}

void PrintJson(const PureInsResult& r, const NavState& initial, const std::string& nav_path) {
  JsonWriter w(std::cout);
  w.BeginObject()
      .Field("imu_samples", r.imu_samples)
      .Field("t_start_s", initial.t_s)
      .Field("t_end_s", r.final_state.t_s)
      .Field("run_time_s", r.run_time_s)
      .Field("output", nav_path);
  if (r.errors) {
    const NavErrorStats& e = *r.errors;
    w.Key("errors").BeginObject().Field("epochs", e.count());
    for (const Row& row : kRows) {
      w.Key(kJsonKeys[row.component])
          .BeginObject()
          .Field("rms", e.Rms(row.component) * row.scale)
          .Field("max", e.Max(row.component) * row.scale)
          .Field("final", e.Final(row.component) * row.scale)
          .EndObject();
    }
    w.Key("horizontal_m").BeginObject().Field("rms", e.HorizontalRms_m()).Field("max", e.HorizontalMax_m()).EndObject();
    w.EndObject();
  }
  w.EndObject();
  std::cout << "\n";
}

int Usage(const std::string& why) {
  std::cerr << "navtwin ins: " << why << "\nusage: " << InsCommand().usage << "\n";
  return kExitUsage;
}

int RunIns(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("unexpected argument '" + args[0] + "'");
  if (FLAGS_out.empty()) return Usage("--out is required");
  const bool init_flags = !std::isnan(FLAGS_init_lat_deg) || !std::isnan(FLAGS_init_lon_deg) ||
                          !std::isnan(FLAGS_init_yaw_deg);
  if (FLAGS_demo) {
    if (!FLAGS_imu.empty() || !FLAGS_truth.empty() || !FLAGS_init_from.empty() || init_flags) {
      return Usage("--demo makes its own --imu, --truth and initial state");
    }
  } else {
    if (FLAGS_imu.empty()) return Usage("--imu is required (or --demo)");
    if (FLAGS_init_from.empty() == !init_flags) {
      return Usage("give exactly one of --init_from NAVFILE or --init_lat_deg/--init_lon_deg/--init_yaw_deg");
    }
    if (init_flags && (std::isnan(FLAGS_init_lat_deg) || std::isnan(FLAGS_init_lon_deg) ||
                       std::isnan(FLAGS_init_yaw_deg))) {
      return Usage("--init_lat_deg, --init_lon_deg and --init_yaw_deg go together");
    }
  }
  if (FLAGS_output_rate_hz < 0.0) return Usage("--output_rate_hz must be >= 0");
  if (FLAGS_calibration.empty() && !std::isnan(FLAGS_imu_temperature_degC)) {
    return Usage("--imu_temperature_degC goes with --calibration");
  }
  if (!(FLAGS_max_bridge_gap_s >= 0.0)) return Usage("--max_bridge_gap_s must be >= 0");
  OutputFolder folder(FLAGS_out);
  if (!folder.Make()) return Usage("cannot create the output folder " + FLAGS_out);

  std::string imu_path = FLAGS_imu, truth_path = FLAGS_truth, init_path = FLAGS_init_from;
  if (FLAGS_demo) {
    std::cerr << "ins: simulating the demo flight (" << FLAGS_demo_duration_s << " s at "
              << FLAGS_demo_rate_hz << " Hz) into " << FLAGS_out << "\n";
    const DemoFiles demo = WriteDemoFlight(FLAGS_out, FLAGS_demo_rate_hz, FLAGS_demo_duration_s);
    imu_path = demo.imu_path;
    truth_path = init_path = demo.truth_path;
    folder.Keep();  // the simulated files stay
  }

  NavState initial;
  if (!init_path.empty()) {
    auto nav = OpenNav(init_path);
    initial = InitialStateFromNav(*nav, Optional(FLAGS_start_s));
  } else {
    initial = StateFromFlags(std::isnan(FLAGS_start_s) ? FirstImuEpoch(imu_path) : FLAGS_start_s);
  }
  RequireMechanizable(initial, init_path.empty() ? std::string("--init_lat_deg/--init_lon_deg/--init_h_m") : init_path,
                      "initial state");

  PureInsOptions options;
  options.strapdown.hold_height_m = Optional(FLAGS_hold_height_m);
  options.output_interval_s = FLAGS_output_rate_hz > 0.0 ? 1.0 / FLAGS_output_rate_hz : 0.0;
  options.end_time_s = FLAGS_end_s;
  options.progress_every = 200000;

  auto imu = ins::GapBridgingImuReader(OpenImu(imu_path, FLAGS_calibration, FLAGS_imu_temperature_degC),
                                       FLAGS_max_bridge_gap_s, "--max_bridge_gap_s");
  std::unique_ptr<NavReader> truth;
  if (!truth_path.empty()) truth = OpenNav(truth_path);
  const std::string nav_path = FLAGS_out + "/nav.nav";
  KfginsNavWriter writer(nav_path);
  const PureInsResult result = RunPureIns(
      *imu, initial, options, [&](const NavState& s) { writer.Write(s); }, truth.get());
  writer.Commit();
  folder.Keep();
  if (truth && !result.errors) {
    std::cerr << "ins: warning: the truth file " << truth_path << " has no epoch inside the run\n";
  }
  if (FLAGS_format == "json") {
    PrintJson(result, initial, nav_path);
  } else {
    PrintText(result, initial, nav_path);
  }
  return kExitOk;
}

}  // namespace

Command InsCommand() {
  return {"ins",
          "Pure inertial navigation (strapdown) over an IMU record; errors against a truth file",
          "navtwin ins --imu F (--init_from NAVFILE | --init_lat_deg D --init_lon_deg D "
          "--init_yaw_deg D [--init_h_m ...]) --out DIR [--truth F] [--output_rate_hz R] "
          "[--max_bridge_gap_s S] [--calibration FILE [--imu_temperature_degC T]] [--format=json]\n       navtwin ins --demo --out DIR",
          {"imu", "out", "truth", "init_from", "init_lat_deg", "init_lon_deg", "init_h_m",
           "init_vn_mps", "init_ve_mps", "init_vd_mps", "init_roll_deg", "init_pitch_deg",
           "init_yaw_deg", "start_s", "end_s", "output_rate_hz", "hold_height_m", "max_bridge_gap_s", "demo",
           "demo_rate_hz", "demo_duration_s", "calibration", "imu_temperature_degC"},
          &RunIns};
}

}  // namespace navtwin::app
