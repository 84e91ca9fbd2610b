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
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/atomic_file.h"
#include "core/io/json_writer.h"
#include "core/rotation.h"
#include "problems/transfer_alignment/ansfl.h"
#include "problems/transfer_alignment/config.h"
#include "problems/transfer_alignment/run.h"

DEFINE_string(csv, "", "transfer-align-ansfl: write one row per path and DOT to this CSV file");

namespace navtwin::app {
namespace {

using transfer::AnsflAlignment;
using transfer::Method;

const char* kUsage =
    "navtwin transfer-align-ansfl --data DIR [--method order2|batch] [--config YAML] [--csv F] [--format=json]\n"
    "  DIR: the ansfl-quadrotor folder (StraightLine/path_*, Horizontal/path_*). Default method order2;\n"
    "  default configuration: the DOT slave against the DJI master (docs/transfer-alignment-real.md).";

int Usage(const std::string& why) {
  std::cerr << "navtwin transfer-align-ansfl: " << why << "\nusage: " << kUsage << "\n";
  return kExitUsage;
}

bool Ok(const AnsflAlignment& a) { return a.note.empty() || a.note == "no epoch after settle_s"; }
// CoarseAlignAnsfl sets the correlation (> 0 at its peak); it stays 0 when the coarse step failed.
bool CoarseOk(const AnsflAlignment& a) { return a.coarse.correlation > 0.0; }

Eigen::Vector3d CoarseDeg(const AnsflAlignment& a) { return EulerFromQuat(a.coarse.mounting) * kRadToDeg; }

/// Mean, standard deviation and max - min of angles (deg) that may wrap at +-180 (the DOT roll
/// is near 180): each is first brought next to the first one.
struct Spread {
  int n = 0;
  double mean = std::nan(""), std = std::nan(""), range = std::nan("");
};

Spread SpreadOf(const std::vector<double>& x, bool angle_deg) {
  Spread s;
  s.n = static_cast<int>(x.size());
  if (x.empty()) return s;
  std::vector<double> u;
  for (double v : x) u.push_back(angle_deg ? x[0] + WrapPi((v - x[0]) * kDegToRad) * kRadToDeg : v);
  double sum = 0.0;
  for (double v : u) sum += v;
  s.mean = sum / u.size();
  double ss = 0.0;
  for (double v : u) ss += (v - s.mean) * (v - s.mean);
  s.std = u.size() > 1 ? std::sqrt(ss / (u.size() - 1)) : std::nan("");
  s.range = *std::max_element(u.begin(), u.end()) - *std::min_element(u.begin(), u.end());
  if (angle_deg) s.mean = WrapPi(s.mean * kDegToRad) * kRadToDeg;
  return s;
}

struct DotRepeatability {
  int dot = 0;
  std::string group;  ///< "all", "StraightLine" or "Horizontal"
  Spread coarse[3], refined[3], delay_ms, residual_mrad;
};

/// Per DOT, over all paths and over each flight type (their excitation differs: the
/// StraightLine flights barely rotate, the Horizontal ones spin in yaw).
std::vector<DotRepeatability> Repeatability(const std::vector<AnsflAlignment>& runs) {
  std::map<std::pair<int, std::string>, std::vector<const AnsflAlignment*>> by_dot;
  for (const AnsflAlignment& a : runs) {
    by_dot[{a.dot, "all"}].push_back(&a);
    by_dot[{a.dot, a.path.substr(0, a.path.find('/'))}].push_back(&a);
  }
  std::vector<DotRepeatability> out;
  for (const auto& [key, list] : by_dot) {
    DotRepeatability r;
    r.dot = key.first;
    r.group = key.second;
    for (int i = 0; i < 3; ++i) {
      std::vector<double> c, f;
      for (const AnsflAlignment* a : list) {
        if (CoarseOk(*a)) c.push_back(CoarseDeg(*a)[i]);
        if (Ok(*a)) f.push_back(a->result.misalignment_deg[i]);
      }
      r.coarse[i] = SpreadOf(c, true);
      r.refined[i] = SpreadOf(f, true);
    }
    std::vector<double> d, res;
    for (const AnsflAlignment* a : list) {
      if (!Ok(*a)) continue;
      d.push_back(a->result.delay_s * 1e3);
      if (std::isfinite(a->residual_attitude_mrad)) res.push_back(a->residual_attitude_mrad);
    }
    r.delay_ms = SpreadOf(d, false);
    r.residual_mrad = SpreadOf(res, false);
    out.push_back(r);
  }
  return out;
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
    if (!CoarseOk(a)) {
      std::printf("skipped: %s\n", a.note.c_str());
      continue;
    }
    const Eigen::Vector3d c = CoarseDeg(a);
    std::printf("%8.3f %5.3f %7.2f %7.2f %7.2f ", a.coarse.clock_offset_s, a.coarse.correlation, c.x(), c.y(), c.z());
    if (!Ok(a)) {
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
    std::snprintf(coarse, sizeof coarse, "%.2f/%.2f/%.2f", r.coarse[0].std, r.coarse[1].std, r.coarse[2].std);
    const auto fmt = [](const Spread& s, const char* unit_fmt) {
      return Cell(s.std, unit_fmt) + " / " + Cell(s.range, unit_fmt) + " [" + Cell(s.mean, unit_fmt) + "]";
    };
    std::printf("%3d %-12s %3d %-24s %-26s %-26s %-26s %s\n", r.dot, r.group.c_str(), r.refined[0].n, coarse,
                fmt(r.refined[0], "%.2f").c_str(), fmt(r.refined[1], "%.2f").c_str(), fmt(r.refined[2], "%.2f").c_str(),
                fmt(r.delay_ms, "%.1f").c_str());
  }
}

void WriteSpread(JsonWriter& w, const std::string& key, const Spread& s) {
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
    if (CoarseOk(a)) {
      w.Field("coarse_offset_s", a.coarse.clock_offset_s).Field("coarse_correlation", a.coarse.correlation);
      vec("coarse_mounting_deg", CoarseDeg(a));
      vec("coarse_gyro_bias_dps", a.coarse.gyro_bias_s_radps * kRadToDeg);
      w.Field("coarse_rate_residual_dps", a.coarse.rate_residual_rms_radps * kRadToDeg);
    }
    if (Ok(a)) {
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
    for (int i = 0; i < 3; ++i) WriteSpread(w, std::string("coarse_") + axes[i] + "_deg", r.coarse[i]);
    for (int i = 0; i < 3; ++i) WriteSpread(w, std::string(axes[i]) + "_deg", r.refined[i]);
    WriteSpread(w, "delay_ms", r.delay_ms);
    WriteSpread(w, "residual_attitude_mrad", r.residual_mrad);
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
    const bool c = CoarseOk(a), r = Ok(a);
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

int RunTransferAlignAnsfl(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("unexpected argument '" + args[0] + "'");
  if (FLAGS_data.empty()) return Usage("--data DIR is required (the ansfl-quadrotor folder)");
  Method method = Method::kOrder2;
  if (!FLAGS_method.empty()) {
    try {
      method = transfer::ParseMethod(FLAGS_method);
    } catch (const std::invalid_argument&) {
      return Usage("--method must be order2 or batch, got '" + FLAGS_method + "'");
    }
    if (method == Method::kOrder1)
      return Usage("--method must be order2 or batch (order1 is the seed's baseline only)");
  }
  const transfer::TransferConfig config =
      FLAGS_config.empty() ? transfer::AnsflDotConfig() : transfer::LoadTransferConfig(FLAGS_config);
  const std::vector<AnsflAlignment> runs = transfer::AlignAllAnsfl(FLAGS_data, config, method);
  const std::vector<DotRepeatability> rep = Repeatability(runs);
  if (!FLAGS_csv.empty()) WriteCsv(runs, FLAGS_csv);
  if (FLAGS_format == "json") {
    std::cout << Json(runs, rep, method) << "\n";
  } else {
    PrintText(runs, rep, method);
  }
  return std::any_of(runs.begin(), runs.end(), Ok) ? kExitOk : kExitFailure;
}

}  // namespace

Command TransferAlignAnsflCommand() {
  return {"transfer-align-ansfl",
          "Transfer alignment of the ANSFL quadrotor's Xsens DOTs to the DJI solution: mounting, delay, repeatability",
          kUsage,
          {"data", "method", "config", "csv"},
          &RunTransferAlignAnsfl};
}

}  // namespace navtwin::app
