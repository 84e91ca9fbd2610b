// navtwin CSV IMU files: comma separated, a header line naming every column with its unit.
// Columns are found by name (ASCII case-insensitive) in any order; other columns are
// ignored; a missing column is an error naming it. Lines before the header that are blank
// or start with '#' are skipped (for provenance notes).
//   time:        t_s [s]  or  t_ms [ms]
//   increments:  dtheta_x_rad dtheta_y_rad dtheta_z_rad dv_x_mps dv_y_mps dv_z_mps
//                over (t_{k-1}, t_k]; the first sample's dt is the second's interval
//   or rates:    gyro_x_rad_s | gyro_x_dps (deg/s), and y, z
//                acc_x_mps2 | acc_x_g (standard gravity 9.80665 m/s^2), and y, z
//                -> increments by the trapezoid rule (rate_to_increment.h); the first
//                rate sample only starts the series.
// Axes: the IMU's (FRD for navtwin data). Time: seconds on whatever scale the file uses.
#pragma once

#include <memory>
#include <string>

#include "core/io/atomic_file.h"
#include "core/io/sample_reader.h"
#include "core/units.h"

namespace navtwin {


std::unique_ptr<ImuReader> OpenCsvImu(const std::string& path);

/// Writes the increment form (t_s, dtheta_*_rad, dv_*_mps) with 17 significant digits.
class CsvImuWriter {
 public:
  /// A non-empty note is written as a "# note" line before the header (the readers skip
  /// it): e.g. the time scale.
  explicit CsvImuWriter(const std::string& path, const std::string& note = "");
  /// Throws std::invalid_argument on a non-finite value.
  void Write(const ImuSample& sample);
  void Commit();

 private:
  AtomicFile file_;
};

}  // namespace navtwin
