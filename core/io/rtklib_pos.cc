#include "core/io/rtklib_pos.h"

#include <cmath>
#include <map>
#include <string_view>
#include <vector>

#include "core/gps_time.h"
#include "core/io/input_error.h"
#include "core/io/plausibility.h"
#include "core/io/text_reader.h"
#include "core/rotation.h"
#include "core/text.h"

namespace navtwin {
namespace {

// Whole seconds (integer arithmetic on GPS time).
constexpr std::int64_t kDayWhole_s = static_cast<std::int64_t>(kSecondsPerDay);
constexpr std::int64_t kWeekWhole_s = static_cast<std::int64_t>(kSecondsPerWeek);
// Plausible GPS times: weeks from the GPS epoch (1980-01-06) to week 10000 (in 2171),
// so that week arithmetic stays far from overflow; calendar years of that span.
constexpr long long kMaxGpsWeek = 10000;
constexpr long long kFirstGpsYear = 1980;
constexpr long long kLastGpsYear = 2171;
// GPS - UTC was 18 s from 2017; far more is a typing error.
constexpr long long kMaxLeapSeconds = 100;

std::int64_t FloorDiv(std::int64_t a, std::int64_t b) {
  std::int64_t q = a / b;
  if ((a % b != 0) && ((a < 0) != (b < 0))) --q;
  return q;
}

bool StartsWithNoCase(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && EqualsNoCase(s.substr(0, prefix.size()), prefix);
}

/// What the '%' header says.
struct PosHeader {
  std::string time_system;         ///< "GPST" or "UTC"
  std::vector<std::string> names;  ///< base names of the columns after the time
  bool has_leap = false;
  int leap_s = 0;
  long column_line = 0;
};

bool IsDigit(char c) { return c >= '0' && c <= '9'; }

/// "% ... leap seconds: 18" (any '%' line naming "leap" and then an integer): the text of
/// that integer with its sign, empty when the line has none.
std::string_view FindLeapSecondsText(std::string_view line) {
  for (std::size_t i = 0; i + 4 <= line.size(); ++i) {
    if (!EqualsNoCase(line.substr(i, 4), "leap")) continue;
    for (std::size_t j = i + 4; j < line.size(); ++j) {
      if (!IsDigit(line[j])) continue;
      const std::size_t start = line[j - 1] == '-' || line[j - 1] == '+' ? j - 1 : j;
      while (j < line.size() && IsDigit(line[j])) ++j;
      return line.substr(start, j - start);
    }
  }
  return {};
}

/// GPS - UTC in seconds from the header's text; InputError unless 0..kMaxLeapSeconds.
int ParseLeapSeconds(std::string_view text, const std::string& path, long line) {
  const long long leap_s = ParseInteger(text, path, line, "leap seconds");
  if (leap_s < 0 || leap_s > kMaxLeapSeconds) {
    throw InputError(
        path, line, "leap seconds",
        "GPS - UTC must be 0.." + std::to_string(kMaxLeapSeconds) + " s, got " + std::string(text));
  }
  return static_cast<int>(leap_s);
}

void ParseColumnLine(const std::vector<std::string_view>& tokens, const std::string& path,
                     long line, PosHeader* h) {
  for (std::string_view t : tokens) {
    if (StartsWithNoCase(t, "x-ecef")) {
      throw InputError(path, line, "x-ecef",
                       "ECEF x/y/z solution: only latitude/longitude/height output is read "
                       "(set RTKLIB's solution format to lat/lon/height)");
    }
    if (StartsWithNoCase(t, "e-baseline")) {
      throw InputError(path, line, "e-baseline",
                       "E/N/U baseline solution: only latitude/longitude/height output is read "
                       "(set RTKLIB's solution format to lat/lon/height)");
    }
    if (StartsWithNoCase(t, "latitude(d'")) {
      throw InputError(path, line, "latitude",
                       "latitude/longitude in deg-min-sec: export decimal degrees");
    }
  }
  h->time_system = std::string(tokens.front());
  h->column_line = line;
  h->names.clear();
  for (std::size_t i = 1; i < tokens.size(); ++i) h->names.emplace_back(StripUnit(tokens[i]));
}

bool IsColumnLine(const std::vector<std::string_view>& tokens) {
  for (std::string_view t : tokens) {
    if (StartsWithNoCase(t, "latitude") || StartsWithNoCase(t, "x-ecef") ||
        StartsWithNoCase(t, "e-baseline")) {
      return true;
    }
  }
  return false;
}

class RtklibPosReader final : public GnssReader {
 public:
  explicit RtklibPosReader(const std::string& path) : lines_(path) {
    ReadHeader();
    Locate();
  }

  bool Next(GnssSample* s) override {
    if (!have_line_ && !ReadDataLine()) return false;
    have_line_ = false;
    const long line = lines_.line_number();
    RequireFieldCount(fields_.size(), 2 + header_.names.size(), path(), line);
    *s = GnssSample();
    SetTime(line, s);
    const double lat_deg = Get(col_.lat, "latitude");
    if (std::fabs(lat_deg) > 90.0) {
      throw InputError(path(), line, "latitude", "latitude beyond +-90 deg");
    }
    s->lat_rad = lat_deg * kDegToRad;
    s->lon_rad = Get(col_.lon, "longitude") * kDegToRad;
    plausible::Longitude(s->lon_rad, path(), line, "longitude");
    s->h_m = Get(col_.h, "height");
    plausible::Height(s->h_m, path(), line, "height");
    s->quality = ParseWholeNumber(fields_[2 + col_.q], path(), line, "Q");
    s->num_sats = ParseWholeNumber(fields_[2 + col_.ns], path(), line, "ns");
    if (s->quality < 0 || s->num_sats < 0) {
      throw InputError(path(), line, s->quality < 0 ? "Q" : "ns", "negative value");
    }
    s->pos_std_ned_m = Sigmas(col_.sdn, {"sdn", "sde", "sdu"});
    if (col_.vn >= 0) {
      s->has_velocity = true;
      s->v_n_mps =
          Eigen::Vector3d(Get(col_.vn, "vn"), Get(col_.vn + 1, "ve"), -Get(col_.vn + 2, "vu"));
      const char* names[3] = {"vn", "ve", "vu"};
      for (int k = 0; k < 3; ++k) plausible::Velocity(s->v_n_mps[k], path(), line, names[k]);
      s->vel_std_ned_mps = Sigmas(col_.sdvn, {"sdvn", "sdve", "sdvu"});
    }
    return true;
  }
  const std::string& path() const override { return lines_.path(); }
  const std::string& time_system() const { return header_.time_system; }

 private:
  /// Column indices (after the two time fields); velocity ones -1 when absent.
  struct Columns {
    int lat = -1, lon = -1, h = -1, q = -1, ns = -1, sdn = -1;
    int vn = -1, sdvn = -1;
  };

  void ReadHeader() {
    while (lines_.Next(&line_)) {
      if (IsBlank(line_)) continue;
      const std::string_view t = Trim(line_);
      if (t.front() != '%') {
        have_line_ = true;
        break;
      }
      const std::string_view leap_text = FindLeapSecondsText(t);
      if (!leap_text.empty()) {
        header_.has_leap = true;
        header_.leap_s = ParseLeapSeconds(leap_text, path(), lines_.line_number());
      }
      SplitLoose(t.substr(1), &fields_);
      if (!fields_.empty() && IsColumnLine(fields_)) {
        ParseColumnLine(fields_, path(), lines_.line_number(), &header_);
      }
    }
    if (header_.column_line == 0) {
      throw InputError(path(), have_line_ ? lines_.line_number() : 0, "",
                       "no '%' column-name header line (the one naming latitude(deg)), so the "
                       "columns are unknown");
    }
    if (!have_line_) throw InputError(path(), 0, "", "no solution epochs (only a header)");
    SplitLoose(line_, &fields_);
  }

  void Locate() {
    const std::vector<std::string_view> names(header_.names.begin(), header_.names.end());
    const HeaderColumns cols(names, path(), header_.column_line);
    col_.lat = cols.Require("latitude");
    col_.lon = cols.Require("longitude");
    col_.h = cols.Require("height");
    col_.q = cols.Require("Q");
    col_.ns = cols.Require("ns");
    col_.sdn = RequireRun(cols, {"sdn", "sde", "sdu"});
    if (cols.Find("vn") >= 0) {
      col_.vn = RequireRun(cols, {"vn", "ve", "vu"});
      col_.sdvn = RequireRun(cols, {"sdvn", "sdve", "sdvu"});
    }
    const std::string& ts = header_.time_system;
    if (EqualsNoCase(ts, "UTC")) {
      if (!header_.has_leap) {
        throw InputError(path(), header_.column_line, "UTC",
                         "times are UTC and the header does not state the GPS-UTC leap seconds; "
                         "export GPST times (or add a '% leap seconds: N' header line)");
      }
    } else if (!EqualsNoCase(ts, "GPST")) {
      throw InputError(path(), header_.column_line, ts,
                       "time system '" + ts + "' is not read; export GPST times");
    }
  }

  /// Three columns that must be adjacent and in this order (x, y, z of one quantity).
  int RequireRun(const HeaderColumns& cols, std::initializer_list<const char*> names) {
    const int first = cols.Require(*names.begin());
    int k = 0;
    for (const char* n : names) {
      if (cols.Require(n) != first + k++) {
        throw InputError(path(), header_.column_line, n,
                         std::string("column '") + n + "' is not where expected (after '" +
                             *names.begin() + "')");
      }
    }
    return first;
  }

  bool ReadDataLine() {
    while (lines_.Next(&line_)) {
      if (IsBlank(line_)) continue;
      if (Trim(line_).front() == '%') continue;
      SplitLoose(line_, &fields_);
      return true;
    }
    return false;
  }

  double Get(int column, const char* name) const {
    return ParseDouble(fields_[2 + column], path(), lines_.line_number(), name);
  }

  Eigen::Vector3d Sigmas(int first, std::initializer_list<const char*> names) const {
    Eigen::Vector3d s;
    int k = 0;
    for (const char* n : names) {
      s[k] = Get(first + k, n);
      RequirePositive(s[k], path(), lines_.line_number(), n);
      plausible::Sigma(s[k], path(), lines_.line_number(), n);
      ++k;
    }
    return s;
  }

  /// Seconds since the GPS epoch, split as whole days and seconds of day (exact enough
  /// for millisecond times and no loss from 1.4e9-second magnitudes).
  void SetTime(long line, GnssSample* s) {
    std::int64_t week = 0;
    double sow = 0.0;
    if (fields_[0].find('/') != std::string_view::npos) {
      CalendarTime(line, &week, &sow);
    } else {
      week = ParseInteger(fields_[0], path(), line, "week");
      sow = ParseDouble(fields_[1], path(), line, "tow");
      CheckGpsWeek(week, path(), line, "week");
      if (sow < 0.0 || sow >= kSecondsPerWeek) {
        throw InputError(
            path(), line, "tow",
            "seconds of week " + PrintableText(std::string(fields_[1])) + " outside [0, 604800)");
      }
    }
    if (EqualsNoCase(header_.time_system, "UTC")) sow += header_.leap_s;
    if (!has_first_week_) {
      first_week_ = week;
      has_first_week_ = true;
    }
    s->gps_week = static_cast<int>(first_week_);
    s->t_s = static_cast<double>((week - first_week_) * kWeekWhole_s) + sow;
    time_.Check(s->t_s, path(), line, "time");
  }

  void CalendarTime(long line, std::int64_t* week, double* sow) {
    std::vector<std::string_view> parts;
    const auto split = [&](std::string_view text, char sep) {
      parts.clear();
      std::size_t start = 0;
      for (std::size_t p = text.find(sep); p != std::string_view::npos; p = text.find(sep, start)) {
        parts.push_back(text.substr(start, p - start));
        start = p + 1;
      }
      parts.push_back(text.substr(start));
    };
    split(fields_[0], '/');
    if (parts.size() != 3) throw InputError(path(), line, "date", "expected yyyy/mm/dd");
    const long long y = ParseInteger(parts[0], path(), line, "date");
    const long long mo = ParseInteger(parts[1], path(), line, "date");
    const long long d = ParseInteger(parts[2], path(), line, "date");
    split(fields_[1], ':');
    if (parts.size() != 3) throw InputError(path(), line, "time", "expected hh:mm:ss.sss");
    const long long hh = ParseInteger(parts[0], path(), line, "time");
    const long long mm = ParseInteger(parts[1], path(), line, "time");
    const double ss = ParseDouble(parts[2], path(), line, "time");
    if (y < kFirstGpsYear || y > kLastGpsYear) {
      throw InputError(path(), line, "date",
                       "year " + std::to_string(y) + " outside the GPS years " +
                           std::to_string(kFirstGpsYear) + ".." + std::to_string(kLastGpsYear));
    }
    if (mo < 1 || mo > 12 || d < 1 || d > 31 ||
        !IsGregorianDate(static_cast<int>(y), static_cast<int>(mo), static_cast<int>(d))) {
      throw InputError(path(), line, "date",
                       "no such date: " + PrintableText(std::string(fields_[0])));
    }
    if (hh < 0 || hh > 23 || mm < 0 || mm > 59 || ss < 0.0 || ss >= 61.0) {
      throw InputError(path(), line, "time", "no such time of day");
    }
    const std::int64_t days =
        DaysFromCivil(static_cast<int>(y), static_cast<int>(mo), static_cast<int>(d)) -
        DaysFromCivil(1980, 1, 6);
    *week = FloorDiv(days, 7);
    CheckGpsWeek(*week, path(), line, "date");
    *sow = static_cast<double>((days - *week * 7) * kDayWhole_s + hh * 3600 + mm * 60) + ss;
  }

  LineReader lines_;
  PosHeader header_;
  Columns col_;
  std::string line_;
  std::vector<std::string_view> fields_;
  bool have_line_ = false;
  std::int64_t first_week_ = 0;
  bool has_first_week_ = false;
  IncreasingTime time_;
};

}  // namespace

std::int64_t DaysFromCivil(int year, int month, int day) {
  // Count years from March so that the leap day ends the counting year; 719468 is the
  // number of days from 0000-03-01 to 1970-01-01 in the proleptic Gregorian calendar.
  const std::int64_t y = year - (month <= 2 ? 1 : 0);
  const std::int64_t m = month <= 2 ? month + 9 : month - 3;  // March = 0
  const std::int64_t year_days = 365 * y + FloorDiv(y, 4) - FloorDiv(y, 100) + FloorDiv(y, 400);
  const std::int64_t day_of_year = (153 * m + 2) / 5 + day - 1;
  return year_days + day_of_year - 719468;
}

namespace {

/// Whole seconds since 1970 in GPST split into the GPS week (64 bits, unchecked) and the
/// whole seconds into it.
struct WholeGpsWeekTime {
  std::int64_t week;
  std::int64_t sow_whole_s;
};

WholeGpsWeekTime SplitGpst1970(std::int64_t seconds) {
  const std::int64_t since_gps_epoch = seconds - DaysFromCivil(1980, 1, 6) * kDayWhole_s;
  const std::int64_t week = FloorDiv(since_gps_epoch, kWeekWhole_s);
  return {week, since_gps_epoch - week * kWeekWhole_s};
}

GpsWeekTime ToGpsWeekTime(const WholeGpsWeekTime& w, double fraction_s) {
  GpsWeekTime t;
  t.week = static_cast<int>(w.week);
  t.sow_s = static_cast<double>(w.sow_whole_s) + fraction_s;
  return t;
}

}  // namespace

GpsWeekTime GpsTimeFromGpst1970(std::int64_t seconds, double fraction_s) {
  return ToGpsWeekTime(SplitGpst1970(seconds), fraction_s);
}

GpsWeekTime GpsTimeFromGpst1970(std::int64_t seconds, double fraction_s, const std::string& path,
                                long line, const char* field) {
  // Refused first also because the split below would overflow near INT64_MIN.
  if (seconds < 0) throw InputError(path, line, field, "negative time");
  const WholeGpsWeekTime w = SplitGpst1970(seconds);
  CheckGpsWeek(w.week, path, line, field);
  return ToGpsWeekTime(w, fraction_s);
}

void CheckGpsWeek(long long week, const std::string& path, long line, const char* field) {
  if (week < 0 || week > kMaxGpsWeek) {
    throw InputError(path, line, field,
                     "GPS week " + std::to_string(week) + " outside 0.." + std::to_string(kMaxGpsWeek) +
                         " (1980-01-06 to 2171)");
  }
}

std::unique_ptr<GnssReader> OpenRtklibPos(const std::string& path) {
  return std::make_unique<RtklibPosReader>(path);
}

FileSummary DescribeRtklibPos(const std::string& path) {
  RtklibPosReader reader(path);
  FileSummary summary;
  summary.path = path;
  summary.kind = "rtklib-pos";
  TimeTagStats stats;
  std::map<int, std::size_t> per_q;
  GnssSample s;
  bool velocity = false;
  int week = -1;
  while (reader.Next(&s)) {
    stats.Add(s.t_s);
    ++per_q[s.quality];
    velocity = s.has_velocity;
    week = s.gps_week;
  }
  std::vector<std::string> fields = {
      "t [s of GPS week]", "lat [deg]", "lon [deg]", "h [m]", "Q", "ns", "sdn sde sdu [m]"};
  if (velocity) fields.insert(fields.end(), {"vn ve vu [m/s]", "sdvn sdve sdvu [m/s]"});
  summary.streams.push_back(StreamSummary::FromStats("gnss", stats, fields));
  summary.notes.push_back("time system " + reader.time_system() + ", GPS week " +
                          std::to_string(week));
  for (const auto& [q, n] : per_q) {
    summary.notes.push_back("Q=" + std::to_string(q) + ": " + std::to_string(n) + " epochs");
  }
  return summary;
}

}  // namespace navtwin
