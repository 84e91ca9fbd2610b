#include "problems/report/csv_table.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <cmath>
#include <string_view>

#include "core/io/input_error.h"

namespace navtwin::report {
namespace {

/// A file mapped read-only into memory (no copy: errors.csv of an hour at 200 Hz is
/// 300 MB per method), unmapped on destruction.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY);
    if (fd < 0) throw InputError(path, 0, "", std::string("cannot open the file: ") + std::strerror(errno));
    struct stat st;
    if (::fstat(fd, &st) == 0 && st.st_size > 0) {
      size_ = static_cast<std::size_t>(st.st_size);
      void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
      if (p == MAP_FAILED) {
        ::close(fd);
        throw InputError(path, 0, "", std::string("cannot read the file: ") + std::strerror(errno));
      }
      data_ = static_cast<const char*>(p);
      ::madvise(p, size_, MADV_SEQUENTIAL);
    }
    ::close(fd);
  }
  ~MappedFile() {
    if (data_ != nullptr) ::munmap(const_cast<char*>(data_), size_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  std::string_view view() const { return data_ == nullptr ? std::string_view() : std::string_view(data_, size_); }

 private:
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

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
  const MappedFile file(path);
  const std::string_view data = file.view();
  std::vector<std::string_view> fields;
  std::vector<int> source(columns.size(), -1);  // field index of each requested column
  std::vector<int> target;                       // requested column of each field, or -1
  std::size_t header_fields = 0;
  long line_number = 0;
  std::size_t pos = 0;
  while (pos < data.size()) {
    std::size_t end = data.find('\n', pos);
    if (end == std::string_view::npos) end = data.size();
    const std::string_view line(data.data() + pos, end - pos);
    pos = end + 1;
    ++line_number;
    if (TrimCsvField(line).empty()) continue;
    if (header_fields == 0) {
      SplitCsvFields(line, &fields);
      header_fields = fields.size();
      target.assign(header_fields, -1);
      // Room for about as many rows as lines of the header's length fit (rows are longer).
      const std::size_t estimate = data.size() / (line.size() + 1) + 1;
      for (std::size_t c = 0; c < columns.size(); ++c) {
        for (std::size_t f = 0; f < fields.size(); ++f) {
          if (fields[f] == columns[c].name) source[c] = static_cast<int>(f);
        }
        present_[c] = source[c] >= 0;
        if (present_[c]) target[static_cast<std::size_t>(source[c])] = static_cast<int>(c);
        if (present_[c] && !columns[c].text) numbers_[c].reserve(estimate);
        if (!present_[c] && columns[c].required) {
          throw InputError(path, line_number, columns[c].name, "missing column '" + columns[c].name + "' in the header");
        }
      }
      continue;
    }
    // The row, field by field; only the requested columns are kept (target[f] >= 0).
    std::size_t f = 0, begin = 0;
    for (;; ++f) {
      const std::size_t comma = line.find(',', begin);
      const std::size_t stop = comma == std::string_view::npos ? line.size() : comma;
      if (f < header_fields && target[f] >= 0) {
        const std::size_t c = static_cast<std::size_t>(target[f]);
        const std::string_view field = TrimCsvField(line.substr(begin, stop - begin));
        if (columns[c].text) {
          texts_[c].emplace_back(field);
        } else {
          numbers_[c].push_back(ParseCsvNumber(field, path, line_number, columns[c].name));
        }
      }
      if (comma == std::string_view::npos) break;
      begin = comma + 1;
    }
    if (f + 1 != header_fields) {
      throw InputError(path, line_number, "", "expected " + std::to_string(header_fields) + " fields (the header's), found " +
                                                  std::to_string(f + 1));
    }
    ++rows_;
  }
  if (header_fields == 0) throw InputError(path, 0, "", "the file is empty (no header)");
}

}  // namespace navtwin::report
