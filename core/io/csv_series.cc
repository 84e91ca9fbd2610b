#include "core/io/csv_series.h"

#include <sstream>
#include <string_view>

#include "core/io/input_error.h"
#include "core/io/plausibility.h"

namespace navtwin {
namespace {

/// The first alternative's column that the header has (one alternative: RequireWithUnit).
UnitColumn ValueColumn(const HeaderColumns& header, std::initializer_list<SeriesColumn> alternatives,
                       const std::string& path, long line, std::string* stem) {
  if (alternatives.size() == 1) {
    *stem = alternatives.begin()->stem;
    return header.RequireWithUnit(*stem, alternatives.begin()->units);
  }
  std::string tried;
  for (const SeriesColumn& c : alternatives) {
    const UnitColumn column = header.FindWithUnit(c.stem, c.units);
    if (column.index >= 0) {
      *stem = c.stem;
      return column;
    }
    for (const UnitSuffix& u : c.units) tried += (tried.empty() ? "'" : " or '") + c.stem + u.suffix + "'";
  }
  throw InputError(path, line, alternatives.begin()->stem, "missing column " + tried);
}

}  // namespace

ScalarSeries ReadScalarSeriesCsv(const std::string& path, const std::string& stem,
                                 std::initializer_list<UnitSuffix> units, double lo, double hi) {
  return ReadScalarSeriesCsv(path, {SeriesColumn{stem, units}}, lo, hi);
}

ScalarSeries ReadScalarSeriesCsv(const std::string& path, std::initializer_list<SeriesColumn> alternatives,
                                 double lo, double hi) {
  ScalarSeries out;
  out.path = path;
  LineReader lines(path);
  std::string line;
  std::vector<std::string_view> fields;
  HeaderColumns header;
  UnitColumn time, column;
  bool have_header = false;
  IncreasingTime monotonic;
  while (lines.Next(&line)) {
    if (IsBlank(line)) continue;
    if (!have_header) {
      if (Trim(line).front() == '#') continue;
      SplitCsv(line, &fields);
      header = HeaderColumns(fields, path, lines.line_number());
      time = header.RequireWithUnit("t", {{"_s", 1.0}, {"_ms", 1e-3}});
      column = ValueColumn(header, alternatives, path, lines.line_number(), &out.stem);
      have_header = true;
      continue;
    }
    SplitCsv(line, &fields);
    RequireFieldCount(fields.size(), header.size(), path, lines.line_number());
    const double t =
        ParseScaled(fields[static_cast<std::size_t>(time.index)], time.scale, path, lines.line_number(), time.name);
    plausible::Time(t, path, lines.line_number(), time.name);
    monotonic.Check(t, path, lines.line_number(), time.name);
    const double v = ParseScaled(fields[static_cast<std::size_t>(column.index)], column.scale, path,
                                 lines.line_number(), column.name);
    if (v < lo || v > hi) {
      std::ostringstream why;
      why.precision(10);
      why << "must be within [" << lo / column.scale << ", " << hi / column.scale << "], got " << v / column.scale;
      throw InputError(path, lines.line_number(), column.name, why.str());
    }
    out.t_s.push_back(t);
    out.value.push_back(v);
  }
  if (!have_header) throw InputError(path, 0, "", "no samples (the file is empty)");
  if (out.t_s.empty()) throw InputError(path, 0, "", "no samples (only a header)");
  return out;
}

}  // namespace navtwin
