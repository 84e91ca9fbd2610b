// navtwin calibrate-mag: hard and soft iron of a magnetometer record by the 3-axis ellipsoid
// fit, the planar fit (3-axis data near one plane) or the seed's 2-axis bidirectional method
// (problems/calibration/mag_calibration.h);
// prints the calibration, the field-magnitude spread and, with --truth, the heading error
// before and after; --out writes the calibration file (core/calibration_file.h).
//
// Roll and pitch (for the bidirectional tilt gate and for the tilt-compensated heading)
// come from --truth when given, else from the --imu accelerometer (the mean specific force
// of the IMU samples within half a magnetometer interval of each sample, levelled as in
// core/leveling_model.h), else every sample is taken as level. The bidirectional method
// runs without either (a level turn is its premise) and says so on stderr.
#include <gflags/gflags.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/calibration_file.h"
#include "core/io/input_error.h"
#include "core/io/json_writer.h"
#include "core/io/open.h"
#include "core/rotation.h"
#include "problems/calibration/calibration_run_folder.h"
#include "problems/calibration/mag_calibration.h"
#include "problems/calibration/mag_heading.h"

DEFINE_double(declination_deg, 0.0,
              "calibrate-mag: magnetic declination (east positive) added to the magnetic heading, deg");
DEFINE_double(field_uT, 0.0,
              "calibrate-mag: Earth field magnitude the ellipsoid fit scales to, uT (0: the data's mean)");

namespace navtwin::app {

Command CalibrateMagCommand();

namespace {

using calibration::HeadingErrors;
using calibration::MagCalibration;

int Usage(const std::string& why) {
  std::cerr << "navtwin calibrate-mag: " << why << "\nusage: " << CalibrateMagCommand().usage << "\n";
  return kExitUsage;
}

/// The command as run, for the calibration file's created_by: the flags of this command
/// that were set.
std::string CommandLine() {
  std::string line = "navtwin calibrate-mag";
  std::vector<std::string> flags = CalibrateMagCommand().flags;
  flags.push_back("format");
  for (const std::string& name : flags) {
    gflags::CommandLineFlagInfo info;
    if (gflags::GetCommandLineFlagInfo(name.c_str(), &info) && info.current_value != info.default_value) {
      line += " --" + name + "=" + info.current_value;
    }
  }
  return line;
}

std::string Fixed(double x, int digits) {
  if (!std::isfinite(x)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, x);
  return buf;
}

bool HasUncalibratedAxis(const MagCalibration& c) { return c.uncalibrated_axis.squaredNorm() > 0.0; }

void PrintText(const MagCalibration& c, const HeadingErrors& h, const std::string& attitude) {
  std::printf("magnetometer calibration (%s): %d samples, %d down-weighted, roll/pitch from %s\n", c.method.c_str(),
              c.samples, c.downweighted, attitude.c_str());
  std::printf("  hard iron [uT]        %10.4f %10.4f %10.4f\n", c.hard_iron_uT.x(), c.hard_iron_uT.y(),
              c.hard_iron_uT.z());
  std::printf("  hard iron sigma [uT]  %10s %10s %10s\n", Fixed(c.hard_iron_sigma_uT.x(), 4).c_str(),
              Fixed(c.hard_iron_sigma_uT.y(), 4).c_str(), Fixed(c.hard_iron_sigma_uT.z(), 4).c_str());
  for (int r = 0; r < 3; ++r) {
    std::printf("  %-21s %10.6f %10.6f %10.6f\n", r == 0 ? "soft iron A" : "", c.correction(r, 0), c.correction(r, 1),
                c.correction(r, 2));
  }
  const auto& s = c.correction_sigma;  // A00 A01 A02 A11 A12 A22
  std::printf("  soft iron sigma       A00 %s A01 %s A02 %s A11 %s A12 %s A22 %s\n", Fixed(s[0], 6).c_str(),
              Fixed(s[1], 6).c_str(), Fixed(s[2], 6).c_str(), Fixed(s[3], 6).c_str(), Fixed(s[4], 6).c_str(),
              Fixed(s[5], 6).c_str());
  const bool in_plane = HasUncalibratedAxis(c);
  if (in_plane) {
    const Eigen::Vector3d& n = c.uncalibrated_axis;
    std::printf("  NOT calibrated along  %10.4f %10.4f %10.4f  (sensor axes: hard iron 0 and A identity along it)\n",
                n.x(), n.y(), n.z());
    std::printf("  in-plane coverage     %10.1f deg\n", c.coverage_deg);
  }
  if (c.method == "planar") std::printf("  off-plane RMS [uT]    %10.4f\n", c.out_of_plane_rms_uT);
  std::printf("  field [uT]            %10.4f%s\n", c.field_uT, in_plane ? "  (in the plane)" : "");
  std::printf("  residual RMS [uT]     %10.4f\n", c.residual_rms_uT);
  std::printf("  %-21s before %s  after %s\n", in_plane ? "in-plane |m| spread" : "|m| spread [uT]",
              Fixed(c.field_spread_before_uT, 4).c_str(), Fixed(c.field_spread_after_uT, 4).c_str());
  std::printf("  heading error RMS [deg] before %s  after %s  (%d samples with truth)\n",
              Fixed(h.before_deg, 3).c_str(), Fixed(h.after_deg, 3).c_str(), h.samples);
}

/// The --format=json object; with `command` (a run folder's summary.json) led by it.
void WriteJson(std::ostream& out, const MagCalibration& c, const HeadingErrors& h, const std::string& attitude,
               const std::string& command) {
  JsonWriter w(out);
  w.BeginObject();
  if (!command.empty()) w.Field("command", command);
  w.Key("hard_iron_uT").BeginArray();
  for (int i = 0; i < 3; ++i) w.Value(c.hard_iron_uT[i]);
  w.EndArray().Key("hard_iron_sigma_uT").BeginArray();
  for (int i = 0; i < 3; ++i) w.Value(c.hard_iron_sigma_uT[i]);
  w.EndArray().Key("soft_iron").BeginArray();
  for (int r = 0; r < 3; ++r) {
    w.BeginArray();
    for (int k = 0; k < 3; ++k) w.Value(c.correction(r, k));
    w.EndArray();
  }
  w.EndArray().Key("soft_iron_sigma").BeginArray();  // A00 A01 A02 A11 A12 A22; NaN -> null
  for (int i = 0; i < 6; ++i) w.Value(c.correction_sigma[i]);
  w.EndArray().Key("uncalibrated_axis_sensor");
  if (HasUncalibratedAxis(c)) {
    w.BeginArray();
    for (int i = 0; i < 3; ++i) w.Value(c.uncalibrated_axis[i]);
    w.EndArray();
  } else {
    w.Value(NAN);  // null: every axis calibrated
  }
  w.Field("spread_of", HasUncalibratedAxis(c) ? "in-plane |m|" : "|m|")
      .Field("coverage_deg", HasUncalibratedAxis(c) ? c.coverage_deg : NAN)
      .Field("out_of_plane_rms_uT", c.method == "planar" ? c.out_of_plane_rms_uT : NAN)
      .Field("field_uT", c.field_uT)
      .Field("residual_rms_uT", c.residual_rms_uT)
      .Field("heading_error_before_deg", h.before_deg)  // NaN -> null (no truth)
      .Field("heading_error_after_deg", h.after_deg)
      .Field("heading_samples", h.samples)
      .Field("field_spread_before_uT", c.field_spread_before_uT)
      .Field("field_spread_after_uT", c.field_spread_after_uT)
      .Field("samples", c.samples)
      .Field("downweighted", c.downweighted)
      .Field("method", c.method)
      .Field("attitude", attitude)
      .EndObject();
}

/// A recursive estimate as the terminal shows it.
void PrintRecursiveStep(const calibration::RecursiveMagStep& s, bool header) {
  if (header) std::printf("recursive ellipsoid fit: the estimate after every 1/20 of the samples\n");
  if (!s.estimate) {
    std::printf("  %7zu samples (t = %.2f s): not yet (%s)\n", s.samples, s.t_s, s.why_not.c_str());
    return;
  }
  const MagCalibration& c = *s.estimate;
  std::printf("  %7zu samples (t = %.2f s): hard iron %9.4f %9.4f %9.4f uT, field %8.4f uT\n", s.samples, s.t_s,
              c.hard_iron_uT.x(), c.hard_iron_uT.y(), c.hard_iron_uT.z(), c.field_uT);
}

/// The fit of --method; the bidirectional one over the samples with a roll and pitch; the
/// recursive one prints its estimates (text format) and keeps them in *steps.
MagCalibration FitByMethod(const std::vector<MagSample>& mag,
                           const std::vector<std::optional<Eigen::Vector2d>>& roll_pitch,
                           std::vector<calibration::RecursiveMagStep>* steps) {
  if (FLAGS_method == "planar") return calibration::FitPlanar(mag);
  if (FLAGS_method == "recursive") {
    const std::size_t block = std::max<std::size_t>(1, mag.size() / 20);
    return calibration::FitRecursive(mag, FLAGS_field_uT, block, [steps](const calibration::RecursiveMagStep& s) {
      if (FLAGS_format == "text") PrintRecursiveStep(s, steps->empty());
      steps->push_back(s);
    });
  }
  if (FLAGS_method == "ellipsoid") {
    calibration::EllipsoidFitOptions options;
    options.field_uT = FLAGS_field_uT;
    return calibration::FitEllipsoid(mag, options);
  }
  std::vector<MagSample> used;
  std::vector<Eigen::Vector2d> used_rp;
  for (std::size_t i = 0; i < mag.size(); ++i) {
    if (!roll_pitch[i]) continue;
    used.push_back(mag[i]);
    used_rp.push_back(*roll_pitch[i]);
  }
  if (used.size() < mag.size()) {
    std::cerr << "calibrate-mag: " << mag.size() - used.size() << " samples outside the attitude record ("
              << (FLAGS_truth.empty() ? FLAGS_imu : FLAGS_truth) << ") are left out\n";
  }
  return calibration::FitBidirectional(used, used_rp);
}

int RunCalibrateMag(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("unexpected argument '" + args.front() + "'");
  if (FLAGS_mag.empty()) return Usage("--mag FILE is required");
  if (FLAGS_method != "ellipsoid" && FLAGS_method != "planar" && FLAGS_method != "bidirectional" &&
      FLAGS_method != "recursive") {
    return Usage("--method must be ellipsoid, planar, bidirectional or recursive, got '" + FLAGS_method + "'");
  }
  if (!std::isfinite(FLAGS_declination_deg)) return Usage("--declination_deg must be a finite angle, deg");
  if (!(std::isfinite(FLAGS_field_uT) && FLAGS_field_uT >= 0.0)) return Usage("--field_uT must be >= 0 (0: from the data)");
  const bool two_axis = FLAGS_method == "bidirectional";
  if (FLAGS_report && FLAGS_run_dir.empty()) return Usage("--report needs --run_dir DIR (it writes DIR/report.html)");
  if (FLAGS_method != "ellipsoid" && FLAGS_method != "recursive" && FLAGS_field_uT != 0.0) {
    return Usage("--field_uT goes with --method ellipsoid or recursive");
  }

  std::vector<MagSample> mag = ReadAll<MagSample>(*OpenMag(FLAGS_mag));
  if (mag.empty()) throw InputError(FLAGS_mag, 0, "t_s", "no magnetometer samples");

  // Attitude per sample: roll, pitch (and yaw from the truth).
  calibration::MagSampleAttitudes attitudes;
  if (!FLAGS_truth.empty()) {
    attitudes = calibration::AttitudesFromNav(mag, ReadAll<NavState>(*OpenNav(FLAGS_truth)));
    if (!FLAGS_imu.empty()) std::cerr << "calibrate-mag: --truth gives roll and pitch; --imu is not used\n";
  } else if (!FLAGS_imu.empty()) {
    attitudes = calibration::AttitudesFromAccelerometer(mag, ReadAll<ImuSample>(*OpenImu(FLAGS_imu)));
  } else {
    attitudes = calibration::LevelAttitudes(mag);
    if (two_axis) std::cerr << "calibrate-mag: no --truth or --imu: every sample is taken as level\n";
  }
  const std::string& attitude = attitudes.source;

  MagCalibration c;
  std::vector<calibration::RecursiveMagStep> steps;
  try {
    c = FitByMethod(mag, attitudes.roll_pitch_rad, &steps);
  } catch (const std::runtime_error& e) {  // data that cannot calibrate: the reason, with what was read
    std::cerr << "navtwin calibrate-mag: refused (" << mag.size() << " samples, |m| spread "
              << Fixed(calibration::FieldMagnitudeSpread_uT(mag), 4) << " uT): " << e.what() << "\n";
    return kExitFailure;
  }
  const calibration::HeadingErrors heading =
      calibration::MagHeadingErrors(mag, attitudes.euler_rad, c, two_axis, FLAGS_declination_deg * kDegToRad);
  if (!FLAGS_truth.empty() && heading.samples == 0) {
    std::cerr << "calibrate-mag: warning: no magnetometer sample inside " << FLAGS_truth
              << " (with |pitch| <= 80 deg): heading errors are n/a\n";
  }

  CalibrationFile file;
  file.created_by = CommandLine();
  file.mag = MagCorrection{c.hard_iron_uT, c.correction, c.field_uT};
  if (!FLAGS_run_dir.empty()) {
    std::ostringstream summary;
    WriteJson(summary, c, heading, attitude, "calibrate-mag");
    std::vector<calibration::RunFolderFile> files = {
        {"residuals.csv", [&c, &mag](std::ostream& o) { calibration::WriteMagResidualsCsv(o, c, mag); }}};
    if (!steps.empty()) {
      files.push_back({"convergence.csv", [&steps](std::ostream& o) { calibration::WriteMagConvergenceCsv(o, steps); }});
    }
    calibration::WriteCalibrationRunFolder(FLAGS_run_dir, summary.str(), file, files);
    std::cerr << "calibrate-mag: run folder " << FLAGS_run_dir << " (summary.json, calibration.yaml, residuals.csv"
              << (steps.empty() ? "" : ", convergence.csv") << ")\n";
    if (FLAGS_report) WriteRunReport("calibrate-mag", FLAGS_run_dir);
  }
  if (!FLAGS_out.empty()) WriteCalibrationFile(FLAGS_out, file);
  if (FLAGS_format == "json") {
    WriteJson(std::cout, c, heading, attitude, "");
    std::cout << "\n";
  } else {
    PrintText(c, heading, attitude);
    if (!FLAGS_out.empty()) std::printf("calibration file: %s\n", FLAGS_out.c_str());
  }
  return kExitOk;
}

}  // namespace

Command CalibrateMagCommand() {
  return {"calibrate-mag",
          "Magnetometer hard and soft iron: 3-axis ellipsoid fit (batch or recursive), planar fit or the 2-axis bidirectional method",
          "navtwin calibrate-mag --mag F --method ellipsoid|recursive|planar|bidirectional [--imu F] [--truth NAV] "
          "[--declination_deg D] [--field_uT B] [--out FILE] [--run_dir DIR [--report]] [--format=json]\n"
          "  recursive: the ellipsoid fit's recursive form, sample by sample, printing the estimate after\n"
          "  every 1/20 of the record (--run_dir adds convergence.csv); no sigma.\n"
          "  planar: 3-axis data near one plane (a level turn in any sensor plane); the axis normal to\n"
          "  the plane is not calibrated (reported as uncalibrated_axis_sensor).\n"
          "  Roll and pitch come from --truth, else the --imu accelerometer, else level; the heading error\n"
          "  before and after needs --truth (else n/a). --out writes the calibration file\n"
          "  (docs/calibration-file.md) that --calibration applies; --run_dir the run folder with every\n"
          "  sample's field magnitude before and after (docs/run-folder.md), --report its page.\n"
          "  Data that cannot calibrate (too little\n"
          "  rotation) exits 1 with the reason and writes no file.",
          {"mag", "imu", "truth", "method", "out", "run_dir", "report", "declination_deg", "field_uT"},
          &RunCalibrateMag};
}

}  // namespace navtwin::app
