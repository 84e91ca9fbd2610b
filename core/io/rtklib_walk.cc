#include "core/io/rtklib_walk.h"

#include <sys/stat.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string_view>
#include <vector>

#include "core/io/csv_imu.h"
#include "core/io/input_error.h"
#include "core/io/plausibility.h"
#include "core/io/rate_to_increment.h"
#include "core/io/rtklib_pos.h"
#include "core/io/text_reader.h"
#include "core/rotation.h"
#include "core/units.h"

namespace navtwin {
namespace {

constexpr std::size_t kTagHeaderBytes = 60;    // text, starting "TIMETAG RTKLIB"
constexpr std::size_t kTagPreambleBytes = 76;  // header + tick_f + time + fraction
constexpr std::size_t kTagRecordBytes = 8;     // uint32 tick_ms, uint32 file position
constexpr std::size_t kRawFields = 7;          // ax ay az gx gy gz t
/// Host tick steps above this are pauses in the data, not the tick period.
constexpr std::uint32_t kMaxTickStepMs = 1000;
/// Tick repeats in at least 1 of this many records mean the tick is coarser than writes.
constexpr std::uint64_t kRepeatShareDenominator = 20;
/// Device and host crystals agree to ~100 ppm; a fitted drift beyond this means the tags
/// do not belong to the file.
constexpr double kMaxDrift = 1e-3;

std::uint64_t FileSize(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throw InputError(path, 0, "", "cannot open the file");
  return static_cast<std::uint64_t>(st.st_size);
}

std::uint64_t LittleEndian(const unsigned char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

/// The RTKLIB time-tag file, read record by record.
class TagFile {
 public:
  explicit TagFile(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw InputError(path, 0, "", "cannot open the time-tag file");
    const std::uint64_t size = FileSize(path);
    if (size < kTagPreambleBytes) {
      throw InputError::AtByte(path, 0, "header", "shorter than the 76-byte time-tag preamble");
    }
    if ((size - kTagPreambleBytes) % kTagRecordBytes != 0) {
      throw InputError::AtByte(
          path, static_cast<long long>(size - (size - kTagPreambleBytes) % kTagRecordBytes),
          "record", "truncated time-tag record");
    }
    records_ = (size - kTagPreambleBytes) / kTagRecordBytes;
    if (records_ == 0) throw InputError::AtByte(path, kTagPreambleBytes, "record", "no time tags");
    ReadPreamble();
    ReadLastPosition();
  }

  /// Next record; validates that ticks and positions never decrease.
  bool Next(std::uint32_t* tick_ms, std::uint32_t* position) {
    if (index_ == records_) return false;
    unsigned char b[kTagRecordBytes];
    const long long at = static_cast<long long>(kTagPreambleBytes + index_ * kTagRecordBytes);
    if (!in_.read(reinterpret_cast<char*>(b), kTagRecordBytes)) {
      throw InputError::AtByte(path_, at, "record", "read failed");
    }
    *tick_ms = static_cast<std::uint32_t>(LittleEndian(b, 4));
    *position = static_cast<std::uint32_t>(LittleEndian(b + 4, 4));
    if (index_ > 0 && *tick_ms < tick_ms_) throw InputError::AtByte(path_, at, "tick", "decreases");
    if (index_ > 0 && *position < position_) {
      throw InputError::AtByte(path_, at, "position", "decreases");
    }
    const std::uint32_t step = *tick_ms - tick_ms_;
    if (index_ > 0 && step == 0) ++repeated_ticks_;
    if (index_ > 0 && step > 0 && step <= kMaxTickStepMs) ++step_histogram_[step];
    tick_ms_ = *tick_ms;
    position_ = *position;
    ++index_;
    return true;
  }

  /// Host tick period. When records often repeat a tick (>= 5 %), writes come faster
  /// than the tick advances, so the typical step between distinct ticks IS the tick
  /// period: the mean of the non-zero steps within a factor 1.5 of their median (Windows
  /// writes its ~15.6 ms period as steps of 15 and 16). Otherwise the tick is finer than
  /// the write spacing and its flooring is neglected (0).
  double TickPeriodMs() const {
    std::uint64_t moving = 0;
    for (std::uint64_t n : step_histogram_) moving += n;
    if (moving == 0 || repeated_ticks_ * kRepeatShareDenominator < (moving + repeated_ticks_)) {
      return 0.0;
    }
    std::uint64_t seen = 0;
    std::size_t median = 0;
    while (median < step_histogram_.size() && (seen += step_histogram_[median]) * 2 < moving)
      ++median;
    double sum = 0.0;
    std::uint64_t n = 0;
    for (std::size_t s = 1; s < step_histogram_.size(); ++s) {
      if (s * 2 < median || s * 2 > median * 3) continue;
      sum += static_cast<double>(s * step_histogram_[s]);
      n += step_histogram_[s];
    }
    return sum / static_cast<double>(n);
  }

  const GpsWeekTime& open_time() const { return open_time_; }
  std::uint32_t last_position() const { return last_position_; }
  const std::string& path() const { return path_; }
  std::uint64_t size() const { return kTagPreambleBytes + records_ * kTagRecordBytes; }

 private:
  void ReadPreamble() {
    unsigned char b[kTagPreambleBytes];
    in_.read(reinterpret_cast<char*>(b), kTagPreambleBytes);
    static const char kMagic[] = "TIMETAG RTKLIB";
    if (!in_ || std::memcmp(b, kMagic, sizeof(kMagic) - 1) != 0) {
      throw InputError::AtByte(path_, 0, "header", "does not start with \"TIMETAG RTKLIB\"");
    }
    const std::uint64_t seconds = LittleEndian(b + kTagHeaderBytes + 4, 4);
    const std::uint64_t fraction_bits = LittleEndian(b + kTagHeaderBytes + 8, 8);
    double fraction = 0.0;
    std::memcpy(&fraction, &fraction_bits, sizeof(fraction));
    if (!(fraction >= 0.0 && fraction < 1.0)) {
      throw InputError::AtByte(path_, kTagHeaderBytes + 8, "fraction", "not in [0, 1)");
    }
    open_time_ = GpsTimeFromGpst1970(static_cast<std::int64_t>(seconds), fraction);
  }

  void ReadLastPosition() {
    in_.seekg(static_cast<std::streamoff>(size() - 4));
    unsigned char b[4];
    in_.read(reinterpret_cast<char*>(b), 4);
    last_position_ = static_cast<std::uint32_t>(LittleEndian(b, 4));
    in_.seekg(static_cast<std::streamoff>(kTagPreambleBytes));
  }

  std::string path_;
  std::ifstream in_;
  std::uint64_t records_ = 0;
  std::uint64_t index_ = 0;
  std::uint32_t tick_ms_ = 0;
  std::uint32_t position_ = 0;
  std::uint32_t last_position_ = 0;
  GpsWeekTime open_time_;
  std::array<std::uint64_t, kMaxTickStepMs + 1> step_histogram_{};
  std::uint64_t repeated_ticks_ = 0;
};

/// One complete line of the raw file.
struct RawRow {
  double acc_mps2[3] = {0, 0, 0};   ///< read in g
  double gyro_radps[3] = {0, 0, 0};  ///< read in deg/s
  double device_ms = 0.0;
  std::uint64_t end_offset = 0;  ///< just past its line break
  std::uint64_t lf_breaks = 0;   ///< bare-LF line breaks up to and including this line's
};

/// Raw lines with the capture-cut rules (see rtklib_walk.h).
class RawRows {
 public:
  explicit RawRows(const std::string& path) : lines_(path) {}

  bool Next(RawRow* row) {
    while (lines_.Next(&line_)) {
      if (lines_.line_end() == LineEnd::kLf) ++lf_breaks_;
      if (IsBlank(line_)) continue;
      SplitCsv(line_, &fields_);
      if (fields_.size() < kRawFields && IsCut()) continue;
      RequireFieldCount(fields_.size(), kRawFields, path(), line());
      Parse(row);
      return true;
    }
    if (rows_ == 0) throw InputError(path(), 0, "", "no samples (the file is empty)");
    return false;
  }
  const std::string& path() const { return lines_.path(); }
  long line() const { return lines_.line_number(); }
  bool cut_first() const { return cut_first_; }
  bool cut_last() const { return cut_last_; }
  std::size_t rows() const { return rows_; }

 private:
  /// A short first line (capture started mid-line) or a short last line without a line
  /// break (capture stopped mid-line).
  bool IsCut() {
    if (rows_ == 0 && !cut_first_ && line() == 1) return cut_first_ = true;
    if (lines_.line_end() == LineEnd::kNone) return cut_last_ = true;
    return false;
  }

  void Parse(RawRow* row) {
    static const char* kNames[6] = {"ax", "ay", "az", "gx", "gy", "gz"};
    for (int k = 0; k < 3; ++k) {
      row->acc_mps2[k] = ParseScaled(fields_[k], kStandardGravity_mps2, path(), line(), kNames[k]);
      row->gyro_radps[k] = ParseScaled(fields_[3 + k], kDegToRad, path(), line(), kNames[3 + k]);
      plausible::SpecificForce(row->acc_mps2[k], path(), line(), kNames[k]);
      plausible::AngularRate(row->gyro_radps[k], path(), line(), kNames[3 + k]);
    }
    const long long t = ParseInteger(fields_[6], path(), line(), "t");
    if (t < 0) throw InputError(path(), line(), "t", "negative device time");
    row->device_ms = static_cast<double>(t);
    time_.Check(row->device_ms * kMillisecond_s, path(), line(), "t");
    row->end_offset = lines_.end_offset();
    row->lf_breaks = lf_breaks_;
    ++rows_;
  }

  LineReader lines_;
  std::string line_;
  std::vector<std::string_view> fields_;
  IncreasingTime time_;
  std::uint64_t lf_breaks_ = 0;
  std::size_t rows_ = 0;
  bool cut_first_ = false;
  bool cut_last_ = false;
};

/// Streaming lower convex hull of points with increasing x, and the hull edge that
/// minimises the mean height of all points above it.
class LowerEnvelope {
 public:
  void Add(double x, double y) {
    while (hull_.size() >= 2 && Turn(hull_[hull_.size() - 2], hull_.back(), {x, y}) <= 0.0) {
      hull_.pop_back();
    }
    hull_.push_back({x, y});
    sum_x_ += x;
    sum_y_ += y;
    ++n_;
  }
  /// Fills intercept c and slope b of the best edge and the mean height above it.
  void Fit(double* c, double* b, double* mean_height) const {
    const double mx = sum_x_ / static_cast<double>(n_);
    const double my = sum_y_ / static_cast<double>(n_);
    *b = 0.0;
    *c = hull_.front().y;
    *mean_height = my - *c;
    for (std::size_t i = 1; i < hull_.size(); ++i) {
      const Point& p = hull_[i - 1];
      const Point& q = hull_[i];
      const double slope = (q.y - p.y) / (q.x - p.x);
      const double intercept = p.y - slope * p.x;
      const double height = my - (intercept + slope * mx);
      if (i == 1 || height < *mean_height) {
        *b = slope;
        *c = intercept;
        *mean_height = height;
      }
    }
  }
  std::size_t count() const { return n_; }

 private:
  struct Point {
    double x, y;
  };
  static double Turn(const Point& o, const Point& a, const Point& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
  }
  std::vector<Point> hull_;
  double sum_x_ = 0.0, sum_y_ = 0.0;
  std::size_t n_ = 0;
};

/// Number of bare-LF line breaks in a file (one streaming pass).
std::uint64_t CountLfBreaks(const std::string& path) {
  LineReader lines(path);
  std::string line;
  std::uint64_t n = 0;
  while (lines.Next(&line)) n += lines.line_end() == LineEnd::kLf ? 1 : 0;
  return n;
}

/// Whether tag positions count CRLF line ends in a file now stored with LF ends.
bool TagsCountCrlf(const std::string& path, const TagFile& tags) {
  const std::uint64_t size = FileSize(path);
  if (tags.last_position() == size) return false;
  const std::uint64_t breaks = CountLfBreaks(path);
  if (tags.last_position() == size + breaks) return true;
  throw InputError::AtByte(tags.path(), static_cast<long long>(tags.size() - 4), "position",
                           "the last tag position " + std::to_string(tags.last_position()) +
                               " matches neither the size of " + path + " (" +
                               std::to_string(size) + " bytes) nor its size with CRLF line ends (" +
                               std::to_string(size + breaks) + ")");
}

class WalkImuReader final : public ImuReader {
 public:
  explicit WalkImuReader(const std::string& path) : clock_(FitRtklibWalkClock(path)), rows_(path) {}

  bool Next(ImuSample* sample) override {
    RawRow r;
    while (rows_.Next(&r)) {
      RateSample rate;
      rate.t_s = clock_.GpsSow(r.device_ms);
      for (int k = 0; k < 3; ++k) {
        rate.acc_mps2[k] = r.acc_mps2[k];
        rate.gyro_radps[k] = r.gyro_radps[k];
      }
      if (to_increment_.Add(rate, sample)) return true;
    }
    if (rows_.rows() == 1) {
      throw InputError(path(), 0, "", "a single rate sample gives no increment (need two)");
    }
    return false;
  }
  const std::string& path() const override { return rows_.path(); }
  const RtklibWalkClock& clock() const { return clock_; }
  bool cut_first() const { return rows_.cut_first(); }
  bool cut_last() const { return rows_.cut_last(); }

 private:
  RtklibWalkClock clock_;
  RawRows rows_;
  RateToIncrement to_increment_;
};

class WalkSfReader final : public ImuReader {
 public:
  explicit WalkSfReader(const std::string& path) : lines_(path) {}

  bool Next(ImuSample* sample) override {
    while (lines_.Next(&line_)) {
      if (IsBlank(line_)) continue;
      SplitCsv(line_, &fields_);
      if (columns_ == 0) {
        if (fields_.size() < kRawFields)
          RequireFieldCount(fields_.size(), kRawFields, path(), line());
        columns_ = fields_.size();
      }
      RequireFieldCount(fields_.size(), columns_, path(), line());
      ++rows_;
      if (to_increment_.Add(Parse(), sample)) return true;
    }
    if (rows_ == 0) throw InputError(path(), 0, "", "no samples (the file is empty)");
    if (rows_ == 1) {
      throw InputError(path(), line(), "", "a single rate sample gives no increment (need two)");
    }
    return false;
  }
  const std::string& path() const override { return lines_.path(); }
  int gps_week() const { return week0_; }

 private:
  long line() const { return lines_.line_number(); }

  RateSample Parse() {
    RateSample r;
    r.t_s = TimeOfWeek(fields_[0]);
    time_.Check(r.t_s, path(), line(), "time");
    static const char* kNames[6] = {"ax", "ay", "az", "gx", "gy", "gz"};
    for (int k = 0; k < 3; ++k) {
      r.acc_mps2[k] = ParseScaled(fields_[1 + k], kStandardGravity_mps2, path(), line(), kNames[k]);
      r.gyro_radps[k] = ParseDouble(fields_[4 + k], path(), line(), kNames[3 + k]);
      plausible::SpecificForce(r.acc_mps2[k], path(), line(), kNames[k]);
      plausible::AngularRate(r.gyro_radps[k], path(), line(), kNames[3 + k]);
    }
    return r;
  }

  /// "1756402240.9670007" (GPST seconds since 1970): whole seconds and fraction parsed
  /// apart so that no precision is lost to the 1.7e9 magnitude.
  double TimeOfWeek(std::string_view text) {
    const std::size_t dot = text.find('.');
    const long long whole = ParseInteger(text.substr(0, dot), path(), line(), "time");
    double fraction = 0.0;
    if (dot != std::string_view::npos) {
      const std::string digits = "0." + std::string(text.substr(dot + 1));
      fraction = ParseDouble(digits, path(), line(), "time");
    }
    const GpsWeekTime t = GpsTimeFromGpst1970(whole, fraction, path(), line(), "time");
    if (rows_ == 1) week0_ = t.week;
    return (t.week - week0_) * kSecondsPerWeek + t.sow_s;
  }

  LineReader lines_;
  std::string line_;
  std::vector<std::string_view> fields_;
  std::size_t columns_ = 0;
  std::size_t rows_ = 0;
  int week0_ = 0;
  IncreasingTime time_;
  RateToIncrement to_increment_;
};

std::string Fixed(double v, int decimals) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(decimals);
  os << v;
  return os.str();
}

}  // namespace

double RtklibWalkClock::GpsSow(double device_ms) const {
  const double x = device_ms - first_device_ms;
  return open_sow_s + (x * (1.0 + drift) + offset_ms + tick_period_ms) * kMillisecond_s;
}

RtklibWalkClock FitRtklibWalkClock(const std::string& path) {
  TagFile tags(path + ".tag");
  RtklibWalkClock clock;
  clock.crlf_positions = TagsCountCrlf(path, tags);
  clock.gps_week = tags.open_time().week;
  clock.open_sow_s = tags.open_time().sow_s;
  RawRows rows(path);
  LowerEnvelope envelope;
  std::uint32_t tick = 0, position = 0;
  bool have_tag = tags.Next(&tick, &position);
  RawRow r;
  while (rows.Next(&r)) {
    if (envelope.count() == 0) clock.first_device_ms = r.device_ms;
    const std::uint64_t end = r.end_offset + (clock.crlf_positions ? r.lf_breaks : 0);
    while (have_tag && position < end) have_tag = tags.Next(&tick, &position);
    if (!have_tag) break;
    const double x = r.device_ms - clock.first_device_ms;
    envelope.Add(x, static_cast<double>(tick) - x);
  }
  while (tags.Next(&tick, &position)) {
  }
  if (envelope.count() == 0) {
    throw InputError(tags.path(), 0, "", "no line of " + path + " is covered by a time tag");
  }
  envelope.Fit(&clock.offset_ms, &clock.drift, &clock.mean_delay_ms);
  if (std::fabs(clock.drift) > kMaxDrift) {
    throw InputError(tags.path(), 0, "",
                     "device and host clocks would differ by " + Fixed(clock.drift / kPpm, 0) +
                         " ppm: the tags do not fit " + path);
  }
  clock.tick_period_ms = tags.TickPeriodMs();
  clock.paired_lines = envelope.count();
  return clock;
}

std::unique_ptr<ImuReader> OpenRtklibWalkImu(const std::string& path) {
  return std::make_unique<WalkImuReader>(path);
}

std::unique_ptr<ImuReader> OpenRtklibWalkImuSf(const std::string& path) {
  return std::make_unique<WalkSfReader>(path);
}

FileSummary DescribeRtklibWalkImu(const std::string& path) {
  WalkImuReader reader(path);
  FileSummary summary;
  summary.path = path;
  summary.kind = "rtklib-walk-imu";
  summary.streams.push_back(SummarizeStream<ImuSample>(
      &reader, "imu", {"ax ay az [g]", "gx gy gz [deg/s]", "t [ms, device clock]"}));
  const RtklibWalkClock& c = reader.clock();
  summary.notes.push_back("t_s = GPS seconds of week " + std::to_string(c.gps_week) +
                          "; axes: the IMU's own (z up at rest), not rotated");
  summary.notes.push_back(
      "device ms -> GPS: file opened at " + Fixed(c.open_sow_s, 3) + " s of week; first line " +
      Fixed(c.first_device_ms, 0) + " ms at +" + Fixed(c.offset_ms + c.tick_period_ms, 1) +
      " ms; drift " + Fixed(c.drift / kPpm, 1) + " ppm; host tick " + Fixed(c.tick_period_ms, 2) +
      " ms; mean receipt delay above the envelope " + Fixed(c.mean_delay_ms, 1) + " ms; " +
      std::to_string(c.paired_lines) + " lines paired with tags" +
      (c.crlf_positions ? "; tag positions count CRLF line ends" : ""));
  if (reader.cut_first()) summary.notes.push_back("first line cut by the capture start: skipped");
  if (reader.cut_last()) summary.notes.push_back("last line cut by the capture end: skipped");
  return summary;
}

FileSummary DescribeRtklibWalkImuSf(const std::string& path) {
  WalkSfReader reader(path);
  FileSummary summary;
  summary.path = path;
  summary.kind = "rtklib-walk-imu-sf";
  summary.streams.push_back(SummarizeStream<ImuSample>(
      &reader, "imu", {"time [s since 1970, GPST]", "ax ay az [g]", "gx gy gz [rad/s]"}));
  summary.notes.push_back("t_s = GPS seconds of week " + std::to_string(reader.gps_week()) +
                          "; values smoothed by the source project; extra columns ignored");
  return summary;
}

}  // namespace navtwin
