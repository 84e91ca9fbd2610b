// One-value time series in CSV: a header naming the time column (t_s or t_ms) and the value
// column under one of its unit suffixes, then one row per sample; the same lexical rules as
// the other navtwin CSV files (blank lines and '#' lines before the header skipped, columns
// found by name, case-insensitive, in any order; every row has the header's field count;
// time strictly increasing). Used for the pendulum's pivot encoder (t_s,theta_rad) and the
// IMU temperature of a warm-up (t_s,temperature_degC).
#pragma once

#include <initializer_list>
#include <limits>
#include <string>
#include <vector>

#include "core/io/text_reader.h"

namespace navtwin {

struct ScalarSeries {
  std::string path;
  std::string stem;           ///< the value column's stem (of the alternatives, the one found)
  std::vector<double> t_s;
  std::vector<double> value;  ///< SI (the unit suffix's scale applied)
};

/// Reads column "<stem><suffix>" (the first of `units` present) against time. Values outside
/// [lo, hi] (in SI) are errors. Throws InputError naming the file, line and field for a
/// missing column, a bad or non-finite number, a short row, time not increasing, an empty file.
ScalarSeries ReadScalarSeriesCsv(const std::string& path, const std::string& stem,
                                 std::initializer_list<UnitSuffix> units,
                                 double lo = -std::numeric_limits<double>::infinity(),
                                 double hi = std::numeric_limits<double>::infinity());

/// One value column of several alternatives: the first stem whose column (with one of its
/// units) the header has; the others as above. A header with none of them is an InputError
/// naming every alternative.
struct SeriesColumn {
  std::string stem;
  std::initializer_list<UnitSuffix> units;
};
ScalarSeries ReadScalarSeriesCsv(const std::string& path, std::initializer_list<SeriesColumn> alternatives,
                                 double lo = -std::numeric_limits<double>::infinity(),
                                 double hi = std::numeric_limits<double>::infinity());

}  // namespace navtwin
