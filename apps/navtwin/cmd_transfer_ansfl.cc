// navtwin transfer-align-ansfl: transfer alignment of every Xsens DOT on every ANSFL quadrotor
// path (problems/transfer_alignment/ansfl.h): the DJI solution is the master, each DOT a
// slave with unknown mounting and clock offset. Prints per path and DOT the coarse clock
// offset and mounting, the refined mounting and delay with their sigmas and the residual
// attitude; then per DOT the spread of each mounting angle and of the delay across paths
// (repeatability, the score of an alignment without truth).
#include <gflags/gflags.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/calibration_file.h"
#include "core/io/atomic_file.h"
#include "core/io/json_writer.h"
#include "core/rotation.h"
#include "problems/transfer_alignment/ansfl.h"
#include "problems/transfer_alignment/config.h"
#include "problems/transfer_alignment/run.h"

DEFINE_string(csv, "", "transfer-align-ansfl: write one row per path and DOT to this CSV file");
DEFINE_string(path, "", "transfer-align-ansfl: only this path folder under --data, e.g. Horizontal/path_4");
DEFINE_int32(dot, 0, "transfer-align-ansfl: only this DOT, 1-4 (0: every IMU_k.csv)");
DEFINE_string(calibration_out, "",
              "transfer-align-ansfl: write the DOT's mounting, time offset and gyro bias as a calibration file "
              "(docs/calibration-file.md) for smooth/navigate --calibration; needs --path and --dot");

namespace navtwin::app {
namespace {

using transfer::AnsflAlignment;
using transfer::Method;

const char* kUsage =
    "navtwin transfer-align-ansfl --data DIR [--method order2|history|batch] [--config YAML] [--csv F] [--format=json]\n"
    "                             [--path TYPE/path_N [--dot K [--calibration_out FILE]]]\n"
    "  DIR: the ansfl-quadrotor folder (StraightLine/path_*, Horizontal/path_*). Default method order2;\n"
    "  default configuration: the DOT slave against the DJI master (docs/transfer-alignment-real.md).\n"
    "  --calibration_out: the one path's and DOT's mounting, time offset and gyro bias for smooth --calibration.";

int Usage(const std::string& why) {
  std::cerr << "navtwin transfer-align-ansfl: " << why << "\nusage: " << kUsage << "\n";
  return kExitUsage;
}

using transfer::AnsflCoarseOk;
using transfer::AnsflRefined;
using transfer::DotRepeatability;
using transfer::SampleSpread;

Eigen::Vector3d CoarseDeg(const AnsflAlignment& a) { return EulerFromQuat(a.coarse.mounting) * kRadToDeg; }

/// A spread in the printed unit: every field times `scale`.
SampleSpread Scaled(const SampleSpread& s, double scale) {
  return {s.n, s.mean * scale, s.std * scale, s.range * scale};
}

std::string Cell(double x, const char* fmt) {
  if (!std::isfinite(x)) return "-";
  char buf[48];
  std::snprintf(buf, sizeof buf, fmt, x);
  return buf;
}

void PrintText(const std::vector<AnsflAlignment>& runs, const std::vector<DotRepeatability>& rep, Method method) {
  std::printf(
      "transfer-align-ansfl, method %s. Mounting R_b_s as ZYX Euler (roll, pitch, yaw) of the DOT axes in\n"
      "the drone's FRD, deg; delay = the DJI record's age left after the coarse clock offset, ms;\n"
      "residual = RMS |attitude residual| (slave x mounting vs GT at t + delay) after settle, mrad.\n",
      transfer::MethodName(method));
  std::printf("%-20s %3s %8s %5s %23s %23s %17s %14s %7s\n", "path", "dot", "offset_s", "corr", "coarse r/p/y deg",
              "refined r/p/y deg", "sigma mrad", "delay ms", "res_mrad");
  for (const AnsflAlignment& a : runs) {
    std::printf("%-20s %3d ", a.path.c_str(), a.dot);
    if (!AnsflCoarseOk(a)) {
      std::printf("skipped: %s\n", a.note.c_str());
      continue;
    }
    const Eigen::Vector3d c = CoarseDeg(a);
    std::printf("%8.3f %5.3f %7.2f %7.2f %7.2f ", a.coarse.clock_offset_s, a.coarse.correlation, c.x(), c.y(), c.z());
    if (!AnsflRefined(a)) {
      std::printf("not refined: %s\n", a.note.c_str());
      continue;
    }
    const Eigen::Vector3d& m = a.result.misalignment_deg;
    const Eigen::Vector3d& s = a.result.misalignment_sigma_mrad;
    std::printf("%7.2f %7.2f %7.2f %5.1f %5.1f %5.1f %6.1f +-%5.1f %7s\n", m.x(), m.y(), m.z(), s.x(), s.y(), s.z(),
                a.result.delay_s * 1e3, a.result.delay_sigma_s * 1e3, Cell(a.residual_attitude_mrad, "%.2f").c_str());
  }
  std::printf("\nrepeatability across paths per DOT (std / max-min; n = paths used; mean in brackets)\n");
  std::printf("%3s %-12s %3s %-24s %-26s %-26s %-26s %s\n", "dot", "paths", "n", "coarse r/p/y std deg",
              "refined roll deg", "refined pitch deg", "refined yaw deg", "delay ms");
  for (const DotRepeatability& r : rep) {
    char coarse[64];
    std::snprintf(coarse, sizeof coarse, "%.2f/%.2f/%.2f", r.coarse_rad[0].std * kRadToDeg,
                  r.coarse_rad[1].std * kRadToDeg, r.coarse_rad[2].std * kRadToDeg);
    const auto fmt = [](const SampleSpread& s, const char* unit_fmt) {
      return Cell(s.std, unit_fmt) + " / " + Cell(s.range, unit_fmt) + " [" + Cell(s.mean, unit_fmt) + "]";
    };
    std::printf("%3d %-12s %3d %-24s %-26s %-26s %-26s %s\n", r.dot, r.group.c_str(), r.mounting_rad[0].n, coarse,
                fmt(Scaled(r.mounting_rad[0], kRadToDeg), "%.2f").c_str(),
                fmt(Scaled(r.mounting_rad[1], kRadToDeg), "%.2f").c_str(),
                fmt(Scaled(r.mounting_rad[2], kRadToDeg), "%.2f").c_str(), fmt(Scaled(r.delay_s, 1e3), "%.1f").c_str());
  }
}

void WriteSpread(JsonWriter& w, const std::string& key, const SampleSpread& s) {
  w.Key(key)
      .BeginObject()
      .Field("n", s.n)
      .Field("mean", s.mean)
      .Field("std", s.std)
      .Field("range", s.range)
      .EndObject();
}

std::string Json(const std::vector<AnsflAlignment>& runs, const std::vector<DotRepeatability>& rep, Method method) {
  std::ostringstream out;
  JsonWriter w(out);
  const auto vec = [&](const std::string& key, const Eigen::Vector3d& v) {
    w.Key(key).BeginArray().Value(v.x()).Value(v.y()).Value(v.z()).EndArray();
  };
  w.BeginObject().Field("method", transfer::MethodName(method)).Key("runs").BeginArray();
  for (const AnsflAlignment& a : runs) {
    w.BeginObject().Field("path", a.path).Field("dot", a.dot);
    if (AnsflCoarseOk(a)) {
      w.Field("coarse_offset_s", a.coarse.clock_offset_s).Field("coarse_correlation", a.coarse.correlation);
      vec("coarse_mounting_deg", CoarseDeg(a));
      vec("coarse_gyro_bias_dps", a.coarse.gyro_bias_s_radps * kRadToDeg);
      w.Field("coarse_rate_residual_dps", a.coarse.rate_residual_rms_radps * kRadToDeg);
    }
    if (AnsflRefined(a)) {
      vec("mounting_deg", a.result.misalignment_deg);
      vec("mounting_sigma_mrad", a.result.misalignment_sigma_mrad);
      w.Field("delay_s", a.result.delay_s)
          .Field("delay_sigma_s", a.result.delay_sigma_s)
          .Field("residual_attitude_mrad", a.residual_attitude_mrad)
          .Field("run_time_s", a.result.run_time_s);
    }
    w.Field("note", a.note).EndObject();
  }
  w.EndArray().Key("repeatability").BeginArray();
  const char* axes[3] = {"roll", "pitch", "yaw"};
  for (const DotRepeatability& r : rep) {
    w.BeginObject().Field("dot", r.dot).Field("paths", r.group);
    for (int i = 0; i < 3; ++i) {
      WriteSpread(w, std::string("coarse_") + axes[i] + "_deg", Scaled(r.coarse_rad[i], kRadToDeg));
    }
    for (int i = 0; i < 3; ++i) WriteSpread(w, std::string(axes[i]) + "_deg", Scaled(r.mounting_rad[i], kRadToDeg));
    WriteSpread(w, "delay_ms", Scaled(r.delay_s, 1e3));
    WriteSpread(w, "residual_attitude_mrad", Scaled(r.residual_rad, 1e3));
    w.EndObject();
  }
  w.EndArray().EndObject();
  return out.str();
}

void WriteCsv(const std::vector<AnsflAlignment>& runs, const std::string& path) {
  AtomicFile f(path);
  std::ostream& o = f.stream();
  o << "path,dot,coarse_offset_s,coarse_correlation,coarse_roll_deg,coarse_pitch_deg,coarse_yaw_deg,"
       "gyro_bias_x_dps,gyro_bias_y_dps,gyro_bias_z_dps,roll_deg,pitch_deg,yaw_deg,roll_sigma_mrad,"
       "pitch_sigma_mrad,yaw_sigma_mrad,delay_s,delay_sigma_s,residual_attitude_mrad,note\n";
  for (const AnsflAlignment& a : runs) {
    const double nan = std::nan("");
    const bool c = AnsflCoarseOk(a), r = AnsflRefined(a);
    const Eigen::Vector3d cm = c ? CoarseDeg(a) : Eigen::Vector3d::Constant(nan);
    const Eigen::Vector3d bias =
        c ? Eigen::Vector3d(a.coarse.gyro_bias_s_radps * kRadToDeg) : Eigen::Vector3d::Constant(nan);
    const Eigen::Vector3d m = r ? a.result.misalignment_deg : Eigen::Vector3d::Constant(nan);
    const Eigen::Vector3d s = r ? a.result.misalignment_sigma_mrad : Eigen::Vector3d::Constant(nan);
    std::string note = a.note;
    std::replace(note.begin(), note.end(), ',', ';');
    std::replace(note.begin(), note.end(), '"', '\'');
    o << a.path << ',' << a.dot << ',' << (c ? a.coarse.clock_offset_s : nan) << ','
      << (c ? a.coarse.correlation : nan);
    for (const Eigen::Vector3d* v : {&cm, &bias, &m, &s}) o << ',' << v->x() << ',' << v->y() << ',' << v->z();
    o << ',' << (r ? a.result.delay_s : nan) << ',' << (r ? a.result.delay_sigma_s : nan) << ','
      << (r ? a.residual_attitude_mrad : nan) << ",\"" << note << "\"\n";
  }
  f.Commit();
}

/// The command as run (the flags that were set), for the calibration file's created_by.
std::string AnsflCommandLine() {
  std::string line = "navtwin transfer-align-ansfl";
  for (const char* name : {"data", "method", "config", "path", "dot", "calibration_out"}) {
    gflags::CommandLineFlagInfo info;
    if (gflags::GetCommandLineFlagInfo(name, &info) && !info.is_default) line += " --" + std::string(name) + "=" + info.current_value;
  }
  return line;
}

int RunTransferAlignAnsfl(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("unexpected argument '" + args[0] + "'");
  if (FLAGS_data.empty()) return Usage("--data DIR is required (the ansfl-quadrotor folder)");
  Method method = Method::kOrder2;
  if (!FLAGS_method.empty()) {
    try {
      method = transfer::ParseMethod(FLAGS_method);
    } catch (const std::invalid_argument&) {
      return Usage("--method must be order2, history or batch, got '" + FLAGS_method + "'");
    }
    if (method == Method::kOrder1)
      return Usage("--method must be order2, history or batch (order1 is the seed's baseline only)");
  }
  const transfer::TransferConfig config =
      FLAGS_config.empty() ? transfer::AnsflDotConfig() : transfer::LoadTransferConfig(FLAGS_config);
  if (FLAGS_dot < 0 || FLAGS_dot > 4) return Usage("--dot must be 1-4 (or 0: all)");
  if (FLAGS_dot != 0 && FLAGS_path.empty()) return Usage("--dot goes with --path (one path folder)");
  if (!FLAGS_calibration_out.empty() && (FLAGS_path.empty() || FLAGS_dot == 0)) {
    return Usage("--calibration_out needs --path and --dot (one path and one DOT: the clock offset differs per path)");
  }
  const std::vector<AnsflAlignment> runs =
      transfer::AlignAllAnsfl(FLAGS_data, config, method, {FLAGS_path, FLAGS_dot});
  const std::vector<DotRepeatability> rep = transfer::AnsflRepeatability(runs);
  if (!FLAGS_csv.empty()) WriteCsv(runs, FLAGS_csv);
  if (!FLAGS_calibration_out.empty()) {
    if (runs.size() != 1 || !AnsflRefined(runs.front())) {
      std::cerr << "navtwin transfer-align-ansfl: no calibration written: "
                << (runs.empty() ? std::string("nothing aligned") : runs.front().note) << "\n";
      return kExitFailure;
    }
    WriteCalibrationFile(FLAGS_calibration_out, transfer::AnsflCalibrationFile(runs.front(), AnsflCommandLine()));
    std::cerr << "navtwin transfer-align-ansfl: wrote " << FLAGS_calibration_out << "\n";
  }
  if (FLAGS_format == "json") {
    std::cout << Json(runs, rep, method) << "\n";
  } else {
    PrintText(runs, rep, method);
  }
  return std::any_of(runs.begin(), runs.end(), AnsflRefined) ? kExitOk : kExitFailure;
}

}  // namespace

Command TransferAlignAnsflCommand() {
  return {"transfer-align-ansfl",
          "Transfer alignment of the ANSFL quadrotor's Xsens DOTs to the DJI solution: mounting, delay, repeatability",
          kUsage,
          {"data", "method", "config", "csv", "path", "dot", "calibration_out"},
          &RunTransferAlignAnsfl};
}

}  // namespace navtwin::app
