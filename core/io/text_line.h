// Builds one line of a text file in a fixed buffer and writes it with one call: numbers in
// the shortest form that reads back exactly (std::to_chars), without the per-number cost
// of stream formatting. Used by the writers of large files (IMU, navigation).
#pragma once

#include <charconv>
#include <cstddef>
#include <ostream>
#include <stdexcept>
#include <string_view>

namespace navtwin {

class TextLine {
 public:
  TextLine& Number(double x) {
    Reserve(32);
    n_ = static_cast<std::size_t>(std::to_chars(buf_ + n_, buf_ + kSize, x).ptr - buf_);
    return *this;
  }
  TextLine& Integer(long long x) {
    Reserve(24);
    n_ = static_cast<std::size_t>(std::to_chars(buf_ + n_, buf_ + kSize, x).ptr - buf_);
    return *this;
  }
  TextLine& Char(char c) {
    Reserve(1);
    buf_[n_++] = c;
    return *this;
  }
  /// What the line holds so far.
  std::string_view view() const { return std::string_view(buf_, n_); }
  /// Appends text as it is.
  TextLine& Text(std::string_view text) {
    Reserve(text.size());
    for (const char c : text) buf_[n_++] = c;
    return *this;
  }
  /// Writes the line (with what it holds; add the '\n' yourself) and empties it.
  void WriteTo(std::ostream& os) {
    os.write(buf_, static_cast<std::streamsize>(n_));
    n_ = 0;
  }

 private:
  static constexpr std::size_t kSize = 1024;
  void Reserve(std::size_t k) {
    if (n_ + k > kSize) throw std::length_error("TextLine: line longer than 1024 characters");
  }
  char buf_[kSize];
  std::size_t n_ = 0;
};

}  // namespace navtwin
