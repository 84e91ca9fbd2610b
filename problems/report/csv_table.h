// A CSV file of a run folder read whole for the report: a header of column names, then one
// row per line with the header's field count. Numbers may be "nan" (a value the run did
// not compute); text columns (residuals.csv's sensor) are kept as strings. Only the
// requested columns are kept, by name, in the order of the request.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace navtwin::report {

struct CsvColumn {
  std::string name;
  bool text = false;      ///< kept as strings instead of numbers
  bool required = true;   ///< a missing required column is an InputError
};

class CsvTable {
 public:
  /// Reads `path`. Throws InputError naming the file, the line and the field for a file that
  /// cannot be opened, an empty file, a missing required column, a row with the wrong number
  /// of fields or a field that is not a number.
  CsvTable(const std::string& path, const std::vector<CsvColumn>& columns);

  std::size_t rows() const { return rows_; }
  /// Whether the i-th requested column was in the file.
  bool has(std::size_t i) const { return present_[i]; }
  /// The i-th requested column's numbers (empty when absent).
  const std::vector<double>& number(std::size_t i) const { return numbers_[i]; }
  /// The i-th requested column's strings (text columns only).
  const std::vector<std::string>& text(std::size_t i) const { return texts_[i]; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::size_t rows_ = 0;
  std::vector<bool> present_;
  std::vector<std::vector<double>> numbers_;
  std::vector<std::vector<std::string>> texts_;
};

}  // namespace navtwin::report
