#include "core/io/text_reader.h"

#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "core/io/input_error.h"

namespace navtwin {
namespace {

bool IsBlankChar(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::string Quote(std::string_view text) {
  constexpr std::size_t kMaxShown = 40;  // a runaway field should not flood the message
  std::string s(text.substr(0, kMaxShown));
  if (text.size() > kMaxShown) s += "...";
  return "'" + s + "'";
}

std::string FormatSeconds(double t_s) {
  std::ostringstream os;
  os.precision(15);
  os << t_s << " s";
  return os.str();
}

char LowerAscii(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

}  // namespace

LineReader::LineReader(const std::string& path)
    : path_(path), in_(path, std::ios::binary), buf_(new char[kBlockBytes]) {
  if (!in_) throw InputError(path, 0, "", "cannot open the file");
}

bool LineReader::Fill() {
  pos_ = 0;
  end_ = 0;
  if (!in_) return false;
  in_.read(buf_.get(), static_cast<std::streamsize>(kBlockBytes));
  end_ = static_cast<std::size_t>(in_.gcount());
  return end_ > 0;
}

int LineReader::Peek() {
  if (pos_ == end_ && !Fill()) return -1;
  return static_cast<unsigned char>(buf_[pos_]);
}

bool LineReader::Next(std::string* line) {
  line->clear();
  line_end_ = LineEnd::kNone;
  bool any = false;
  while (pos_ < end_ || Fill()) {
    any = true;
    const char* begin = buf_.get() + pos_;
    const std::size_t n = end_ - pos_;
    // The first '\n', then a '\r' before it (never scanning past the line's end).
    const char* lf = static_cast<const char*>(std::memchr(begin, '\n', n));
    const std::size_t upto = lf ? static_cast<std::size_t>(lf - begin) : n;
    const char* cr = static_cast<const char*>(std::memchr(begin, '\r', upto));
    const char* stop = cr ? cr : lf;
    if (!stop) {  // the line goes on in the next block
      line->append(begin, n);
      offset_ += n;
      pos_ = end_;
      continue;
    }
    const std::size_t length = static_cast<std::size_t>(stop - begin);
    line->append(begin, length);
    pos_ += length + 1;
    offset_ += length + 1;
    line_end_ = cr ? LineEnd::kCr : LineEnd::kLf;
    if (cr && Peek() == '\n') {
      ++pos_;
      ++offset_;
      line_end_ = LineEnd::kCrLf;
    }
    break;
  }
  if (!any) return false;
  ++line_number_;
  return true;
}

bool IsBlank(std::string_view line) {
  for (char c : line) {
    if (!IsBlankChar(c)) return false;
  }
  return true;
}

std::string_view Trim(std::string_view text) {
  std::size_t b = 0;
  std::size_t e = text.size();
  while (b < e && IsBlankChar(text[b])) ++b;
  while (e > b && IsBlankChar(text[e - 1])) --e;
  return text.substr(b, e - b);
}

std::string_view StripUnit(std::string_view name) { return Trim(name.substr(0, name.find('('))); }

void SplitCsv(std::string_view line, std::vector<std::string_view>* fields) {
  fields->clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields->push_back(Trim(line.substr(start)));
      return;
    }
    fields->push_back(Trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
}

void SplitLoose(std::string_view line, std::vector<std::string_view>* fields) {
  // A table of the separators (blanks and ','): one load per character instead of six
  // comparisons; this loop was 40 % of reading a KF-GINS IMU file.
  static const auto kSeparator = [] {
    std::array<bool, 256> table{};
    for (int c = 0; c < 256; ++c) table[c] = IsBlankChar(static_cast<char>(c)) || c == ',';
    return table;
  }();
  const auto separator = [](char c) { return kSeparator[static_cast<unsigned char>(c)]; };
  fields->clear();
  const char* p = line.data();
  const char* const end = p + line.size();
  while (p < end) {
    while (p < end && separator(*p)) ++p;
    const char* start = p;
    while (p < end && !separator(*p)) ++p;
    if (p > start) fields->emplace_back(start, static_cast<std::size_t>(p - start));
  }
}

double ParseDouble(std::string_view text, const std::string& path, long line,
                   const std::string& field) {
  std::string_view t = text;
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (t.empty() || ec == std::errc::invalid_argument || end != t.data() + t.size()) {
    throw InputError(path, line, field, "not a number: " + Quote(text));
  }
  if (ec == std::errc::result_out_of_range || !std::isfinite(value)) {
    throw InputError(path, line, field, "not a finite number: " + Quote(text));
  }
  return value;
}

double ParseScaled(std::string_view text, double scale, const std::string& path, long line,
                   const std::string& field) {
  const double value = ParseDouble(text, path, line, field) * scale;
  if (!std::isfinite(value)) {
    std::ostringstream os;
    os << "not a finite number in SI units: " << Quote(text) << " times the unit factor " << scale
       << " overflows";
    throw InputError(path, line, field, os.str());
  }
  return value;
}

long long ParseInteger(std::string_view text, const std::string& path, long line,
                       const std::string& field) {
  std::string_view t = text;
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  long long value = 0;
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (t.empty() || ec != std::errc() || end != t.data() + t.size()) {
    throw InputError(path, line, field, "not an integer: " + Quote(text));
  }
  return value;
}

int ParseWholeNumber(std::string_view text, const std::string& path, long line,
                     const std::string& field) {
  const double v = ParseDouble(text, path, line, field);
  constexpr double kLimit = 1e9;  // far beyond any count or flag these files hold
  if (v != std::floor(v) || std::fabs(v) > kLimit) {
    throw InputError(path, line, field, "not a whole number: " + Quote(text));
  }
  return static_cast<int>(v);
}

void RequirePositive(double value, const std::string& path, long line, const std::string& field) {
  if (!(value > 0.0)) {
    std::ostringstream os;
    os << "must be > 0, got " << value;
    throw InputError(path, line, field, os.str());
  }
  // A subnormal value (below 2.2e-308) is > 0 but has lost its precision, and 1/value^2
  // (a weight) overflows.
  if (value < std::numeric_limits<double>::min()) {
    std::ostringstream os;
    os << "must be > 0 and not subnormal (below " << std::numeric_limits<double>::min() << "), got " << value;
    throw InputError(path, line, field, os.str());
  }
}

void RequireFieldCount(std::size_t found, std::size_t expected, const std::string& path,
                       long line) {
  if (found != expected) {
    throw InputError(
        path, line, "",
        "expected " + std::to_string(expected) + " columns, found " + std::to_string(found));
  }
}

void IncreasingTime::Check(double t_s, const std::string& path, long line,
                           const std::string& field) {
  if (line_ > 0 && !(t_s > t_s_)) {
    throw InputError(path, line, field,
                     "time " + FormatSeconds(t_s) + " does not increase (previous " +
                         FormatSeconds(t_s_) + " at line " + std::to_string(line_) + ")");
  }
  t_s_ = t_s;
  line_ = line;
}

bool EqualsNoCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (LowerAscii(a[i]) != LowerAscii(b[i])) return false;
  }
  return true;
}

HeaderColumns::HeaderColumns(const std::vector<std::string_view>& names, const std::string& path,
                             long line)
    : path_(path), line_(line) {
  names_.reserve(names.size());
  for (std::string_view n : names) names_.emplace_back(Trim(n));
}

int HeaderColumns::Find(std::string_view name) const {
  for (std::size_t i = 0; i < names_.size(); ++i) {
    if (EqualsNoCase(names_[i], name)) return static_cast<int>(i);
  }
  return -1;
}

int HeaderColumns::Require(const std::string& name) const {
  const int i = Find(name);
  if (i < 0) throw InputError(path_, line_, name, "missing column '" + name + "'");
  return i;
}

UnitColumn HeaderColumns::FindWithUnit(const std::string& stem,
                                       std::initializer_list<UnitSuffix> units) const {
  for (const UnitSuffix& u : units) {
    const std::string name = stem + u.suffix;
    const int i = Find(name);
    if (i >= 0) return UnitColumn{i, u.scale, name};
  }
  return UnitColumn{-1, 1.0, stem + units.begin()->suffix};
}

UnitColumn HeaderColumns::RequireWithUnit(const std::string& stem,
                                          std::initializer_list<UnitSuffix> units) const {
  const UnitColumn c = FindWithUnit(stem, units);
  if (c.index >= 0) return c;
  std::string tried;
  for (const UnitSuffix& u : units) tried += (tried.empty() ? "'" : " or '") + stem + u.suffix + "'";
  throw InputError(path_, line_, c.name, "missing column " + tried);
}

}  // namespace navtwin
