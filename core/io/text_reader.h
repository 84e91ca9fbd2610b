// Shared pieces of the text-format readers: a streaming line reader that counts lines,
// field splitting (CSV or blank/comma separated), number parsing that throws InputError
// naming file, line and field, and the checks every reader makes (finite numbers,
// positive standard deviations, strictly increasing time, named columns).
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/file_summary.h"
#include "core/io/sample_reader.h"

namespace navtwin {

/// How the line last returned by LineReader::Next ended.
enum class LineEnd { kNone, kLf, kCrLf, kCr };

/// Reads a text file one line at a time (never the whole file). Accepts LF, CRLF and
/// bare CR line ends (one of the ANSFL files uses old Mac CR ends); the line break is not
/// part of the returned line.
class LineReader {
 public:
  /// Bytes read per block: large enough that a read call per block costs nothing beside the
  /// parsing, small enough that opening a file (the fuzz targets open one per input) does not
  /// cost a megabyte of fresh pages.
  static constexpr std::size_t kBlockBytes = std::size_t{1} << 16;

  /// Throws InputError(path, 0, ...) when the file cannot be opened.
  explicit LineReader(const std::string& path);
  /// Next line into *line; false at the end of the file.
  bool Next(std::string* line);
  /// 1-based number of the line last returned (0 before the first).
  long line_number() const { return line_number_; }
  /// Byte offset just past the line last returned, its line break included.
  std::uint64_t end_offset() const { return offset_; }
  LineEnd line_end() const { return line_end_; }
  const std::string& path() const { return path_; }

 private:
  /// Refills buf_ from the file; false at its end.
  bool Fill();
  /// The next byte without taking it (-1 at the end of the file).
  int Peek();

  std::string path_;
  std::ifstream in_;
  /// One block, left uninitialised (only the bytes read are ever looked at); the lines are
  /// found in it with memchr.
  std::unique_ptr<char[]> buf_;
  std::size_t pos_ = 0, end_ = 0;  ///< unread bytes are buf_[pos_, end_)
  long line_number_ = 0;
  std::uint64_t offset_ = 0;
  LineEnd line_end_ = LineEnd::kNone;
};

/// True when the line holds only blanks.
bool IsBlank(std::string_view line);
/// Removes leading and trailing blanks (space, tab, CR).
std::string_view Trim(std::string_view text);
/// A column name without its unit in parentheses: " compass_heading(degrees)" ->
/// "compass_heading" (trimmed).
std::string_view StripUnit(std::string_view name);
/// Splits on every comma; fields keep their position (empty fields stay) and are trimmed.
void SplitCsv(std::string_view line, std::vector<std::string_view>* fields);
/// Splits on runs of blanks and/or commas (KF-GINS and RTKLIB files); no empty fields.
void SplitLoose(std::string_view line, std::vector<std::string_view>* fields);

/// Whole-field decimal number (a leading '+' allowed); throws InputError naming file,
/// line and field when it is not a number or not finite (nan, inf).
double ParseDouble(std::string_view text, const std::string& path, long line,
                   const std::string& field);
/// ParseDouble times `scale` (a unit's factor to SI); throws InputError naming file, line and
/// field also when the product is not finite (1e308 g is finite, in m/s^2 it is not).
double ParseScaled(std::string_view text, double scale, const std::string& path, long line,
                   const std::string& field);
/// Whole-field decimal integer; throws InputError like ParseDouble.
long long ParseInteger(std::string_view text, const std::string& path, long line,
                       const std::string& field);
/// A number that must be a whole number (RTKLIB writes Q and ns as "1.0000000").
int ParseWholeNumber(std::string_view text, const std::string& path, long line,
                     const std::string& field);
/// Throws InputError unless value > 0 and not subnormal (standard deviations, intervals).
void RequirePositive(double value, const std::string& path, long line, const std::string& field);
/// Throws InputError unless the line has exactly `expected` fields.
void RequireFieldCount(std::size_t found, std::size_t expected, const std::string& path, long line);

/// Checks that time tags increase strictly, remembering where the last one was.
class IncreasingTime {
 public:
  /// Throws InputError "time ... does not increase" naming the line and field.
  void Check(double t_s, const std::string& path, long line, const std::string& field);
  bool has_previous() const { return line_ > 0; }
  double previous_s() const { return t_s_; }

 private:
  double t_s_ = 0.0;
  long line_ = 0;
};

/// Column names of a CSV header line, looked up by name.
/// A unit suffix a column name may carry and its factor to the SI unit, e.g. {"_dps", deg->rad}.
struct UnitSuffix {
  const char* suffix;
  double scale;
};

/// A column found under one of its accepted names, with the factor to the SI unit.
struct UnitColumn {
  int index = -1;  ///< -1: absent
  double scale = 1.0;
  std::string name;
};

class HeaderColumns {
 public:
  HeaderColumns() = default;
  /// `names` are the header fields (trimmed); `line` is the header's line number.
  HeaderColumns(const std::vector<std::string_view>& names, const std::string& path, long line);
  /// Index of the column whose name equals `name` (ASCII case-insensitive), or -1.
  int Find(std::string_view name) const;
  /// Like Find, but throws InputError "missing column 'name'" when absent.
  int Require(const std::string& name) const;
  /// The column "<stem><suffix>" for the first of `units` present, or index -1 (named by the
  /// first, SI, suffix).
  UnitColumn FindWithUnit(const std::string& stem, std::initializer_list<UnitSuffix> units) const;
  /// Like FindWithUnit, but throws InputError naming every accepted name when none is present.
  UnitColumn RequireWithUnit(const std::string& stem, std::initializer_list<UnitSuffix> units) const;
  std::size_t size() const { return names_.size(); }
  const std::vector<std::string>& names() const { return names_; }

 private:
  std::vector<std::string> names_;
  std::string path_;
  long line_ = 0;
};

/// ASCII case-insensitive equality.
bool EqualsNoCase(std::string_view a, std::string_view b);

/// Reads a whole stream and summarises its time tags (for `navtwin info`).
template <typename Sample>
StreamSummary SummarizeStream(SampleReader<Sample>* reader, const std::string& name,
                              std::vector<std::string> fields) {
  TimeTagStats stats;
  Sample sample;
  while (reader->Next(&sample)) stats.Add(sample.t_s);
  return StreamSummary::FromStats(name, stats, std::move(fields));
}

}  // namespace navtwin
