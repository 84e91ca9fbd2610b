#include "core/io/input_error.h"

namespace navtwin {
namespace {

std::string Compose(const std::string& file, const std::string& place, const std::string& field,
                    const std::string& reason) {
  std::string m = file;
  if (!place.empty()) m += ":" + place;
  m += ": ";
  if (!field.empty()) m += "field '" + field + "': ";
  return m + reason;
}

}  // namespace

InputError::InputError(const std::string& file, long line, const std::string& field,
                       const std::string& reason)
    : InputError(file, line, -1, field, reason,
                 Compose(file, line > 0 ? "line " + std::to_string(line) : std::string(), field,
                         reason)) {}

InputError InputError::AtByte(const std::string& file, long long byte_offset,
                              const std::string& field, const std::string& reason) {
  return InputError(file, -1, byte_offset, field, reason,
                    Compose(file, "byte " + std::to_string(byte_offset), field, reason));
}

InputError::InputError(const std::string& file, long line, long long byte, const std::string& field,
                       const std::string& reason, const std::string& message)
    : std::runtime_error(message), file_(file), line_(line), byte_(byte), field_(field),
      reason_(reason) {}

}  // namespace navtwin
