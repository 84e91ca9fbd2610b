#include "core/io/kfgins.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/io/input_error.h"
#include "core/io/plausibility.h"
#include "core/io/rate_to_increment.h"
#include "core/io/text_line.h"
#include "core/io/text_reader.h"
#include "core/rotation.h"
#include "core/units.h"

namespace navtwin {
namespace {


/// Numeric rows of a KF-GINS file: blank and '#' lines skipped, fields split, the column
/// count checked against the first row (which must be one of the allowed counts).
class Rows {
 public:
  Rows(const std::string& path, std::vector<std::size_t> allowed)
      : lines_(path), allowed_(std::move(allowed)) {}

  bool Next() {
    while (lines_.Next(&line_)) {
      if (IsBlank(line_) || Trim(line_).front() == '#') continue;
      SplitLoose(line_, &fields_);
      CheckCount();
      return true;
    }
    return false;
  }
  double Get(std::size_t i, const char* field) const {
    return ParseDouble(fields_[i], path(), line(), field);
  }
  std::string_view Text(std::size_t i) const { return fields_[i]; }
  std::size_t size() const { return fields_.size(); }
  long line() const { return lines_.line_number(); }
  const std::string& path() const { return lines_.path(); }
  /// Throws the "empty file" error; readers call it when the first Next() fails.
  [[noreturn]] void ThrowEmpty() const {
    throw InputError(path(), 0, "", "no samples (the file is empty)");
  }

 private:
  void CheckCount() {
    if (count_ == 0) {
      for (std::size_t n : allowed_) {
        if (fields_.size() == n) count_ = n;
      }
      if (count_ == 0) {
        std::string expected;
        for (std::size_t n : allowed_)
          expected += (expected.empty() ? "" : " or ") + std::to_string(n);
        throw InputError(
            path(), line(), "",
            "expected " + expected + " columns, found " + std::to_string(fields_.size()));
      }
      return;
    }
    RequireFieldCount(fields_.size(), count_, path(), line());
  }

  LineReader lines_;
  std::vector<std::size_t> allowed_;
  std::size_t count_ = 0;
  std::string line_;
  std::vector<std::string_view> fields_;
};

double LatitudeRad(const Rows& rows, std::size_t i) {
  const double lat_deg = rows.Get(i, "lat");
  if (std::fabs(lat_deg) > 90.0) {
    throw InputError(rows.path(), rows.line(), "lat", "latitude beyond +-90 deg");
  }
  return lat_deg * kDegToRad;
}

Eigen::Vector3d Triple(const Rows& rows, std::size_t first, const char* x, const char* y,
                       const char* z) {
  return Eigen::Vector3d(rows.Get(first, x), rows.Get(first + 1, y), rows.Get(first + 2, z));
}

Eigen::Vector3d Sigmas(const Rows& rows, std::size_t first, const char* x, const char* y,
                       const char* z) {
  const Eigen::Vector3d s = Triple(rows, first, x, y, z);
  const char* names[3] = {x, y, z};
  for (int k = 0; k < 3; ++k) {
    RequirePositive(s[k], rows.path(), rows.line(), names[k]);
    plausible::Sigma(s[k], rows.path(), rows.line(), names[k]);
  }
  return s;
}

Eigen::Vector3d Velocities(const Rows& rows, std::size_t first, const char* x, const char* y, const char* z) {
  const Eigen::Vector3d v = Triple(rows, first, x, y, z);
  const char* names[3] = {x, y, z};
  for (int k = 0; k < 3; ++k) plausible::Velocity(v[k], rows.path(), rows.line(), names[k]);
  return v;
}

/// Time, longitude and height of a GNSS or navigation row (latitude: LatitudeRad).
double PlausibleTime(const Rows& rows, std::size_t i, const char* field) {
  const double t = rows.Get(i, field);
  plausible::Time(t, rows.path(), rows.line(), field);
  return t;
}
double LongitudeRad(const Rows& rows, std::size_t i) {
  const double lon_rad = rows.Get(i, "lon") * kDegToRad;
  plausible::Longitude(lon_rad, rows.path(), rows.line(), "lon");
  return lon_rad;
}
double Height(const Rows& rows, std::size_t i) {
  const double h_m = rows.Get(i, "h");
  plausible::Height(h_m, rows.path(), rows.line(), "h");
  return h_m;
}

/// Increments of an IMU row over dt_s: |dtheta| and |dv| within the full scales of
/// core/io/plausibility.h times the interval.
void CheckIncrements(const Rows& rows, const ImuSample& row, double dt_s) {
  const char* angle[3] = {"dtheta_x", "dtheta_y", "dtheta_z"};
  const char* velocity[3] = {"dv_x", "dv_y", "dv_z"};
  for (int k = 0; k < 3; ++k) {
    plausible::AngleIncrement(row.dtheta_b_rad[k], dt_s, rows.path(), rows.line(), angle[k]);
    plausible::VelocityIncrement(row.dv_b_mps[k], dt_s, rows.path(), rows.line(), velocity[k]);
  }
}

class KfginsImuReader final : public ImuReader {
 public:
  explicit KfginsImuReader(const std::string& path) : rows_(path, {7, 8}) {}

  bool Next(ImuSample* sample) override {
    while (rows_.Next()) {
      ImuSample row;
      row.t_s = PlausibleTime(rows_, 0, "t");
      const double dt_s =
          time_.has_previous() ? row.t_s - time_.previous_s() : plausible::kFirstIncrementInterval_s;
      time_.Check(row.t_s, path(), rows_.line(), "t");
      row.dtheta_b_rad = Triple(rows_, 1, "dtheta_x", "dtheta_y", "dtheta_z");
      row.dv_b_mps = Triple(rows_, 4, "dv_x", "dv_y", "dv_z");
      CheckIncrements(rows_, row, dt_s);
      if (intervals_.Add(row, sample)) return true;
    }
    if (intervals_.rows() == 0) rows_.ThrowEmpty();
    if (intervals_.rows() == 1) {
      throw InputError(path(), rows_.line(), "t",
                       "a single IMU sample: its interval is taken from the second sample's, "
                       "so at least two lines are needed");
    }
    return intervals_.Flush(sample);
  }
  const std::string& path() const override { return rows_.path(); }

 private:
  Rows rows_;
  IncreasingTime time_;
  IncrementIntervals intervals_;
};

class KfginsGnssReader final : public GnssReader {
 public:
  explicit KfginsGnssReader(const std::string& path) : rows_(path, {7, 13}) {
    if (!rows_.Next()) rows_.ThrowEmpty();
    have_row_ = true;
  }

  bool Next(GnssSample* s) override {
    if (!have_row_ && !rows_.Next()) return false;
    have_row_ = false;
    *s = GnssSample();
    s->t_s = PlausibleTime(rows_, 0, "t");
    time_.Check(s->t_s, path(), rows_.line(), "t");
    s->lat_rad = LatitudeRad(rows_, 1);
    s->lon_rad = LongitudeRad(rows_, 2);
    s->h_m = Height(rows_, 3);
    s->pos_std_ned_m = Sigmas(rows_, 4, "sigma_n", "sigma_e", "sigma_d");
    if (rows_.size() == 13) {
      s->has_velocity = true;
      s->v_n_mps = Velocities(rows_, 7, "v_n", "v_e", "v_d");
      s->vel_std_ned_mps = Sigmas(rows_, 10, "sigma_vn", "sigma_ve", "sigma_vd");
    }
    return true;
  }
  const std::string& path() const override { return rows_.path(); }

 private:
  Rows rows_;
  IncreasingTime time_;
  bool have_row_ = false;
};

class KfginsNavReader final : public NavReader {
 public:
  explicit KfginsNavReader(const std::string& path) : rows_(path, {11}) {
    if (!rows_.Next()) rows_.ThrowEmpty();
    have_row_ = true;
  }

  bool Next(NavState* s) override {
    if (!have_row_ && !rows_.Next()) return false;
    have_row_ = false;
    *s = NavState();
    s->gps_week = ParseWholeNumber(rows_.Text(0), path(), rows_.line(), "week");
    if (s->gps_week < 0) throw InputError(path(), rows_.line(), "week", "negative GPS week");
    s->t_s = PlausibleTime(rows_, 1, "sow");
    time_.Check(s->gps_week * kSecondsPerWeek + s->t_s, path(), rows_.line(), "sow");
    s->lat_rad = LatitudeRad(rows_, 2);
    s->lon_rad = LongitudeRad(rows_, 3);
    s->h_m = Height(rows_, 4);
    s->v_n_mps = Velocities(rows_, 5, "v_n", "v_e", "v_d");
    const Eigen::Vector3d euler_deg = Triple(rows_, 8, "roll", "pitch", "yaw");
    s->q_n_b = QuatFromEuler(euler_deg.x() * kDegToRad, euler_deg.y() * kDegToRad,
                             euler_deg.z() * kDegToRad);
    return true;
  }
  const std::string& path() const override { return rows_.path(); }

 private:
  Rows rows_;
  IncreasingTime time_;
  bool have_row_ = false;
};

void RequireFinite(double v, const char* what) {
  if (!std::isfinite(v)) throw std::invalid_argument(std::string("non-finite ") + what);
}

void RequireFinite(const Eigen::Vector3d& v, const char* what) {
  if (!v.allFinite()) throw std::invalid_argument(std::string("non-finite ") + what);
}

void RequireSigma(const Eigen::Vector3d& s, const char* what) {
  RequireFinite(s, what);
  if (!(s.minCoeff() > 0.0)) throw std::invalid_argument(std::string(what) + " must be > 0");
}

/// A navigation state that cannot be on or near the Earth (core/io/plausibility.h): |lat| >
/// 90 deg, a height outside [kMinHeight_m, kMaxHeight_m], a speed above kMaxSpeed_mps.
void RequirePossible(const NavState& s) {
  const auto refuse = [&](const std::string& what) {
    std::ostringstream os;
    os.precision(10);
    os << "impossible navigation state at t = " << s.t_s << " s: " << what;
    throw std::invalid_argument(os.str());
  };
  if (std::abs(s.lat_rad) > 0.5 * kPi) refuse("latitude " + std::to_string(s.lat_rad * kRadToDeg) + " deg beyond +-90 deg");
  if (s.h_m < plausible::kMinHeight_m || s.h_m > plausible::kMaxHeight_m) {
    refuse("height " + std::to_string(s.h_m) + " m outside [-12 km, 1e7 m]");
  }
  if (s.v_n_mps.cwiseAbs().maxCoeff() > plausible::kMaxSpeed_mps) {
    refuse("velocity component above " + std::to_string(plausible::kMaxSpeed_mps) + " m/s");
  }
}

void AddTriple(TextLine& line, const Eigen::Vector3d& v) {
  line.Char(' ').Number(v.x()).Char(' ').Number(v.y()).Char(' ').Number(v.z());
}

}  // namespace

std::vector<OdometerSample> ReadKfginsImuOdometer(const std::string& path) {
  Rows rows(path, {7, 8});
  IncreasingTime time;
  std::vector<OdometerSample> out;
  while (rows.Next()) {
    if (rows.size() != 8) {
      throw InputError(path, rows.line(), "odo", "an IMU file with 7 columns has no odometer column (OB_GINS: 8)");
    }
    OdometerSample s;
    s.t_s = PlausibleTime(rows, 0, "t");
    time.Check(s.t_s, path, rows.line(), "t");
    s.speed_mps = rows.Get(7, "odo");
    plausible::Velocity(s.speed_mps, path, rows.line(), "odo");
    out.push_back(s);
  }
  if (out.empty()) rows.ThrowEmpty();
  return out;
}

std::unique_ptr<ImuReader> OpenKfginsImu(const std::string& path) {
  return std::make_unique<KfginsImuReader>(path);
}
std::unique_ptr<GnssReader> OpenKfginsGnss(const std::string& path) {
  return std::make_unique<KfginsGnssReader>(path);
}
std::unique_ptr<NavReader> OpenKfginsNav(const std::string& path) {
  return std::make_unique<KfginsNavReader>(path);
}

KfginsImuWriter::KfginsImuWriter(const std::string& path) : file_(path) {}

void KfginsImuWriter::Write(const ImuSample& s) {
  RequireFinite(s.t_s, "IMU time");
  RequireFinite(s.dtheta_b_rad, "dtheta");
  RequireFinite(s.dv_b_mps, "dv");
  TextLine line;
  line.Number(s.t_s);
  AddTriple(line, s.dtheta_b_rad);
  AddTriple(line, s.dv_b_mps);
  line.Char('\n').WriteTo(file_.stream());
}

void KfginsImuWriter::Commit() { file_.Commit(); }

KfginsGnssWriter::KfginsGnssWriter(const std::string& path) : file_(path) {}

void KfginsGnssWriter::Write(const GnssSample& s) {
  const int columns = s.has_velocity ? 13 : 7;
  if (columns_ == 0) columns_ = columns;
  if (columns != columns_) {
    throw std::invalid_argument("KF-GINS GNSS file: samples with and without velocity mixed");
  }
  RequireFinite(s.t_s, "GNSS time");
  RequireFinite(Eigen::Vector3d(s.lat_rad, s.lon_rad, s.h_m), "GNSS position");
  RequireSigma(s.pos_std_ned_m, "GNSS position sigma");
  TextLine line;
  line.Number(s.t_s).Char(' ').Number(s.lat_rad * kRadToDeg).Char(' ');
  line.Number(s.lon_rad * kRadToDeg).Char(' ').Number(s.h_m);
  AddTriple(line, s.pos_std_ned_m);
  if (s.has_velocity) {
    RequireFinite(s.v_n_mps, "GNSS velocity");
    RequireSigma(s.vel_std_ned_mps, "GNSS velocity sigma");
    AddTriple(line, s.v_n_mps);
    AddTriple(line, s.vel_std_ned_mps);
  }
  line.Char('\n').WriteTo(file_.stream());
}

void KfginsGnssWriter::Commit() { file_.Commit(); }

KfginsNavWriter::KfginsNavWriter(const std::string& path) : file_(path) {}

void RequireWritableNavState(const NavState& s) {
  RequireFinite(s.t_s, "navigation time");
  RequireFinite(Eigen::Vector3d(s.lat_rad, s.lon_rad, s.h_m), "navigation position");
  RequireFinite(s.v_n_mps, "navigation velocity");
  RequireFinite(s.q_n_b.coeffs().head<3>(), "attitude quaternion");
  RequirePossible(s);
}

void AppendNavFields(const NavState& s, char separator, TextLine* line) {
  RequireWritableNavState(s);
  // Longitude in (-180, 180]: the estimators do not all wrap it (a state past the
  // antimeridian is possible, its longitude written as the format has it).
  const double lon_rad = std::abs(s.lon_rad) > kPi ? WrapPi(s.lon_rad) : s.lon_rad;
  const Eigen::Vector3d euler_deg = EulerFromQuat(s.q_n_b) * kRadToDeg;
  const double fields[10] = {s.t_s,         s.lat_rad * kRadToDeg, lon_rad * kRadToDeg, s.h_m,        s.v_n_mps.x(),
                             s.v_n_mps.y(), s.v_n_mps.z(),         euler_deg.x(),         euler_deg.y(), euler_deg.z()};
  line->Number(fields[0]);
  for (int i = 1; i < 10; ++i) line->Char(separator).Number(fields[i]);
}

void KfginsNavWriter::Write(const NavState& s) {
  TextLine line;
  line.Integer(s.gps_week < 0 ? 0 : s.gps_week).Char(' ');
  AppendNavFields(s, ' ', &line);
  line.Char('\n').WriteTo(file_.stream());
}

void KfginsNavWriter::WriteFields(int gps_week, std::string_view comma_separated_fields) {
  TextLine line;
  line.Integer(gps_week < 0 ? 0 : gps_week).Char(' ');
  for (const char c : comma_separated_fields) line.Char(c == ',' ? ' ' : c);
  line.Char('\n').WriteTo(file_.stream());
}

void KfginsNavWriter::Commit() { file_.Commit(); }

}  // namespace navtwin
