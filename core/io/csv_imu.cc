#include "core/io/csv_imu.h"

#include <cmath>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/io/input_error.h"
#include "core/io/plausibility.h"
#include "core/io/rate_to_increment.h"
#include "core/io/text_reader.h"
#include "core/rotation.h"

namespace navtwin {
namespace {

class CsvImuReader final : public ImuReader {
 public:
  explicit CsvImuReader(const std::string& path) : lines_(path) { ReadHeader(); }

  bool Next(ImuSample* sample) override {
    while (ReadRow()) {
      if (rates_) {
        RateSample r;
        r.t_s = time_s_;
        r.gyro_radps = Triple(0);
        r.acc_mps2 = Triple(3);
        CheckRates(r);
        if (to_increment_.Add(r, sample)) return true;
      } else {
        ImuSample row;
        row.t_s = time_s_;
        row.dtheta_b_rad = Triple(0);
        row.dv_b_mps = Triple(3);
        CheckIncrements(row);
        if (intervals_.Add(row, sample)) return true;
      }
    }
    if (rows_ == 0) throw InputError(path(), 0, "", "no samples (only a header)");
    if (rows_ == 1) {
      throw InputError(path(), lines_.line_number(), "",
                       "a single sample: at least two rows are needed to know an interval");
    }
    return rates_ ? false : intervals_.Flush(sample);
  }
  const std::string& path() const override { return lines_.path(); }

 private:
  void ReadHeader() {
    while (lines_.Next(&line_)) {
      if (IsBlank(line_) || Trim(line_).front() == '#') continue;
      SplitCsv(line_, &fields_);
      header_ = HeaderColumns(fields_, path(), lines_.line_number());
      LocateColumns();
      return;
    }
    throw InputError(path(), 0, "", "no samples (the file is empty)");
  }

  void LocateColumns() {
    time_ = header_.RequireWithUnit("t", {{"_s", 1.0}, {"_ms", 1e-3}});
    rates_ = header_.Find("dtheta_x_rad") < 0 &&
             (header_.Find("gyro_x_rad_s") >= 0 || header_.Find("gyro_x_dps") >= 0);
    const char* axes[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      const std::string a = axes[k];
      if (rates_) {
        columns_[k] =
            header_.RequireWithUnit("gyro_" + a, {{"_rad_s", 1.0}, {"_dps", kDegToRad}});
        columns_[3 + k] =
            header_.RequireWithUnit("acc_" + a, {{"_mps2", 1.0}, {"_g", kStandardGravity_mps2}});
      } else {
        columns_[k] = header_.RequireWithUnit("dtheta_" + a, {{"_rad", 1.0}});
        columns_[3 + k] = header_.RequireWithUnit("dv_" + a, {{"_mps", 1.0}});
      }
    }
  }

  bool ReadRow() {
    while (lines_.Next(&line_)) {
      if (IsBlank(line_)) continue;
      SplitCsv(line_, &fields_);
      RequireFieldCount(fields_.size(), header_.size(), path(), lines_.line_number());
      time_s_ = Value(time_);
      plausible::Time(time_s_, path(), lines_.line_number(), time_.name);
      dt_s_ = monotonic_.has_previous() ? time_s_ - monotonic_.previous_s() : plausible::kFirstIncrementInterval_s;
      monotonic_.Check(time_s_, path(), lines_.line_number(), time_.name);
      ++rows_;
      return true;
    }
    return false;
  }

  double Value(const UnitColumn& c) const {
    return ParseScaled(fields_[static_cast<std::size_t>(c.index)], c.scale, path(), lines_.line_number(), c.name);
  }
  /// Rates and increments within the full scales of core/io/plausibility.h.
  void CheckRates(const RateSample& r) const {
    for (int k = 0; k < 3; ++k) {
      plausible::AngularRate(r.gyro_radps[k], path(), lines_.line_number(), columns_[k].name);
      plausible::SpecificForce(r.acc_mps2[k], path(), lines_.line_number(), columns_[3 + k].name);
    }
  }
  void CheckIncrements(const ImuSample& row) const {
    for (int k = 0; k < 3; ++k) {
      plausible::AngleIncrement(row.dtheta_b_rad[k], dt_s_, path(), lines_.line_number(), columns_[k].name);
      plausible::VelocityIncrement(row.dv_b_mps[k], dt_s_, path(), lines_.line_number(), columns_[3 + k].name);
    }
  }

  Eigen::Vector3d Triple(int first) const {
    return Eigen::Vector3d(Value(columns_[first]), Value(columns_[first + 1]),
                           Value(columns_[first + 2]));
  }

  LineReader lines_;
  HeaderColumns header_;
  UnitColumn time_;
  UnitColumn columns_[6];  ///< gyro or dtheta x y z, then acc or dv x y z
  bool rates_ = false;
  std::string line_;
  std::vector<std::string_view> fields_;
  double time_s_ = 0.0;
  double dt_s_ = 0.0;  ///< since the previous row (plausible::kFirstIncrementInterval_s for the first)
  std::size_t rows_ = 0;
  IncreasingTime monotonic_;
  RateToIncrement to_increment_;
  IncrementIntervals intervals_;
};

void RequireFinite(const Eigen::Vector3d& v, const char* what) {
  if (!v.allFinite()) throw std::invalid_argument(std::string("non-finite ") + what);
}

}  // namespace

std::unique_ptr<ImuReader> OpenCsvImu(const std::string& path) {
  return std::make_unique<CsvImuReader>(path);
}

CsvImuWriter::CsvImuWriter(const std::string& path, const std::string& note) : file_(path) {
  if (!note.empty()) file_.stream() << "# " << note << "\n";
  file_.stream() << "t_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps\n";
}

void CsvImuWriter::Write(const ImuSample& s) {
  if (!std::isfinite(s.t_s)) throw std::invalid_argument("non-finite IMU time");
  RequireFinite(s.dtheta_b_rad, "dtheta");
  RequireFinite(s.dv_b_mps, "dv");
  std::ostream& os = file_.stream();
  os << s.t_s;
  for (int k = 0; k < 3; ++k) os << ',' << s.dtheta_b_rad[k];
  for (int k = 0; k < 3; ++k) os << ',' << s.dv_b_mps[k];
  os << '\n';
}

void CsvImuWriter::Commit() { file_.Commit(); }

}  // namespace navtwin
