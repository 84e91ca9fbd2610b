// Wheel-odometer files (navtwin CSV): a header, then one row per sample, either
//   t_s,speed_mps     the forward speed of the vehicle reference point at t_s, or
//   t_s,distance_m    the distance travelled over (previous t_s, t_s] (the first row only
//                     starts the count), read as the mean speed distance / interval at the
//                     interval's middle.
// Lexical rules as for the other navtwin CSV files (core/io/csv_series.h); t_ms is accepted
// for the time. Bad input throws InputError naming the file, the line and the field.
#pragma once

#include <string>
#include <vector>

#include "core/io/atomic_file.h"

namespace navtwin {

struct OdometerSample {
  double t_s = 0.0;
  double speed_mps = 0.0;  ///< forward speed (negative when reversing)
};

/// Speeds in time order. Speeds beyond +-200 m/s are an InputError.
std::vector<OdometerSample> ReadOdometerCsv(const std::string& path);

/// Writes t_s,speed_mps with 17 significant digits; the file appears on Commit().
class CsvOdometerWriter {
 public:
  explicit CsvOdometerWriter(const std::string& path);
  /// Throws std::invalid_argument on a non-finite value.
  void Write(const OdometerSample& sample);
  void Commit() { file_.Commit(); }

 private:
  AtomicFile file_;
};

}  // namespace navtwin
