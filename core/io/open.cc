#include "core/io/open.h"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <string_view>
#include <vector>

#include "core/io/ansfl.h"
#include "core/io/csv_imu.h"
#include "core/io/csv_mag_baro.h"
#include "core/io/input_error.h"
#include "core/io/kfgins.h"
#include "core/io/rtklib_pos.h"
#include "core/io/rtklib_walk.h"
#include "core/io/text_reader.h"
#include "core/io/ulog.h"

namespace navtwin {
namespace {

/// Above this a leading time is seconds since 1970 (rtklib-walk converted file), not a
/// GPS week (< 1e4) or seconds of week (< 604800).
constexpr double kEpochSecondsThreshold = 1e8;
/// KF-GINS 7 columns: GNSS when latitude/longitude (deg) exceed this in magnitude; IMU
/// angle increments (rad) stay far below it.
constexpr double kDegreesNotIncrement = 0.5;

bool EndsWithNoCase(const std::string& s, std::string_view suffix) {
  return s.size() >= suffix.size() &&
         EqualsNoCase(std::string_view(s).substr(s.size() - suffix.size()), suffix);
}

bool Exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

bool StartsWithULogMagic(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {0, 0, 0, 0};
  in.read(magic, 4);
  return in && std::memcmp(magic, "ULog", 4) == 0;
}

/// First line that is not blank and not a '#' note; throws InputError for an empty file.
std::string FirstLine(const std::string& path) {
  LineReader lines(path);
  std::string line;
  while (lines.Next(&line)) {
    if (!IsBlank(line) && Trim(line).front() != '#') return line;
  }
  throw InputError(path, 0, "", "the file is empty");
}

FileFormat FromHeader(const HeaderColumns& h) {
  const auto has = [&h](const char* name) { return h.Find(name) >= 0; };
  if (has("SampleTimeFine")) return FileFormat::kAnsflDotRaw;
  if (has("time") && has("Acc_X") && has("Gyr_X")) return FileFormat::kAnsflImu;
  if (has("time") && has("North") && has("East") && has("Down")) {
    if (has("latitude") && has("xSpeed")) return FileFormat::kAnsflGtExtended;
    if (has("compass_heading")) return FileFormat::kAnsflGt;
  }
  if ((has("t_s") || has("t_ms")) &&
      (has("dtheta_x_rad") || has("gyro_x_rad_s") || has("gyro_x_dps"))) {
    return FileFormat::kCsvImu;
  }
  const bool timed = has("t_s") || has("t_ms");
  if (timed && (has("mx_uT") || has("mx_G") || has("mx_ga") || has("mx_nT"))) {
    return FileFormat::kCsvMag;
  }
  if (timed && (has("pressure_pa") || has("altitude_m"))) return FileFormat::kCsvBaro;
  return FileFormat::kUnknown;
}

/// Data lines looked at to tell a numeric format: a corrupt first line does not decide.
constexpr int kDetectLines = 5;
/// KF-GINS 7 columns near (0 deg, 0 deg): a GNSS fix has positive sigmas in its last three
/// columns and a height, or comes at 5 Hz or slower; IMU samples come at 5 Hz or faster and
/// hold increments (|dtheta_z| < 0.5 rad) there.
constexpr double kImuMaxStep_s = 0.2;

/// Up to `count` data lines (not blank, not a '#' note) with their 1-based line numbers;
/// throws InputError for a file without any.
std::vector<std::pair<long, std::string>> DataLines(const std::string& path, int count) {
  LineReader lines(path);
  std::vector<std::pair<long, std::string>> out;
  std::string line;
  while (static_cast<int>(out.size()) < count && lines.Next(&line)) {
    if (!IsBlank(line) && Trim(line).front() != '#') out.emplace_back(lines.line_number(), line);
  }
  if (out.empty()) throw InputError(path, 0, "", "the file is empty");
  return out;
}

/// The numbers of a line split on blanks and commas; false when a field is not a number.
bool Numbers(const std::string& path, const std::string& line, std::vector<double>* v) {
  std::vector<std::string_view> fields;
  SplitLoose(Trim(line), &fields);
  v->clear();
  for (std::string_view text : fields) {
    try {
      v->push_back(ParseDouble(text, path, 1, ""));
    } catch (const InputError&) {
      return false;
    }
  }
  return true;
}

/// The format of numeric data lines: the first line that is all numbers with a known count
/// decides; 7 columns (KF-GINS IMU or GNSS) are GNSS with latitude/longitude beyond 0.5 deg,
/// else with positive sigmas and a height beyond 0.5 m or a time step of 0.2 s or more.
FileFormat FromNumberLines(const std::string& path, const std::vector<std::pair<long, std::string>>& lines) {
  std::vector<double> v, next;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (!Numbers(path, lines[i].second, &v)) continue;
    switch (v.size()) {
      case 7: {
        if (std::max(std::fabs(v[1]), std::fabs(v[2])) > kDegreesNotIncrement) return FileFormat::kKfginsGnss;
        if (!(v[4] > 0.0 && v[5] > 0.0 && v[6] > 0.0)) return FileFormat::kKfginsImu;  // not sigmas
        if (std::fabs(v[3]) > kDegreesNotIncrement) return FileFormat::kKfginsGnss;       // a height
        for (std::size_t j = i + 1; j < lines.size(); ++j) {
          if (Numbers(path, lines[j].second, &next) && next.size() == 7) {
            return next[0] - v[0] >= kImuMaxStep_s ? FileFormat::kKfginsGnss : FileFormat::kKfginsImu;
          }
        }
        return FileFormat::kKfginsImu;
      }
      case 8:  // OB_GINS: an IMU with the odometer speed
        return FileFormat::kKfginsImu;
      case 11:
        return v[0] > kEpochSecondsThreshold ? FileFormat::kRtklibWalkImuSf : FileFormat::kKfginsNav;
      case 13:
        return FileFormat::kKfginsGnss;
      default:
        continue;
    }
  }
  return FileFormat::kUnknown;
}

/// Why a file's kind is unknown, as an InputError naming the line and the field.
[[noreturn]] void RefuseUnknown(const std::string& path) {
  const std::vector<std::pair<long, std::string>> lines = DataLines(path, 1);
  const auto& [number, line] = lines.front();
  std::vector<std::string_view> fields;
  SplitCsv(Trim(line), &fields);
  const char c = fields.front().empty() ? ' ' : fields.front().front();
  if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z')) {
    throw InputError(path, number, "header",
                     "the columns are not a format navtwin reads (CSV IMU: t_s or t_ms with dtheta_x_rad, "
                     "gyro_x_rad_s or gyro_x_dps; magnetometer: t_s with mx_uT, mx_G, mx_ga or mx_nT; barometer: t_s "
                     "with pressure_pa or altitude_m; Xsens DOT and ANSFL files; docs/formats.md)");
  }
  SplitLoose(Trim(line), &fields);
  for (std::size_t k = 0; k < fields.size(); ++k) ParseDouble(fields[k], path, number, "field " + std::to_string(k + 1));
  throw InputError(path, number, "",
                   std::to_string(fields.size()) + " numbers in the first data lines: the numeric formats have 7 "
                   "(KF-GINS IMU or GNSS), 8 (OB_GINS IMU), 11 (KF-GINS navigation, rtklib-walk) or 13 (KF-GINS "
                   "GNSS with velocity) columns (docs/formats.md)");
}

[[noreturn]] void Refuse(const std::string& path, const char* stream, FileFormat format) {
  if (format == FileFormat::kUnknown) RefuseUnknown(path);
  throw InputError(
      path, 0, "",
      std::string("cannot read ") + stream + " from a file of kind " + FormatName(format));
}

std::vector<std::string> HeaderNames(const std::string& path) {
  std::vector<std::string_view> fields;
  const std::string line = FirstLine(path);
  SplitCsv(line, &fields);
  return std::vector<std::string>(fields.begin(), fields.end());
}

FileSummary Summary(const std::string& path, FileFormat format) {
  FileSummary s;
  s.path = path;
  s.kind = FormatName(format);
  return s;
}

FileSummary DescribeKfginsGnss(const std::string& path) {
  FileSummary s = Summary(path, FileFormat::kKfginsGnss);
  auto reader = OpenKfginsGnss(path);
  TimeTagStats stats;
  GnssSample g;
  bool velocity = false;
  while (reader->Next(&g)) {
    stats.Add(g.t_s);
    velocity = g.has_velocity;
  }
  std::vector<std::string> fields = {"t [s of GPS week]", "lat lon [deg]", "h [m]",
                                     "sigma_n sigma_e sigma_d [m]"};
  if (velocity)
    fields.insert(fields.end(), {"v_n v_e v_d [m/s]", "sigma_vn sigma_ve sigma_vd [m/s]"});
  s.streams.push_back(StreamSummary::FromStats("gnss", stats, fields));
  return s;
}

FileSummary DescribeNav(const std::string& path, FileFormat format, std::vector<std::string> fields,
                        const char* note) {
  FileSummary s = Summary(path, format);
  auto reader = OpenNav(path);
  s.streams.push_back(SummarizeStream<NavState>(reader.get(), "nav", std::move(fields)));
  if (note != nullptr) s.notes.push_back(note);
  return s;
}

}  // namespace

FileFormat DetectFormat(const std::string& path) {
  if (EndsWithNoCase(path, ".ulg") || StartsWithULogMagic(path)) return FileFormat::kULog;
  const std::vector<std::pair<long, std::string>> lines = DataLines(path, kDetectLines);
  const std::string_view first = Trim(lines.front().second);
  if (first.front() == '%') return FileFormat::kRtklibPos;
  std::vector<std::string_view> fields;
  SplitCsv(first, &fields);
  const char c = fields.front().empty() ? ' ' : fields.front().front();
  if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z')) {
    for (std::string_view& f : fields) f = StripUnit(f);
    return FromHeader(HeaderColumns(fields, path, lines.front().first));
  }
  if (Exists(path + ".tag")) return FileFormat::kRtklibWalkImu;
  return FromNumberLines(path, lines);
}

std::string FormatName(FileFormat format) {
  switch (format) {
    case FileFormat::kKfginsImu:
      return "kfgins-imu";
    case FileFormat::kKfginsGnss:
      return "kfgins-gnss";
    case FileFormat::kKfginsNav:
      return "kfgins-nav";
    case FileFormat::kRtklibPos:
      return "rtklib-pos";
    case FileFormat::kCsvImu:
      return "csv-imu";
    case FileFormat::kAnsflImu:
      return "ansfl-imu";
    case FileFormat::kAnsflDotRaw:
      return "ansfl-dot-raw";
    case FileFormat::kAnsflGt:
      return "ansfl-gt";
    case FileFormat::kAnsflGtExtended:
      return "ansfl-gt-extended";
    case FileFormat::kRtklibWalkImu:
      return "rtklib-walk-imu";
    case FileFormat::kRtklibWalkImuSf:
      return "rtklib-walk-imu-sf";
    case FileFormat::kULog:
      return "ulog";
    case FileFormat::kCsvMag:
      return "csv-mag";
    case FileFormat::kCsvBaro:
      return "csv-baro";
    case FileFormat::kUnknown:
      break;
  }
  return "unknown";
}

std::unique_ptr<ImuReader> OpenImu(const std::string& path) {
  const FileFormat format = DetectFormat(path);
  switch (format) {
    case FileFormat::kKfginsImu:
      return OpenKfginsImu(path);
    case FileFormat::kCsvImu:
      return OpenCsvImu(path);
    case FileFormat::kAnsflImu:
      return OpenAnsflImu(path);
    case FileFormat::kAnsflDotRaw:
      return OpenAnsflDotRawImu(path);
    case FileFormat::kRtklibWalkImu:
      return OpenRtklibWalkImu(path);
    case FileFormat::kRtklibWalkImuSf:
      return OpenRtklibWalkImuSf(path);
    case FileFormat::kULog:
      return OpenULogImu(path);
    default:
      Refuse(path, "IMU samples", format);
  }
}

std::unique_ptr<GnssReader> OpenGnss(const std::string& path) {
  const FileFormat format = DetectFormat(path);
  switch (format) {
    case FileFormat::kKfginsGnss:
      return OpenKfginsGnss(path);
    case FileFormat::kRtklibPos:
      return OpenRtklibPos(path);
    case FileFormat::kULog:
      return OpenULogGnss(path);
    default:
      Refuse(path, "GNSS samples", format);
  }
}

std::unique_ptr<NavReader> OpenNav(const std::string& path) {
  const FileFormat format = DetectFormat(path);
  switch (format) {
    case FileFormat::kKfginsNav:
      return OpenKfginsNav(path);
    case FileFormat::kAnsflGt:
      return OpenAnsflGt(path);
    case FileFormat::kAnsflGtExtended:
      return OpenAnsflGtExtended(path);
    case FileFormat::kULog:
      return OpenULogPx4Estimate(path);
    default:
      Refuse(path, "navigation states", format);
  }
}

std::vector<OdometerSample> ReadOdometer(const std::string& path) {
  if (DetectFormat(path) == FileFormat::kKfginsImu) return ReadKfginsImuOdometer(path);
  return ReadOdometerCsv(path);
}

std::unique_ptr<MagReader> OpenMag(const std::string& path) {
  const FileFormat format = DetectFormat(path);
  switch (format) {
    case FileFormat::kCsvMag:
      return OpenCsvMag(path);
    case FileFormat::kAnsflDotRaw:
      return OpenAnsflDotRawMag(path);
    case FileFormat::kULog:
      return OpenULogMag(path);
    default:
      Refuse(path, "magnetometer samples", format);
  }
}

std::unique_ptr<BaroReader> OpenBaro(const std::string& path) {
  const FileFormat format = DetectFormat(path);
  if (format == FileFormat::kULog) return OpenULogBaro(path);
  if (format == FileFormat::kCsvBaro) return OpenCsvBaro(path);
  Refuse(path, "barometer samples", format);
}

FileSummary DescribeFile(const std::string& path) {
  const FileFormat format = DetectFormat(path);
  switch (format) {
    case FileFormat::kULog:
      return DescribeULog(path);
    case FileFormat::kRtklibPos:
      return DescribeRtklibPos(path);
    case FileFormat::kAnsflImu:
      return DescribeAnsflImu(path);
    case FileFormat::kAnsflDotRaw:
      return DescribeAnsflDotRaw(path);
    case FileFormat::kRtklibWalkImu:
      return DescribeRtklibWalkImu(path);
    case FileFormat::kRtklibWalkImuSf:
      return DescribeRtklibWalkImuSf(path);
    case FileFormat::kKfginsGnss:
      return DescribeKfginsGnss(path);
    case FileFormat::kKfginsImu: {
      FileSummary s = Summary(path, format);
      auto reader = OpenKfginsImu(path);
      s.streams.push_back(SummarizeStream<ImuSample>(
          reader.get(), "imu",
          {"t [s of GPS week]", "dtheta_x dtheta_y dtheta_z [rad]", "dv_x dv_y dv_z [m/s]"}));
      s.notes.push_back("the first sample's interval is taken from the second's");
      return s;
    }
    case FileFormat::kCsvImu: {
      FileSummary s = Summary(path, format);
      auto reader = OpenCsvImu(path);
      s.streams.push_back(SummarizeStream<ImuSample>(reader.get(), "imu", HeaderNames(path)));
      return s;
    }
    case FileFormat::kCsvMag: {
      FileSummary s = Summary(path, format);
      auto reader = OpenCsvMag(path);
      s.streams.push_back(SummarizeStream<MagSample>(reader.get(), "mag", HeaderNames(path)));
      return s;
    }
    case FileFormat::kCsvBaro: {
      FileSummary s = Summary(path, format);
      auto reader = OpenCsvBaro(path);
      s.streams.push_back(SummarizeStream<BaroSample>(reader.get(), "baro", HeaderNames(path)));
      return s;
    }
    case FileFormat::kKfginsNav:
      return DescribeNav(path, format,
                         {"week", "sow [s]", "lat lon [deg]", "h [m]", "v_n v_e v_d [m/s]",
                          "roll pitch yaw [deg]"},
                         nullptr);
    case FileFormat::kAnsflGt:
      return DescribeNav(path, format,
                         {"time [s]", "North East Down [m]", "roll pitch compass_heading [deg]"},
                         "position = origin (first GTExtended.csv row beside it, else 0/0 deg, "
                         "0 m) + North/East/Down; velocity from GTExtended.csv speeds, else "
                         "differenced positions");
    case FileFormat::kAnsflGtExtended:
      return DescribeNav(
          path, format,
          {"time [ms]", "latitude longitude [deg]", "altitude_above_seaLevel [m]",
           "xSpeed ySpeed zSpeed = v_N v_E v_D [m/s]", "roll pitch compass_heading [deg]"},
          nullptr);
    case FileFormat::kUnknown:
      break;
  }
  throw InputError(path, 0, "", "not a recognised format (docs/formats.md lists them)");
}

}  // namespace navtwin
