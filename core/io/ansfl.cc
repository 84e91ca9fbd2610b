#include "core/io/ansfl.h"

#include <sys/stat.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string_view>
#include <vector>

#include "core/io/input_error.h"
#include "core/io/plausibility.h"
#include "core/io/rate_to_increment.h"
#include "core/io/text_reader.h"
#include "core/rotation.h"
#include "core/units.h"

namespace navtwin {
namespace {

constexpr std::uint64_t kDotClockModulus = 1ULL << 32;  // SampleTimeFine is a uint32 (us)
/// A SampleTimeFine step (modulo 2^32) longer than this many times the previous nonzero
/// step is a corrupt clock value, not a gap or a wrap (a lost sample doubles the step).
constexpr std::uint64_t kMaxDotStepRatio = 100;
/// The same bound before any step is known: 100 x 1 s, the slowest DOT output rate.
constexpr std::uint64_t kMaxFirstDotStep_us = 100'000'000;
/// A repeated time tag is the lost-sample pattern only after an interval this many times
/// longer than the one before it (the pattern leaves a double interval: ratio 2).
constexpr double kLostSampleGapRatio = 1.5;
/// GT.csv and GTExtended.csv rows pair up when their times (from the first row) agree
/// to this: GT times carry float noise (0.10000000000000142), GTExtended whole ms.
constexpr double kGtPairTolerance_s = 0.005;

bool FileExists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

std::string Folder(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string(".") : path.substr(0, slash);
}

/// Header names reduced to their base ("compass_heading(degrees)" -> "compass_heading").
HeaderColumns BaseNameColumns(const std::vector<std::string_view>& fields, const std::string& path,
                              long line) {
  std::vector<std::string_view> names;
  names.reserve(fields.size());
  for (std::string_view f : fields) names.push_back(StripUnit(f));
  return HeaderColumns(names, path, line);
}

/// A CSV file with a header line: rows split and checked against the header's width.
class CsvRows {
 public:
  /// Reads the header (base names); throws InputError for an empty file.
  explicit CsvRows(const std::string& path) : lines_(path) {
    while (lines_.Next(&line_)) {
      if (IsBlank(line_)) continue;
      SplitCsv(line_, &fields_);
      header_ = BaseNameColumns(fields_, path, lines_.line_number());
      return;
    }
    throw InputError(path, 0, "", "no samples (the file is empty)");
  }
  bool Next() {
    while (lines_.Next(&line_)) {
      if (IsBlank(line_)) continue;
      SplitCsv(line_, &fields_);
      RequireFieldCount(fields_.size(), header_.size(), path(), line());
      ++rows_;
      return true;
    }
    return false;
  }
  double Get(int column) const {
    return ParseDouble(Text(column), path(), line(), header_.names()[column]);
  }
  Eigen::Vector3d Get3(int x, int y, int z) const {
    return Eigen::Vector3d(Get(x), Get(y), Get(z));
  }
  std::string_view Text(int column) const { return fields_[static_cast<std::size_t>(column)]; }
  const HeaderColumns& header() const { return header_; }
  const std::string& path() const { return lines_.path(); }
  long line() const { return lines_.line_number(); }
  std::size_t rows() const { return rows_; }

 private:
  LineReader lines_;
  HeaderColumns header_;
  std::string line_;
  std::vector<std::string_view> fields_;
  std::size_t rows_ = 0;
};

/// One row of a DOT file (processed IMU_k.csv or raw Xsens_DOT*.csv).
struct DotRow {
  long line = 0;
  double t_s = 0.0;
  Eigen::Vector3d acc_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_dps = Eigen::Vector3d::Zero();
  std::string bad_field;  ///< first non-finite Acc/Gyr field (raw files), else empty
  bool lost = false;      ///< second row of a lost-sample pair
  Eigen::Vector3d mag_au = Eigen::Vector3d::Zero();
};

/// DOT rows in time order with the lost-sample repair (see ansfl.h), one row look-ahead.
class DotRows {
 public:
  DotRows(const std::string& path, bool raw) : csv_(path), raw_(raw) {
    const HeaderColumns& h = csv_.header();
    time_name_ = raw ? "SampleTimeFine" : "time";
    time_col_ = h.Require(time_name_);
    const char* names[6] = {"Acc_X", "Acc_Y", "Acc_Z", "Gyr_X", "Gyr_Y", "Gyr_Z"};
    for (int k = 0; k < 6; ++k) inertial_[k] = h.Require(names[k]);
    if (raw && h.Find("Mag_X") >= 0) {
      mag_[0] = h.Require("Mag_X");
      mag_[1] = h.Require("Mag_Y");
      mag_[2] = h.Require("Mag_Z");
      has_mag_ = true;
    }
  }

  bool Next(DotRow* row) {
    if (!has_pending_) {
      if (!Parse(&pending_)) return false;
      has_pending_ = true;
    }
    DotRow next;
    const bool more = Parse(&next);
    if (more && next.t_s == pending_.t_s) Repair(&next);
    if (!pending_.bad_field.empty() && !pending_.lost) {
      throw InputError(path(), pending_.line, pending_.bad_field, "not a finite number");
    }
    time_.Check(pending_.t_s, path(), pending_.line, time_name_);
    if (emitted_ > 0) previous_interval_s_ = pending_.t_s - previous_t_s_;
    previous_t_s_ = pending_.t_s;
    ++emitted_;
    *row = pending_;
    has_pending_ = more;
    if (more) pending_ = next;
    return true;
  }

  const std::string& path() const { return csv_.path(); }
  bool raw() const { return raw_; }
  bool has_mag() const { return has_mag_; }
  std::size_t retimed() const { return retimed_; }
  std::size_t clock_wraps() const { return wraps_; }

 private:
  /// `next` repeats the pending row's time: re-time the pending row to the middle of the
  /// double interval before it, or refuse when the pattern does not fit.
  void Repair(DotRow* next) {
    const bool fits =
        emitted_ >= 2 && pending_.t_s - previous_t_s_ > kLostSampleGapRatio * previous_interval_s_;
    if (!fits) {
      throw InputError(path(), next->line, time_name_,
                       "time repeats line " + std::to_string(pending_.line) +
                           " (not the DOT lost-sample pattern: no double interval before it)");
    }
    pending_.t_s = 0.5 * (previous_t_s_ + pending_.t_s);
    next->lost = true;
    ++retimed_;
  }

  bool Parse(DotRow* row) {
    if (!csv_.Next()) return false;
    row->line = csv_.line();
    row->t_s = raw_ ? DeviceTime() : csv_.Get(time_col_);
    const char* names[6] = {"Acc_X", "Acc_Y", "Acc_Z", "Gyr_X", "Gyr_Y", "Gyr_Z"};
    double v[6];
    for (int k = 0; k < 6; ++k) {
      v[k] = raw_ ? Lenient(inertial_[k]) : csv_.Get(inertial_[k]);
      if (!std::isfinite(v[k]) && row->bad_field.empty()) row->bad_field = names[k];
    }
    row->acc_mps2 = Eigen::Vector3d(v[0], v[1], v[2]);
    row->gyro_dps = Eigen::Vector3d(v[3], v[4], v[5]);
    if (has_mag_) row->mag_au = csv_.Get3(mag_[0], mag_[1], mag_[2]);
    return true;
  }

  /// A number that may be NaN/Infinity (raw DOT lost samples); other text is an error.
  double Lenient(int column) const {
    const std::string_view t = csv_.Text(column);
    double v = 0.0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec == std::errc() && end == t.data() + t.size() && !std::isfinite(v)) return v;
    return csv_.Get(column);
  }

  /// SampleTimeFine (uint32 us) unwrapped at 2^32, in seconds.
  double DeviceTime() {
    const long long raw = ParseInteger(csv_.Text(time_col_), path(), csv_.line(), time_name_);
    if (raw < 0 || raw >= static_cast<long long>(kDotClockModulus)) {
      throw InputError(path(), csv_.line(), time_name_, "not a uint32 microsecond count");
    }
    const std::uint64_t ticks = static_cast<std::uint64_t>(raw);
    if (has_last_tick_) CheckStep(ticks);
    last_tick_ = ticks;
    has_last_tick_ = true;
    return static_cast<double>(ticks + wraps_ * kDotClockModulus) * kMicrosecond_s;
  }

  /// The step from the previous SampleTimeFine: forward by about the sample interval,
  /// across 2^32 when the counter wraps (previous value near 2^32, this one near 0). A
  /// short step back is left to the time check; a step (modulo 2^32) far longer than the
  /// previous one is an InputError: one corrupt value would otherwise pass for a wrap
  /// and shift every later sample by 4295 s.
  void CheckStep(std::uint64_t ticks) {
    const std::uint64_t forward = (ticks + kDotClockModulus - last_tick_) % kDotClockModulus;
    const std::uint64_t backward = (last_tick_ + kDotClockModulus - ticks) % kDotClockModulus;
    const std::uint64_t limit =
        last_step_ > 0 ? kMaxDotStepRatio * last_step_ : kMaxFirstDotStep_us;
    if (forward <= limit) {
      if (ticks < last_tick_) ++wraps_;
      if (forward > 0) last_step_ = forward;
      return;
    }
    if (backward <= limit && ticks < last_tick_) return;  // back: the time check reports it
    throw InputError(path(), csv_.line(), time_name_,
                     "clock jumps from " + std::to_string(last_tick_) + " to " +
                         std::to_string(ticks) + " us: neither about one sample interval (" +
                         std::to_string(last_step_) + " us before) nor a wrap at 2^32");
  }

  CsvRows csv_;
  bool raw_ = false;
  std::string time_name_;
  int time_col_ = -1;
  int inertial_[6] = {-1, -1, -1, -1, -1, -1};
  int mag_[3] = {-1, -1, -1};
  bool has_mag_ = false;
  DotRow pending_;
  bool has_pending_ = false;
  double previous_t_s_ = 0.0;
  double previous_interval_s_ = 0.0;
  std::size_t emitted_ = 0;
  std::size_t retimed_ = 0;
  std::uint64_t last_tick_ = 0;
  bool has_last_tick_ = false;
  std::uint64_t wraps_ = 0;
  std::uint64_t last_step_ = 0;  ///< last nonzero SampleTimeFine step, 0 before the first
  IncreasingTime time_;
};

class DotImuReader final : public ImuReader {
 public:
  DotImuReader(const std::string& path, bool raw) : rows_(path, raw) {}

  bool Next(ImuSample* sample) override {
    DotRow r;
    while (rows_.Next(&r)) {
      if (!r.bad_field.empty()) {  // only a lost-sample row gets here with NaN/Infinity
        ++lost_dropped_;
        continue;
      }
      if (rows_.raw() && used_ == 0 && r.acc_mps2.isZero(0.0) && r.gyro_dps.isZero(0.0)) {
        ++zero_skipped_;
        continue;
      }
      ++used_;
      RateSample rate;
      rate.t_s = r.t_s;
      rate.gyro_radps = r.gyro_dps * kDegToRad;
      rate.acc_mps2 = r.acc_mps2;
      CheckRates(rate, r.line);
      if (to_increment_.Add(rate, sample)) return true;
    }
    if (used_ == 0) throw InputError(path(), 0, "", "no samples (only a header)");
    if (used_ == 1) {
      throw InputError(path(), 0, "", "a single rate sample gives no increment (need two)");
    }
    return false;
  }
  const std::string& path() const override { return rows_.path(); }

  /// Rates within the full scales of core/io/plausibility.h.
  void CheckRates(const RateSample& rate, long line) const {
    const char* acc[3] = {"Acc_X", "Acc_Y", "Acc_Z"};
    const char* gyro[3] = {"Gyr_X", "Gyr_Y", "Gyr_Z"};
    for (int k = 0; k < 3; ++k) {
      plausible::SpecificForce(rate.acc_mps2[k], path(), line, acc[k]);
      plausible::AngularRate(rate.gyro_radps[k], path(), line, gyro[k]);
    }
  }

  std::size_t zero_skipped() const { return zero_skipped_; }
  std::size_t lost_dropped() const { return lost_dropped_; }
  std::size_t retimed() const { return rows_.retimed(); }
  std::size_t clock_wraps() const { return rows_.clock_wraps(); }

 private:
  DotRows rows_;
  RateToIncrement to_increment_;
  std::size_t used_ = 0;
  std::size_t zero_skipped_ = 0;
  std::size_t lost_dropped_ = 0;
};

class DotMagReader final : public MagReader {
 public:
  explicit DotMagReader(const std::string& path) : rows_(path, true) {
    if (!rows_.has_mag()) {
      throw InputError(path, 1, "Mag_X",
                       "missing column 'Mag_X' (this DOT file has no magnetometer)");
    }
  }
  bool Next(MagSample* sample) override {
    DotRow r;
    if (!rows_.Next(&r)) return false;
    sample->t_s = r.t_s;
    sample->m_b_uT = r.mag_au * kXsensDotMagUtPerUnit;
    const char* names[3] = {"Mag_X", "Mag_Y", "Mag_Z"};
    for (int k = 0; k < 3; ++k) plausible::MagneticField(sample->m_b_uT[k], path(), r.line, names[k]);
    return true;
  }
  const std::string& path() const override { return rows_.path(); }

 private:
  DotRows rows_;
};

NavState MakeNav(double t_s, const wgs84::Geodetic& p, const Eigen::Vector3d& v_n,
                 const Eigen::Vector3d& rpy_deg) {
  NavState s;
  s.t_s = t_s;
  s.lat_rad = p.lat_rad;
  s.lon_rad = p.lon_rad;
  s.h_m = p.h_m;
  s.v_n_mps = v_n;
  s.q_n_b =
      QuatFromEuler(rpy_deg.x() * kDegToRad, rpy_deg.y() * kDegToRad, rpy_deg.z() * kDegToRad);
  return s;
}

/// GTExtended.csv rows.
struct GtExtRow {
  long line = 0;
  double t_s = 0.0;  ///< time [ms] / 1000
  wgs84::Geodetic position;
  Eigen::Vector3d v_n_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy_deg = Eigen::Vector3d::Zero();
};

class GtExtRows {
 public:
  explicit GtExtRows(const std::string& path) : csv_(path) {
    const HeaderColumns& h = csv_.header();
    time_ = h.Require("time");
    lat_ = h.Require("latitude");
    lon_ = h.Require("longitude");
    alt_ = h.Require("altitude_above_seaLevel");
    speed_[0] = h.Require("xSpeed");
    speed_[1] = h.Require("ySpeed");
    speed_[2] = h.Require("zSpeed");
    rpy_[0] = h.Require("roll");
    rpy_[1] = h.Require("pitch");
    rpy_[2] = h.Require("compass_heading");
  }
  bool Next(GtExtRow* r) {
    if (!csv_.Next()) return false;
    r->line = csv_.line();
    r->t_s = csv_.Get(time_) * kMillisecond_s;
    time_check_.Check(r->t_s, path(), r->line, "time");
    const double lat_deg = csv_.Get(lat_);
    if (std::fabs(lat_deg) > 90.0) {
      throw InputError(path(), r->line, "latitude", "latitude beyond +-90 deg");
    }
    r->position.lat_rad = lat_deg * kDegToRad;
    r->position.lon_rad = csv_.Get(lon_) * kDegToRad;
    plausible::Longitude(r->position.lon_rad, path(), r->line, "longitude");
    r->position.h_m = csv_.Get(alt_);
    plausible::Height(r->position.h_m, path(), r->line, "altitude_above_seaLevel");
    r->v_n_mps = csv_.Get3(speed_[0], speed_[1], speed_[2]);
    const char* speeds[3] = {"xSpeed", "ySpeed", "zSpeed"};
    for (int k = 0; k < 3; ++k) plausible::Velocity(r->v_n_mps[k], path(), r->line, speeds[k]);
    r->rpy_deg = csv_.Get3(rpy_[0], rpy_[1], rpy_[2]);
    return true;
  }
  const std::string& path() const { return csv_.path(); }

 private:
  CsvRows csv_;
  int time_ = -1, lat_ = -1, lon_ = -1, alt_ = -1;
  int speed_[3] = {-1, -1, -1};
  int rpy_[3] = {-1, -1, -1};
  IncreasingTime time_check_;
};

class GtExtendedReader final : public NavReader {
 public:
  explicit GtExtendedReader(const std::string& path) : rows_(path) {}
  bool Next(NavState* s) override {
    GtExtRow r;
    if (!rows_.Next(&r)) {
      if (count_ == 0) throw InputError(path(), 0, "", "no samples (only a header)");
      return false;
    }
    ++count_;
    *s = MakeNav(r.t_s, r.position, r.v_n_mps, r.rpy_deg);
    return true;
  }
  const std::string& path() const override { return rows_.path(); }

 private:
  GtExtRows rows_;
  std::size_t count_ = 0;
};

/// GT.csv rows (with the GTExtended.csv row paired to them when that file is used).
struct GtRow {
  long line = 0;
  double t_s = 0.0;
  Eigen::Vector3d ned_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_n_mps = Eigen::Vector3d::Zero();  ///< from GTExtended.csv when paired
};

class GtReader final : public NavReader {
 public:
  GtReader(const std::string& path, const AnsflGtOptions& options) : csv_(path) {
    const HeaderColumns& h = csv_.header();
    time_ = h.Require("time");
    ned_[0] = h.Require("North");
    ned_[1] = h.Require("East");
    ned_[2] = h.Require("Down");
    rpy_[0] = h.Require("roll");
    rpy_[1] = h.Require("pitch");
    rpy_[2] = h.Require("compass_heading");
    const std::string ext_path = Folder(path) + "/GTExtended.csv";
    if (FileExists(ext_path)) {
      ext_ = std::make_unique<GtExtRows>(ext_path);
      if (!ext_->Next(&ext_first_)) throw InputError(ext_path, 0, "", "no samples (only a header)");
      has_ext_first_ = true;
    }
    if (options.origin) {
      origin_ = *options.origin;
    } else if (ext_) {
      origin_ = ext_first_.position;
    } else {
      origin_ = AnsflSiteOrigin();
    }
  }

  bool Next(NavState* s) override {
    if (!started_) Start();
    if (!has_cur_) return false;
    Eigen::Vector3d v = cur_.v_n_mps;
    if (!ext_) v = DifferencedVelocity();
    *s = MakeNav(cur_.t_s, wgs84::NedToGeodetic(cur_.ned_m, origin_), v, cur_.rpy_deg);
    prev_ = cur_;
    has_prev_ = true;
    has_cur_ = has_next_;
    if (has_cur_) {
      cur_ = next_;
      has_next_ = Read(&next_);
    }
    return true;
  }
  const std::string& path() const override { return csv_.path(); }

 private:
  void Start() {
    started_ = true;
    has_cur_ = Read(&cur_);
    if (!has_cur_) throw InputError(path(), 0, "", "no samples (only a header)");
    has_next_ = Read(&next_);
    if (!has_next_ && !ext_) {
      throw InputError(path(), cur_.line, "", "a single row: velocity needs two");
    }
  }

  bool Read(GtRow* r) {
    if (!csv_.Next()) return false;
    r->line = csv_.line();
    r->t_s = csv_.Get(time_);
    time_check_.Check(r->t_s, path(), r->line, "time");
    r->ned_m = csv_.Get3(ned_[0], ned_[1], ned_[2]);
    r->rpy_deg = csv_.Get3(rpy_[0], rpy_[1], rpy_[2]);
    if (ext_) PairExtended(r);
    return true;
  }

  /// Takes the next GTExtended.csv row for GT row r and checks that their times agree.
  void PairExtended(GtRow* r) {
    GtExtRow e;
    if (has_ext_first_) {
      e = ext_first_;
      has_ext_first_ = false;
    } else if (!ext_->Next(&e)) {
      throw InputError(ext_->path(), 0, "",
                       "ends before GT.csv (its line " + std::to_string(r->line) + ")");
    }
    const double ext_t_s = e.t_s - ext_first_.t_s;
    if (std::fabs(ext_t_s - r->t_s) > kGtPairTolerance_s) {
      throw InputError(ext_->path(), e.line, "time",
                       "does not match GT.csv line " + std::to_string(r->line) +
                           " (rows of the two files must pair up)");
    }
    r->v_n_mps = e.v_n_mps;
  }

  /// Central difference of the N/E/D positions, one-sided at the ends.
  Eigen::Vector3d DifferencedVelocity() const {
    const GtRow& a = has_prev_ ? prev_ : cur_;
    const GtRow& b = has_next_ ? next_ : cur_;
    return (b.ned_m - a.ned_m) / (b.t_s - a.t_s);
  }

  CsvRows csv_;
  int time_ = -1;
  int ned_[3] = {-1, -1, -1};
  int rpy_[3] = {-1, -1, -1};
  std::unique_ptr<GtExtRows> ext_;
  GtExtRow ext_first_;
  bool has_ext_first_ = false;
  wgs84::Geodetic origin_;
  GtRow prev_, cur_, next_;
  bool started_ = false, has_prev_ = false, has_cur_ = false, has_next_ = false;
  IncreasingTime time_check_;
};

std::vector<std::string> ImuFields(bool raw) {
  return {raw ? "SampleTimeFine [us, device clock]" : "time [s]", "Acc_X Acc_Y Acc_Z [m/s^2]",
          "Gyr_X Gyr_Y Gyr_Z [deg/s]"};
}

void AddImuNotes(const DotImuReader& r, FileSummary* summary) {
  summary->notes.push_back(
      "axes: the DOT sensor's own (z up at rest), not rotated; increments by the trapezoid rule "
      "(the first row only starts the series)");
  if (r.retimed() > 0) {
    summary->notes.push_back(std::to_string(r.retimed()) +
                             " rows re-timed to the middle of a double interval (DOT lost-sample "
                             "pattern: the next row repeats their time)");
  }
  if (r.lost_dropped() > 0) {
    summary->notes.push_back(std::to_string(r.lost_dropped()) +
                             " lost-sample rows with NaN/Infinity Acc/Gyr dropped");
  }
  if (r.zero_skipped() > 0) {
    summary->notes.push_back(std::to_string(r.zero_skipped()) +
                             " leading rows with all-zero Acc/Gyr skipped");
  }
}

}  // namespace

wgs84::Geodetic AnsflSiteOrigin() {
  wgs84::Geodetic g;
  g.lat_rad = 32.8256829718786 * kDegToRad;
  g.lon_rad = 34.9559595644856 * kDegToRad;
  g.h_m = 10.1942341;
  return g;
}

std::unique_ptr<ImuReader> OpenAnsflImu(const std::string& path) {
  return std::make_unique<DotImuReader>(path, false);
}

std::unique_ptr<ImuReader> OpenAnsflDotRawImu(const std::string& path) {
  return std::make_unique<DotImuReader>(path, true);
}

std::unique_ptr<MagReader> OpenAnsflDotRawMag(const std::string& path) {
  return std::make_unique<DotMagReader>(path);
}

std::unique_ptr<NavReader> OpenAnsflGt(const std::string& path, const AnsflGtOptions& options) {
  return std::make_unique<GtReader>(path, options);
}

std::unique_ptr<NavReader> OpenAnsflGtExtended(const std::string& path) {
  return std::make_unique<GtExtendedReader>(path);
}

FileSummary DescribeAnsflImu(const std::string& path) {
  DotImuReader reader(path, false);
  FileSummary summary;
  summary.path = path;
  summary.kind = "ansfl-imu";
  summary.streams.push_back(SummarizeStream<ImuSample>(&reader, "imu", ImuFields(false)));
  AddImuNotes(reader, &summary);
  return summary;
}

FileSummary DescribeAnsflDotRaw(const std::string& path) {
  DotImuReader reader(path, true);
  FileSummary summary;
  summary.path = path;
  summary.kind = "ansfl-dot-raw";
  summary.streams.push_back(SummarizeStream<ImuSample>(&reader, "imu", ImuFields(true)));
  AddImuNotes(reader, &summary);
  summary.notes.push_back("t = SampleTimeFine unwrapped, seconds since the DOT's power-on (" +
                          std::to_string(reader.clock_wraps()) + " wraps)");
  DotRows probe(path, true);
  if (probe.has_mag()) {
    DotMagReader mag(path);
    summary.streams.push_back(SummarizeStream<MagSample>(
        &mag, "mag", {"Mag_X Mag_Y Mag_Z [a.u., x 40 uT in MagSample]"}));
  }
  return summary;
}

}  // namespace navtwin
