// navtwin convert --in F --out F: reads any supported input and writes the KF-GINS text
// formats (IMU, GNSS, navigation), the navtwin IMU CSV, or the navtwin magnetometer and
// barometer CSV. The output appears whole or not at all.
//
// ULog inputs: times are GPS seconds of week when the log has GPS fixes with UTC, else
// seconds since boot (core/io/ulog_time.h); which one is printed on stderr, and CSV
// outputs carry it as a '#' note before the header. `--what px4_estimate` (or `nav`)
// writes PX4's own EKF2 solution as a KF-GINS navigation file (OpenULogPx4Estimate).
//
// Navigation inputs (the ANSFL DJI reference GT.csv / GTExtended.csv, KF-GINS .nav) with
// `--what gnss`: one GNSS fix per record with the sigma of --pos_sigma_m / --vel_sigma_mps
// (core/io/nav_as_gnss.h), so a reference solution can aid `smooth` / `navigate`. For the
// ANSFL files the flags default to kAnsflReferencePosSigma_m / kAnsflReferenceVelSigma_mps
// (core/io/ansfl.h gives the reasoning); other navigation files need them stated.
//
// Navigation streams also go to other people's tools (core/io/track_export.h): `--to kml`
// (Google Earth; `--std std.csv --ellipse_sigma K` adds K-sigma horizontal ellipses every
// --ellipse_interval_s), `--to gpx`, `--to pos` (RTKLIB, for rtkplot; needs --std for its
// sigma columns). The format follows the output's extension when --to is not given.
#include <gflags/gflags.h>

#include <cmath>
#include <iostream>
#include <stdexcept>
#include <utility>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/ansfl.h"
#include "core/io/csv_imu.h"
#include "core/io/csv_mag_baro.h"
#include "core/io/input_error.h"
#include "core/io/json_writer.h"
#include "core/io/kfgins.h"
#include "core/io/nav_as_gnss.h"
#include "core/io/open.h"
#include "core/io/ulog.h"
#include "core/io/track_export.h"
#include "core/io/ulog_time.h"

DEFINE_string(in, "", "Input file (any format `navtwin info` knows)");
DEFINE_string(what, "",
              "Stream to convert: imu, gnss, nav, mag, baro or px4_estimate (ULog: PX4's own "
              "estimate, the same as nav) (default: the file's main stream)");
DEFINE_string(to, "",
              "Output format: kfgins or csv; for navigation streams also kml, gpx or pos (RTKLIB) (default: from "
              "the output's extension .csv/.kml/.gpx/.pos, else kfgins; mag and baro: csv)");
DEFINE_string(std, "",
              "A run's std.csv with the navigation file's sigmas (--to pos: required, its sigma columns; --to kml: "
              "for --ellipse_sigma)");
DEFINE_double(ellipse_sigma, 0.0, "--to kml: draw the K-sigma horizontal position ellipse (0: none; needs --std)");
DEFINE_double(ellipse_interval_s, 1.0, "--to kml: one ellipse at least this many seconds apart");
DEFINE_double(pos_sigma_m, NAN,
              "convert --what gnss from a navigation file: position sigma per axis of the fixes, m (ANSFL "
              "GT.csv/GTExtended.csv default 0.1; required for other navigation files)");
DEFINE_double(vel_sigma_mps, NAN,
              "convert --what gnss from a navigation file: velocity sigma per axis of the fixes, m/s (ANSFL "
              "default 0.15; required for other navigation files)");

namespace navtwin::app {
namespace {

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// The stream a file of this kind is mainly about.
std::string MainStream(FileFormat f) {
  switch (f) {
    case FileFormat::kKfginsGnss:
    case FileFormat::kRtklibPos:
      return "gnss";
    case FileFormat::kKfginsNav:
    case FileFormat::kAnsflGt:
    case FileFormat::kAnsflGtExtended:
      return "nav";
    case FileFormat::kCsvMag:
      return "mag";
    case FileFormat::kCsvBaro:
      return "baro";
    default:
      return "imu";
  }
}

template <typename Sample, typename Writer>
std::size_t CopyAll(SampleReader<Sample>& reader, Writer& writer) {
  Sample s;
  std::size_t n = 0;
  while (reader.Next(&s)) {
    writer.Write(s);
    ++n;
  }
  writer.Commit();
  return n;
}

int Usage(const std::string& why) {
  std::cerr << "navtwin convert: " << why << "\nusage: " << ConvertCommand().usage << "\n";
  return kExitUsage;
}

/// What the run needs to know about the input's time scale.
struct InputTime {
  bool ulog = false;
  ULogClock clock;
  /// The '#' note for CSV outputs ("" for inputs other than ULog).
  std::string Note(const std::string& in) const {
    if (!ulog) return "";
    return clock.gps ? "t_s: GPS seconds of week " + std::to_string(clock.gps_week) + " (from " +
                           in + ", " + clock.source + " + " + std::to_string(clock.leap_s) +
                           " leap seconds)"
                     : "t_s: seconds since boot of " + in + " (the log has no GPS time)";
  }
};

/// PX4 estimate: what was skipped and which height, on stderr.
void ReportEstimate(const Px4EstimateStats& st) {
  std::cerr << "navtwin convert: PX4 estimate: " << st.epochs
            << " epochs at vehicle_global_position; skipped " << st.invalid << " invalid, "
            << st.outside << " outside the velocity/attitude record, " << st.gaps
            << " with a gap over 0.5 s; " << st.across_reset
            << " took the nearer sample across a reset; height from " << st.height_field
            << (st.ellipsoid ? " (WGS84 ellipsoid)\n"
                             : " (AMSL: differs from WGS84 heights by the geoid undulation)\n");
}

bool IsNavFormat(FileFormat f) {
  return f == FileFormat::kKfginsNav || f == FileFormat::kAnsflGt || f == FileFormat::kAnsflGtExtended;
}

bool IsAnsflReference(FileFormat f) { return f == FileFormat::kAnsflGt || f == FileFormat::kAnsflGtExtended; }

/// The sigmas of fixes made from a navigation file: the flags, or the ANSFL defaults.
NavAsGnssOptions ReferenceSigmas(FileFormat f) {
  NavAsGnssOptions o;
  o.pos_sigma_m = std::isnan(FLAGS_pos_sigma_m) && IsAnsflReference(f) ? kAnsflReferencePosSigma_m : FLAGS_pos_sigma_m;
  o.vel_sigma_mps =
      std::isnan(FLAGS_vel_sigma_mps) && IsAnsflReference(f) ? kAnsflReferenceVelSigma_mps : FLAGS_vel_sigma_mps;
  return o;
}

/// What a user of fixes made from the ANSFL reference must know, on stderr.
void ReportAnsflReference(FileFormat f, const NavAsGnssOptions& o) {
  std::cerr << "navtwin convert: " << FLAGS_in << ": the DJI reference as GNSS fixes, sigma " << o.pos_sigma_m
            << " m and " << o.vel_sigma_mps << " m/s per axis; heights above mean sea level (the DJI log's)\n";
  if (f == FileFormat::kAnsflGtExtended) {
    std::cerr << "navtwin convert: note: GTExtended.csv times are the DJI log's clock (ms / 1000); the "
                 "time offset transfer-align-ansfl writes refers to GT.csv's times: convert GT.csv (it takes "
                 "GTExtended.csv's speeds and origin when beside it) to use that calibration\n";
  } else {
    std::cerr << "navtwin convert: GT.csv times (s from the path start); velocity from GTExtended.csv's speeds "
                 "when beside it, else differenced positions; origin of N/E/D: GTExtended.csv's first row, else "
                 "the StraightLine take-off point (docs/formats.md)\n";
  }
}

std::size_t WriteTrack(NavReader& reader, const std::string& to);

/// Writes a navigation stream in `to` (kfgins, kml, gpx, pos); returns the epoch count. A
/// state the format cannot hold (no GPS week for .pos) is an error naming the input file.
std::size_t WriteNav(NavReader& reader, const std::string& to) {
  if (to == "kfgins") {
    KfginsNavWriter writer(FLAGS_out);
    return CopyAll(reader, writer);
  }
  try {
    return WriteTrack(reader, to);
  } catch (const std::invalid_argument& e) {
    throw InputError(FLAGS_in, 0, "t_s", e.what());
  }
}

/// kml, gpx or pos, with the sigmas of --std.
std::size_t WriteTrack(NavReader& reader, const std::string& to) {
  NavStdSeries sigmas;
  if (!FLAGS_std.empty()) sigmas = ReadNavStdCsv(FLAGS_std);
  const auto sigma_at = [&](const NavState& s) -> long {
    if (FLAGS_std.empty()) return -1;
    const long row = sigmas.Find(s.t_s);
    if (row < 0 && to == "pos") {
      throw InputError(FLAGS_std, 0, "t_s", "no row at t = " + std::to_string(s.t_s) + " s of " + FLAGS_in);
    }
    return row;
  };
  std::size_t n = 0;
  NavState s;
  if (to == "pos") {
    RtklibPosWriter writer(FLAGS_out, FLAGS_in);
    for (; reader.Next(&s); ++n) {
      const long row = sigma_at(s);
      writer.Write(s, sigmas.pos_ned_m[row], sigmas.vel_ned_mps[row]);
    }
    writer.Commit();
  } else if (to == "kml") {
    KmlWriter writer(FLAGS_out, FLAGS_in, FLAGS_ellipse_sigma, FLAGS_ellipse_interval_s);
    for (; reader.Next(&s); ++n) {
      const long row = sigma_at(s);
      writer.Write(s, row >= 0 ? &sigmas.pos_ned_m[row] : nullptr);
    }
    writer.Commit();
  } else {
    GpxWriter writer(FLAGS_out, FLAGS_in);
    for (; reader.Next(&s); ++n) writer.Write(s);
    writer.Commit();
  }
  return n;
}

/// Converts one stream; returns the sample count. `to` is checked already.
std::size_t ConvertStream(const std::string& what, const std::string& to, const InputTime& time) {
  const std::string note = time.Note(FLAGS_in);
  if (what == "imu") {
    auto reader = OpenImu(FLAGS_in);
    if (to == "csv") {
      CsvImuWriter writer(FLAGS_out, note);
      return CopyAll(*reader, writer);
    }
    KfginsImuWriter writer(FLAGS_out);
    return CopyAll(*reader, writer);
  }
  if (what == "gnss" && IsNavFormat(DetectFormat(FLAGS_in))) {
    const FileFormat f = DetectFormat(FLAGS_in);
    const NavAsGnssOptions sigmas = ReferenceSigmas(f);
    if (IsAnsflReference(f)) ReportAnsflReference(f, sigmas);
    auto reader = NavAsGnssReader(OpenNav(FLAGS_in), sigmas);
    KfginsGnssWriter writer(FLAGS_out);
    return CopyAll(*reader, writer);
  }
  if (what == "gnss") {
    auto reader = OpenGnss(FLAGS_in);
    KfginsGnssWriter writer(FLAGS_out);
    return CopyAll(*reader, writer);
  }
  if (what == "mag") {
    auto reader = OpenMag(FLAGS_in);
    CsvMagWriter writer(FLAGS_out, note);
    return CopyAll(*reader, writer);
  }
  if (what == "baro") {
    auto reader = OpenBaro(FLAGS_in);
    CsvBaroWriter writer(FLAGS_out, note);
    return CopyAll(*reader, writer);
  }
  if (time.ulog) {  // nav or px4_estimate from a ULog: PX4's own estimate
    auto reader = OpenULogPx4Estimate(FLAGS_in);
    const std::size_t n = WriteNav(*reader, to);
    ReportEstimate(reader->stats());
    return n;
  }
  if (what == "px4_estimate") {
    throw InputError(FLAGS_in, 0, "px4_estimate",
                     "PX4's estimate comes from a ULog file (.ulg), not from a file of kind " +
                         FormatName(DetectFormat(FLAGS_in)));
  }
  auto reader = OpenNav(FLAGS_in);
  return WriteNav(*reader, to);
}

/// The output format, or "" with *why set when the stream cannot be written so.
std::string OutputFormat(const std::string& what, std::string* why) {
  const bool csv_only = what == "mag" || what == "baro";
  const bool nav = what == "nav" || what == "px4_estimate";
  std::string to = FLAGS_to;
  if (to.empty()) {
    to = csv_only || EndsWith(FLAGS_out, ".csv") ? "csv" : "kfgins";
    for (const char* ext : {"kml", "gpx", "pos"}) {
      if (nav && EndsWith(FLAGS_out, std::string(".") + ext)) to = ext;
    }
  }
  const bool track = to == "kml" || to == "gpx" || to == "pos";
  if (to != "kfgins" && to != "csv" && !track) *why = "--to must be kfgins, csv, kml, gpx or pos";
  if (csv_only && to != "csv") *why = "magnetometer and barometer streams are written as csv only";
  if (what == "gnss" && to != "kfgins") *why = "GNSS streams are written as kfgins only";
  if (nav && to != "kfgins" && !track) *why = "navigation streams are written as kfgins, kml, gpx or pos";
  if (track && !nav) *why = "kml, gpx and pos are written from navigation streams (--what nav)";
  if (to == "pos" && FLAGS_std.empty()) *why = "--to pos needs --std (a run's std.csv) for RTKLIB's sigma columns";
  if (FLAGS_ellipse_sigma != 0.0 && (to != "kml" || FLAGS_std.empty())) {
    *why = "--ellipse_sigma goes with --to kml and --std";
  }
  if (!(FLAGS_ellipse_sigma >= 0.0) || !std::isfinite(FLAGS_ellipse_sigma) || !(FLAGS_ellipse_interval_s >= 0.0) ||
      !std::isfinite(FLAGS_ellipse_interval_s)) {
    *why = "--ellipse_sigma and --ellipse_interval_s must be finite and >= 0";
  }
  if (!FLAGS_std.empty() && !track) *why = "--std goes with --to kml or --to pos";
  return why->empty() ? to : "";
}

void PrintResult(const std::string& what, const std::string& to, FileFormat in_format,
                 const InputTime& time, std::size_t n) {
  if (FLAGS_format == "json") {
    JsonWriter w(std::cout);
    w.BeginObject()
        .Field("in", FLAGS_in)
        .Field("in_kind", FormatName(in_format))
        .Field("stream", what)
        .Field("out", FLAGS_out)
        .Field("out_format", to)
        .Field("samples", n);
    if (time.ulog) {
      w.Field("time_scale", time.clock.gps ? "gps" : "boot").Field("gps_week", time.clock.gps_week);
    }
    w.EndObject();
    std::cout << "\n";
  } else {
    std::cout << "converted " << n << " " << what << " samples from " << FLAGS_in << " ("
              << FormatName(in_format) << ") to " << FLAGS_out << " (" << to << ")\n";
  }
}

/// --pos_sigma_m / --vel_sigma_mps: only for fixes made from a navigation file, > 0, and
/// given for navigation files other than the ANSFL reference; "" when fine.
std::string CheckSigmaFlags(const std::string& what, FileFormat in_format) {
  const bool given = FlagGiven("pos_sigma_m") || FlagGiven("vel_sigma_mps");
  const bool nav_to_gnss = what == "gnss" && IsNavFormat(in_format);
  if (!nav_to_gnss) {
    return given ? "--pos_sigma_m and --vel_sigma_mps go with --what gnss from a navigation file" : "";
  }
  for (const auto& [name, value] : {std::pair<const char*, double>{"pos_sigma_m", FLAGS_pos_sigma_m},
                                    {"vel_sigma_mps", FLAGS_vel_sigma_mps}}) {
    if (FlagGiven(name) && !(std::isfinite(value) && value > 0.0)) {
      return std::string("--") + name + " must be > 0 (a standard deviation)";
    }
    if (!FlagGiven(name) && !IsAnsflReference(in_format)) {
      return std::string("--") + name + " is required for GNSS fixes from a " + FormatName(in_format) +
             " file (a navigation file carries no sigma)";
    }
  }
  return "";
}

int RunConvert(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("unexpected argument '" + args[0] + "'");
  if (FLAGS_in.empty() || FLAGS_out.empty()) return Usage("--in and --out are required");
  if (FLAGS_in == FLAGS_out) return Usage("--in and --out must differ");
  const FileFormat in_format = DetectFormat(FLAGS_in);
  const std::string what = FLAGS_what.empty() ? MainStream(in_format) : FLAGS_what;
  if (what != "imu" && what != "gnss" && what != "nav" && what != "mag" && what != "baro" &&
      what != "px4_estimate") {
    return Usage("--what must be imu, gnss, nav, mag, baro or px4_estimate");
  }
  std::string why;
  const std::string to = OutputFormat(what, &why);
  if (!why.empty()) return Usage(why);
  const std::string sigma_error = CheckSigmaFlags(what, in_format);
  if (!sigma_error.empty()) return Usage(sigma_error);
  InputTime time;
  if (in_format == FileFormat::kULog) {
    time.ulog = true;
    time.clock = FindULogClock(FLAGS_in);
    std::cerr << "navtwin convert: " << FLAGS_in << ": " << time.clock.Describe() << "\n";
  }
  const std::size_t n = ConvertStream(what, to, time);
  PrintResult(what, to, in_format, time, n);
  return kExitOk;
}

}  // namespace

Command ConvertCommand() {
  return {"convert",
          "Convert between formats (ULog, RTKLIB, CSV, drone files -> KF-GINS or CSV; PX4's estimate; navigation -> KML, GPX, RTKLIB .pos)",
          "navtwin convert --in F --out F [--what imu|gnss|nav|mag|baro|px4_estimate] "
          "[--to kfgins|csv|kml|gpx|pos] [--std STD_CSV [--ellipse_sigma K [--ellipse_interval_s S]]] "
          "[--pos_sigma_m S --vel_sigma_mps S (gnss from a navigation file)] [--format=json]",
          {"in", "out", "what", "to", "std", "ellipse_sigma", "ellipse_interval_s", "pos_sigma_m", "vel_sigma_mps"},
          &RunConvert};
}

}  // namespace navtwin::app
