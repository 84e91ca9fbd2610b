#include "core/io/csv_mag_baro.h"

#include <cmath>
#include <initializer_list>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/io/input_error.h"
#include "core/io/plausibility.h"
#include "core/io/text_reader.h"
#include "core/units.h"

namespace navtwin {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The rows of a headed CSV file: header found, field count and time checked per row.
class CsvTable {
 public:
  explicit CsvTable(const std::string& path) : lines_(path) {
    while (lines_.Next(&line_)) {
      if (IsBlank(line_) || Trim(line_).front() == '#') continue;
      SplitCsv(line_, &fields_);
      header_ = HeaderColumns(fields_, path, lines_.line_number());
      header_line_ = lines_.line_number();
      time_ = header_.RequireWithUnit("t", {{"_s", 1.0}, {"_ms", 1e-3}});
      return;
    }
    throw InputError(path, 0, "", "no samples (the file is empty)");
  }

  /// The next non-blank row; false at the end (InputError when there was no row at all).
  bool NextRow() {
    while (lines_.Next(&line_)) {
      if (IsBlank(line_)) continue;
      SplitCsv(line_, &fields_);
      RequireFieldCount(fields_.size(), header_.size(), path(), line());
      time_s_ = Value(time_);
      plausible::Time(time_s_, path(), line(), time_.name);
      monotonic_.Check(time_s_, path(), line(), time_.name);
      ++rows_;
      return true;
    }
    if (rows_ == 0) throw InputError(path(), 0, "", "no samples (only a header)");
    return false;
  }

  /// The number in column c times its unit factor.
  double Value(const UnitColumn& c) const {
    return ParseScaled(Field(c), c.scale, path(), line(), c.name);
  }
  /// Like Value, but NaN for an absent column or an empty field.
  double OptionalValue(const UnitColumn& c) const {
    if (c.index < 0 || Field(c).empty()) return kNaN;
    return Value(c);
  }

  const HeaderColumns& header() const { return header_; }
  long header_line() const { return header_line_; }
  double time_s() const { return time_s_; }
  long line() const { return lines_.line_number(); }
  const std::string& path() const { return lines_.path(); }

 private:
  std::string_view Field(const UnitColumn& c) const {
    return fields_[static_cast<std::size_t>(c.index)];
  }

  LineReader lines_;
  HeaderColumns header_;
  long header_line_ = 0;
  UnitColumn time_;
  std::string line_;
  std::vector<std::string_view> fields_;
  double time_s_ = 0.0;
  std::size_t rows_ = 0;
  IncreasingTime monotonic_;
};

class CsvMagReader final : public MagReader {
 public:
  explicit CsvMagReader(const std::string& path) : table_(path) {
    const char* axes[3] = {"mx", "my", "mz"};
    for (int k = 0; k < 3; ++k) {
      axes_[k] = table_.header().RequireWithUnit(
          axes[k], {{"_uT", 1.0}, {"_G", kGauss_uT}, {"_ga", kGauss_uT}, {"_nT", kNanotesla_uT}});
    }
  }

  bool Next(MagSample* sample) override {
    if (!table_.NextRow()) return false;
    sample->t_s = table_.time_s();
    for (int k = 0; k < 3; ++k) {
      sample->m_b_uT[k] = table_.Value(axes_[k]);
      plausible::MagneticField(sample->m_b_uT[k], path(), table_.line(), axes_[k].name);
    }
    return true;
  }
  const std::string& path() const override { return table_.path(); }

 private:
  CsvTable table_;
  UnitColumn axes_[3];
};

class CsvBaroReader final : public BaroReader {
 public:
  explicit CsvBaroReader(const std::string& path) : table_(path) {
    pressure_ = table_.header().FindWithUnit("pressure", {{"_pa", 1.0}});
    altitude_ = table_.header().FindWithUnit("altitude", {{"_m", 1.0}});
    temperature_ = table_.header().FindWithUnit("temperature", {{"_degC", 1.0}});
    if (pressure_.index < 0 && altitude_.index < 0) {
      throw InputError(path, table_.header_line(), "pressure_pa",
                       "missing column 'pressure_pa' or 'altitude_m'");
    }
  }

  bool Next(BaroSample* sample) override {
    if (!table_.NextRow()) return false;
    sample->t_s = table_.time_s();
    sample->pressure_pa = table_.OptionalValue(pressure_);
    sample->altitude_m = table_.OptionalValue(altitude_);
    sample->temperature_degC = table_.OptionalValue(temperature_);
    if (!std::isnan(sample->pressure_pa)) {
      RequirePositive(sample->pressure_pa, path(), table_.line(), pressure_.name);
      plausible::Pressure(sample->pressure_pa, path(), table_.line(), pressure_.name);
    }
    if (!std::isnan(sample->altitude_m)) plausible::Height(sample->altitude_m, path(), table_.line(), altitude_.name);
    if (sample->temperature_degC <= kAbsoluteZero_degC) {
      throw InputError(path(), table_.line(), temperature_.name, "below absolute zero");
    }
    if (std::isnan(sample->pressure_pa) && std::isnan(sample->altitude_m)) {
      throw InputError(path(), table_.line(),
                       pressure_.index >= 0 ? pressure_.name : altitude_.name,
                       "no value: a row needs pressure_pa or altitude_m");
    }
    return true;
  }
  const std::string& path() const override { return table_.path(); }

 private:
  CsvTable table_;
  UnitColumn pressure_, altitude_, temperature_;
};

/// A value, or nothing for NaN (an absent barometer quantity).
void WriteOptional(std::ostream& os, double value) {
  os << ',';
  if (!std::isnan(value)) os << value;
}

}  // namespace

std::unique_ptr<MagReader> OpenCsvMag(const std::string& path) {
  return std::make_unique<CsvMagReader>(path);
}

std::unique_ptr<BaroReader> OpenCsvBaro(const std::string& path) {
  return std::make_unique<CsvBaroReader>(path);
}

CsvMagWriter::CsvMagWriter(const std::string& path, const std::string& note) : file_(path) {
  if (!note.empty()) file_.stream() << "# " << note << "\n";
  file_.stream() << "t_s,mx_uT,my_uT,mz_uT\n";
}

void CsvMagWriter::Write(const MagSample& s) {
  if (!std::isfinite(s.t_s) || !s.m_b_uT.allFinite()) {
    throw std::invalid_argument("CsvMagWriter: non-finite magnetometer sample");
  }
  file_.stream() << s.t_s << ',' << s.m_b_uT.x() << ',' << s.m_b_uT.y() << ',' << s.m_b_uT.z()
                 << '\n';
}

void CsvMagWriter::Commit() { file_.Commit(); }

CsvBaroWriter::CsvBaroWriter(const std::string& path, const std::string& note) : file_(path) {
  if (!note.empty()) file_.stream() << "# " << note << "\n";
  file_.stream() << "t_s,pressure_pa,altitude_m,temperature_degC\n";
}

void CsvBaroWriter::Write(const BaroSample& s) {
  const double values[3] = {s.pressure_pa, s.altitude_m, s.temperature_degC};
  bool infinite = !std::isfinite(s.t_s);
  for (const double v : values) infinite = infinite || std::isinf(v);
  if (infinite || (std::isnan(s.pressure_pa) && std::isnan(s.altitude_m))) {
    throw std::invalid_argument(
        "CsvBaroWriter: non-finite time or value, or neither pressure nor altitude");
  }
  std::ostream& os = file_.stream();
  os << s.t_s;
  for (const double v : values) WriteOptional(os, v);
  os << '\n';
}

void CsvBaroWriter::Commit() { file_.Commit(); }

}  // namespace navtwin
