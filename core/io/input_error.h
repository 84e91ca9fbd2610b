// The one error type for bad input: it names the file, the place (line, or byte offset
// for binary files) and the field, so that a user can go straight to the problem.
#pragma once

#include <stdexcept>
#include <string>

namespace navtwin {

class InputError : public std::runtime_error {
 public:
  /// Text files: line is 1-based; 0 means "the file as a whole" (e.g. it cannot be opened).
  InputError(const std::string& file, long line, const std::string& field, const std::string& reason);
  /// Binary files: the byte offset of the record at fault.
  static InputError AtByte(const std::string& file, long long byte_offset, const std::string& field,
                           const std::string& reason);

  const std::string& file() const { return file_; }
  long line() const { return line_; }              ///< -1 for binary positions
  long long byte_offset() const { return byte_; }  ///< -1 for text positions
  const std::string& field() const { return field_; }
  const std::string& reason() const { return reason_; }

 private:
  InputError(const std::string& file, long line, long long byte, const std::string& field,
             const std::string& reason, const std::string& message);
  std::string file_;
  long line_ = -1;
  long long byte_ = -1;
  std::string field_;
  std::string reason_;
};

}  // namespace navtwin
