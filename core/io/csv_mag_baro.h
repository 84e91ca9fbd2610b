// navtwin CSV magnetometer and barometer files: comma separated, a header line naming the
// columns with their units. As for the CSV IMU files, columns are found by name (ASCII
// case-insensitive) in any order, other columns are ignored, lines before the header that
// are blank or start with '#' are skipped, and every row must have the header's number of
// fields.
//
// Magnetometer (written: t_s,mx_uT,my_uT,mz_uT):
//   time:  t_s [s]  or  t_ms [ms]
//   field: mx_uT | mx_G | mx_ga (gauss, 1 G = 100 uT) | mx_nT, and my, mz; sensor axes.
//          A 2-axis sensor writes mz = 0.
// Barometer (written: t_s,pressure_pa,altitude_m,temperature_degC):
//   time:  t_s [s]  or  t_ms [ms]
//   pressure_pa [Pa, > 0], altitude_m [m], temperature_degC [degC, > -273.15]: each
//   optional; at least one of pressure_pa and altitude_m must be a column, and every row
//   needs a value in one of them. A missing column, or an empty field, reads as NaN
//   (absent); the writer leaves NaN values empty.
// Bad input throws InputError naming the file, the line and the field.
#pragma once

#include <memory>
#include <string>

#include "core/io/atomic_file.h"
#include "core/io/sample_reader.h"

namespace navtwin {

std::unique_ptr<MagReader> OpenCsvMag(const std::string& path);
std::unique_ptr<BaroReader> OpenCsvBaro(const std::string& path);

/// Writes t_s,mx_uT,my_uT,mz_uT with 17 significant digits; the file appears on Commit().
class CsvMagWriter {
 public:
  /// A non-empty note is written as a "# note" line before the header (the readers skip
  /// it): e.g. the time scale.
  explicit CsvMagWriter(const std::string& path, const std::string& note = "");
  /// Throws std::invalid_argument on a non-finite value.
  void Write(const MagSample& sample);
  void Commit();

 private:
  AtomicFile file_;
};

/// Writes t_s,pressure_pa,altitude_m,temperature_degC with 17 significant digits, NaN as
/// an empty field; the file appears on Commit().
class CsvBaroWriter {
 public:
  /// A non-empty note is written as a "# note" line before the header (the readers skip
  /// it): e.g. the time scale.
  explicit CsvBaroWriter(const std::string& path, const std::string& note = "");
  /// Throws std::invalid_argument for a non-finite time, an infinite value, or a sample
  /// with neither pressure nor altitude.
  void Write(const BaroSample& sample);
  void Commit();

 private:
  AtomicFile file_;
};

}  // namespace navtwin
