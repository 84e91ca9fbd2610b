// Low-level PX4 ULog parsing (spec: PX4 "ULog File Format", docs.px4.io dev_log):
// basic types, 'F' format definitions flattened into byte layouts, and a buffered
// message stream that reads one message at a time and handles a file cut short and
// appended-data segments. Used by core/io/ulog.cc; not meant for other callers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace navtwin::ulog {

/// The ULog basic types (all little endian in the file).
enum class BaseType {
  kInt8,
  kUInt8,
  kInt16,
  kUInt16,
  kInt32,
  kUInt32,
  kInt64,
  kUInt64,
  kFloat,
  kDouble,
  kBool,
  kChar
};

/// "float" -> kFloat etc.; false when the name is not a basic type.
bool ParseBaseType(const std::string& name, BaseType* type);
const char* BaseTypeName(BaseType type);
std::size_t BaseTypeSize(BaseType type);
/// One little-endian value at p, converted to double (bool 0/1, char its code).
double DecodeAsDouble(BaseType type, const std::uint8_t* p);
/// An unsigned little-endian integer of n bytes (n <= 8).
std::uint64_t DecodeUnsigned(const std::uint8_t* p, std::size_t n);

/// "type name" or "type[n] name" as written in 'F', 'I' and 'P' messages.
struct TypedName {
  std::string type;      ///< basic type or nested format name, without "[n]"
  int array_length = 0;  ///< 0 for a scalar
  std::string name;
};
/// Parses "float[3] gyro_rad"; false (and *reason set) when it is malformed. Keys of
/// key-value messages may have empty arrays ("char[0] name", an empty string value);
/// allow_empty_array accepts them (array_length 0, as for a scalar).
bool ParseTypedName(const std::string& text, TypedName* out, std::string* reason,
                    bool allow_empty_array = false);

/// One 'F' message as written: "name:type field;type[n] field;...".
struct Format {
  std::string name;
  std::vector<TypedName> fields;
  long long byte_offset = 0;  ///< of the 'F' message, for errors found later
};
/// Parses the text of an 'F' message; throws InputError (file, byte) when malformed.
Format ParseFormat(const std::string& text, const std::string& file, long long byte_offset);

/// A basic-type field after nested formats are flattened: "q", "esc[1].esc_rpm".
struct Leaf {
  std::string name;
  BaseType type = BaseType::kUInt8;
  int array_length = 0;  ///< 0 for a scalar
  std::size_t offset = 0;
};

/// The byte layout of a subscribed format. Padding fields (names starting with
/// "_padding") are counted in the size but are not leaves.
struct Layout {
  std::vector<Leaf> leaves;
  std::size_t size = 0;      ///< full size in bytes
  std::size_t min_size = 0;  ///< size without a trailing top-level padding field, which
                             ///< the logger may leave out of data messages
};
/// Checks format `name` without expanding it: every nested type defined, no circular
/// nesting, a size (bytes, nested arrays multiplied out) no larger than the 65535 bytes
/// of a data message. Returns that size; *sizes keeps the sizes of the formats checked
/// so far (pass the same map to check many formats in linear time). Throws InputError
/// at the offending 'F' message.
std::size_t CheckFormat(const std::string& name, const std::map<std::string, Format>& formats,
                        const std::string& file, std::map<std::string, std::size_t>* sizes);
/// Flattens format `name` after CheckFormat (whose InputErrors it throws).
Layout Flatten(const std::string& name, const std::map<std::string, Format>& formats,
               const std::string& file);

/// One message: type character, byte offset of its 3-byte header, payload.
struct Message {
  char type = 0;
  long long byte_offset = 0;
  std::vector<std::uint8_t> payload;
};

/// Reads a ULog file message by message through a buffered std::ifstream.
class MessageStream {
 public:
  /// Opens the file and checks the 16-byte header; throws InputError (byte 0 for a
  /// bad magic) when it is not a ULog file.
  explicit MessageStream(const std::string& path);
  MessageStream(const MessageStream&) = delete;
  MessageStream& operator=(const MessageStream&) = delete;

  /// The next message, or false at the end of the file. A message cut short by the
  /// end of the file is discarded and recorded (truncated_at_byte()).
  bool Next(Message* message);
  /// Appended-data offsets from the flag-bits message: the data before each offset
  /// may end inside a message, which is discarded; reading resumes at the offset.
  void SetAppendedOffsets(std::vector<long long> offsets);

  const std::string& path() const { return path_; }
  int version() const { return version_; }
  std::uint64_t start_time_us() const { return start_time_us_; }
  long long position() const { return pos_; }
  /// Byte offset of the record cut short by the end of the file, -1 if none.
  long long truncated_at_byte() const { return truncated_at_; }

 private:
  bool ReadExactly(std::uint8_t* out, std::size_t n);
  void SeekTo(long long offset);

  std::string path_;
  std::vector<char> buffer_;
  std::ifstream in_;
  long long pos_ = 0;
  int version_ = 0;
  std::uint64_t start_time_us_ = 0;
  long long truncated_at_ = -1;
  std::vector<long long> segment_ends_;  ///< pending appended-data offsets, ascending
};

}  // namespace navtwin::ulog
