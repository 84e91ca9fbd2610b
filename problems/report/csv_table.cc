#include "problems/report/csv_table.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string_view>

#include "core/io/input_error.h"

namespace navtwin::report {
namespace {

std::string ReadWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "", "cannot open the file");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string_view TrimCsvField(std::string_view f) {
  while (!f.empty() && (f.front() == ' ' || f.front() == '\t')) f.remove_prefix(1);
  while (!f.empty() && (f.back() == ' ' || f.back() == '\t' || f.back() == '\r')) f.remove_suffix(1);
  return f;
}

/// Splits one line at every comma into *fields (trimmed).
void SplitCsvFields(std::string_view line, std::vector<std::string_view>* fields) {
  fields->clear();
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    fields->push_back(TrimCsvField(line.substr(start, comma == std::string_view::npos ? line.size() - start
                                                                                         : comma - start)));
    if (comma == std::string_view::npos) return;
    start = comma + 1;
  }
}

/// A whole-field number; "nan" (any case, with a sign) is NaN.
double ParseCsvNumber(std::string_view f, const std::string& path, long line, const std::string& field) {
  if (!f.empty() && f.front() == '+') f.remove_prefix(1);
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(f.data(), f.data() + f.size(), value);
  if (f.empty() || ec != std::errc() || ptr != f.data() + f.size()) {
    throw InputError(path, line, field, "'" + std::string(f) + "' is not a number");
  }
  return value;
}

}  // namespace

CsvTable::CsvTable(const std::string& path, const std::vector<CsvColumn>& columns)
    : path_(path), present_(columns.size(), false), numbers_(columns.size()), texts_(columns.size()) {
  const std::string data = ReadWholeFile(path);
  std::vector<std::string_view> fields;
  std::vector<int> source(columns.size(), -1);  // field index of each requested column
  std::size_t header_fields = 0;
  long line_number = 0;
  std::size_t pos = 0;
  while (pos < data.size()) {
    std::size_t end = data.find('\n', pos);
    if (end == std::string::npos) end = data.size();
    const std::string_view line(data.data() + pos, end - pos);
    pos = end + 1;
    ++line_number;
    if (TrimCsvField(line).empty()) continue;
    SplitCsvFields(line, &fields);
    if (header_fields == 0) {
      header_fields = fields.size();
      for (std::size_t c = 0; c < columns.size(); ++c) {
        for (std::size_t f = 0; f < fields.size(); ++f) {
          if (fields[f] == columns[c].name) source[c] = static_cast<int>(f);
        }
        present_[c] = source[c] >= 0;
        if (!present_[c] && columns[c].required) {
          throw InputError(path, line_number, columns[c].name, "missing column '" + columns[c].name + "' in the header");
        }
      }
      continue;
    }
    if (fields.size() != header_fields) {
      throw InputError(path, line_number, "", "expected " + std::to_string(header_fields) + " fields (the header's), found " +
                                                  std::to_string(fields.size()));
    }
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (source[c] < 0) continue;
      const std::string_view f = fields[static_cast<std::size_t>(source[c])];
      if (columns[c].text) {
        texts_[c].emplace_back(f);
      } else {
        numbers_[c].push_back(ParseCsvNumber(f, path, line_number, columns[c].name));
      }
    }
    ++rows_;
  }
  if (header_fields == 0) throw InputError(path, 0, "", "the file is empty (no header)");
}

}  // namespace navtwin::report
