#include "core/io/ulog_format.h"

#include <algorithm>
#include <cctype>
#include <cstring>

#include "core/io/input_error.h"
#include "core/text.h"

namespace navtwin::ulog {
namespace {

constexpr std::size_t kHeaderSize = 16;
constexpr std::uint8_t kMagic[7] = {'U', 'L', 'o', 'g', 0x01, 0x12, 0x35};
constexpr std::size_t kStreamBufferBytes = 1 << 16;
// Nested formats deeper than this are treated as circular (real logs nest 2-3 levels).
constexpr std::size_t kMaxNesting = 32;
// A data message holds at most 65535 bytes, so no loggable format is larger.
constexpr std::size_t kMaxFormatBytes = 65535;

struct BaseTypeInfo {
  const char* name;
  BaseType type;
  std::size_t size;
};

constexpr BaseTypeInfo kBaseTypes[] = {
    {"int8_t", BaseType::kInt8, 1},   {"uint8_t", BaseType::kUInt8, 1},
    {"int16_t", BaseType::kInt16, 2}, {"uint16_t", BaseType::kUInt16, 2},
    {"int32_t", BaseType::kInt32, 4}, {"uint32_t", BaseType::kUInt32, 4},
    {"int64_t", BaseType::kInt64, 8}, {"uint64_t", BaseType::kUInt64, 8},
    {"float", BaseType::kFloat, 4},   {"double", BaseType::kDouble, 8},
    {"bool", BaseType::kBool, 1},     {"char", BaseType::kChar, 1},
};

const BaseTypeInfo& Info(BaseType type) { return kBaseTypes[static_cast<int>(type)]; }

bool IsPadding(const std::string& field_name) { return field_name.rfind("_padding", 0) == 0; }

bool IsNameChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-' || c == '/';
}

// Signed value of an n-byte two's-complement integer.
std::int64_t SignExtend(std::uint64_t u, std::size_t n) {
  if (n == 8) {
    std::int64_t s;
    std::memcpy(&s, &u, sizeof s);
    return s;
  }
  const std::uint64_t sign = std::uint64_t{1} << (8 * n - 1);
  return static_cast<std::int64_t>(u ^ sign) - static_cast<std::int64_t>(sign);
}

// The format that field `field` of `format` nests; throws at the 'F' message of `format`
// when the type is not defined or the nesting is circular (`stack`: formats being resolved).
const Format& NestedFormat(const Format& format, const TypedName& field,
                           const std::map<std::string, Format>& formats, const std::string& file,
                           const std::vector<std::string>& stack) {
  const std::string where = PrintableText(format.name) + "." + PrintableText(field.name);
  const auto nested = formats.find(field.type);
  if (nested == formats.end()) {
    throw InputError::AtByte(file, format.byte_offset, where,
                             "unknown type '" + PrintableText(field.type) +
                                 "' (neither a basic type nor a defined format)");
  }
  if (stack.size() >= kMaxNesting ||
      std::find(stack.begin(), stack.end(), field.type) != stack.end()) {
    throw InputError::AtByte(file, format.byte_offset, where,
                             "circular nesting of format '" + PrintableText(field.type) + "'");
  }
  return nested->second;
}

// The size in bytes of `format` with its nested formats resolved, without expanding them;
// sizes already known are in *sizes, which gets this one. Throws at the 'F' message of
// the first format found larger than a data message can hold.
std::size_t ResolvedSize(const Format& format, const std::map<std::string, Format>& formats,
                         const std::string& file, std::vector<std::string>* stack,
                         std::map<std::string, std::size_t>* sizes) {
  const auto known = sizes->find(format.name);
  if (known != sizes->end()) return known->second;
  std::size_t total = 0;
  for (const TypedName& field : format.fields) {
    BaseType type;
    std::size_t element = 0;
    if (ParseBaseType(field.type, &type)) {
      element = BaseTypeSize(type);
    } else {
      const Format& nested = NestedFormat(format, field, formats, file, *stack);
      stack->push_back(field.type);
      element = ResolvedSize(nested, formats, file, stack, sizes);
      stack->pop_back();
    }
    const std::size_t count =
        field.array_length > 0 ? static_cast<std::size_t>(field.array_length) : 1;
    // total <= kMaxFormatBytes here, so the bound below cannot overflow.
    if (element > (kMaxFormatBytes - total) / count) {
      throw InputError::AtByte(
          file, format.byte_offset, PrintableText(format.name) + "." + PrintableText(field.name),
          "format '" + PrintableText(format.name) + "' is larger than " +
              std::to_string(kMaxFormatBytes) + " bytes (the most a data message holds)");
    }
    total += element * count;
  }
  sizes->emplace(format.name, total);
  return total;
}

// Appends the leaves of `format` (prefix e.g. "esc[1].") at byte `base` to *leaves and
// returns the format's size in bytes. The format has been checked by ResolvedSize.
std::size_t FlattenInto(const Format& format, const std::string& prefix, std::size_t base,
                        const std::map<std::string, Format>& formats, std::vector<Leaf>* leaves) {
  std::size_t offset = 0;
  for (const TypedName& field : format.fields) {
    const std::size_t count =
        field.array_length > 0 ? static_cast<std::size_t>(field.array_length) : 1;
    const bool keep = !IsPadding(field.name);
    BaseType type;
    if (ParseBaseType(field.type, &type)) {
      if (keep) leaves->push_back({prefix + field.name, type, field.array_length, base + offset});
      offset += count * BaseTypeSize(type);
      continue;
    }
    const Format& nested = formats.at(field.type);
    std::vector<Leaf> scratch;  // leaves of a nested padding field are dropped
    for (std::size_t i = 0; i < count; ++i) {
      std::string nested_prefix = prefix + field.name;
      if (field.array_length > 0) nested_prefix += "[" + std::to_string(i) + "]";
      offset += FlattenInto(nested, nested_prefix + ".", base + offset, formats,
                            keep ? leaves : &scratch);
    }
  }
  return offset;
}

}  // namespace

bool ParseBaseType(const std::string& name, BaseType* type) {
  for (const BaseTypeInfo& info : kBaseTypes) {
    if (name == info.name) {
      *type = info.type;
      return true;
    }
  }
  return false;
}

const char* BaseTypeName(BaseType type) { return Info(type).name; }

std::size_t BaseTypeSize(BaseType type) { return Info(type).size; }

std::uint64_t DecodeUnsigned(const std::uint8_t* p, std::size_t n) {
  std::uint64_t u = 0;
  for (std::size_t i = 0; i < n; ++i) u |= std::uint64_t{p[i]} << (8 * i);
  return u;
}

double DecodeAsDouble(BaseType type, const std::uint8_t* p) {
  const std::size_t n = BaseTypeSize(type);
  const std::uint64_t u = DecodeUnsigned(p, n);
  switch (type) {
    case BaseType::kInt8:
    case BaseType::kInt16:
    case BaseType::kInt32:
    case BaseType::kInt64: return static_cast<double>(SignExtend(u, n));
    case BaseType::kFloat: {
      const std::uint32_t bits = static_cast<std::uint32_t>(u);
      float f;
      std::memcpy(&f, &bits, sizeof f);
      return f;
    }
    case BaseType::kDouble: {
      double d;
      std::memcpy(&d, &u, sizeof d);
      return d;
    }
    default:  // unsigned integers, bool, char
      return static_cast<double>(u);
  }
}

bool ParseTypedName(const std::string& text, TypedName* out, std::string* reason,
                    bool allow_empty_array) {
  const std::size_t space = text.find(' ');
  if (space == std::string::npos || space == 0 || space + 1 == text.size()) {
    *reason = "expected 'type name', got '" + PrintableText(text) + "'";
    return false;
  }
  out->name = text.substr(space + 1);
  if (!std::all_of(out->name.begin(), out->name.end(), IsNameChar)) {
    *reason = "bad field name '" + PrintableText(out->name) + "'";
    return false;
  }
  std::string type = text.substr(0, space);
  out->array_length = 0;
  const std::size_t open = type.find('[');
  if (open != std::string::npos) {
    const std::string digits = type.substr(open + 1, type.size() - open - 2);
    if (type.back() != ']' || digits.empty() || digits.size() > 5 ||
        !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }) ||
        (std::stoi(digits) == 0 && !allow_empty_array)) {
      *reason = "bad array type '" + PrintableText(type) + "'";
      return false;
    }
    out->array_length = std::stoi(digits);
    type.resize(open);
  }
  if (type.empty() || !std::all_of(type.begin(), type.end(), IsNameChar)) {
    *reason = "bad type '" + PrintableText(text.substr(0, space)) + "'";
    return false;
  }
  out->type = type;
  return true;
}

Format ParseFormat(const std::string& text, const std::string& file, long long byte_offset) {
  Format format;
  format.byte_offset = byte_offset;
  const std::size_t colon = text.find(':');
  if (colon == std::string::npos || colon == 0) {
    throw InputError::AtByte(file, byte_offset, "format",
                             "expected 'name:type field;...', got '" + PrintableText(text) + "'");
  }
  format.name = text.substr(0, colon);
  std::size_t start = colon + 1;
  while (start < text.size()) {
    std::size_t end = text.find(';', start);
    if (end == std::string::npos) end = text.size();
    if (end > start) {
      TypedName field;
      std::string reason;
      if (!ParseTypedName(text.substr(start, end - start), &field, &reason)) {
        throw InputError::AtByte(
            file, byte_offset,
            PrintableText(format.name) + " field " + std::to_string(format.fields.size() + 1),
            reason);
      }
      format.fields.push_back(field);
    }
    start = end + 1;
  }
  if (format.fields.empty()) {
    throw InputError::AtByte(file, byte_offset, PrintableText(format.name), "format has no fields");
  }
  return format;
}

std::size_t CheckFormat(const std::string& name, const std::map<std::string, Format>& formats,
                        const std::string& file, std::map<std::string, std::size_t>* sizes) {
  std::vector<std::string> stack = {name};
  return ResolvedSize(formats.at(name), formats, file, &stack, sizes);
}

Layout Flatten(const std::string& name, const std::map<std::string, Format>& formats,
               const std::string& file) {
  std::map<std::string, std::size_t> sizes;
  CheckFormat(name, formats, file, &sizes);
  const Format& format = formats.at(name);
  Layout layout;
  layout.size = FlattenInto(format, "", 0, formats, &layout.leaves);
  layout.min_size = layout.size;
  const TypedName& last = format.fields.back();
  BaseType type;
  if (IsPadding(last.name) && ParseBaseType(last.type, &type)) {
    layout.min_size -=
        BaseTypeSize(type) * static_cast<std::size_t>(std::max(1, last.array_length));
  }
  return layout;
}

MessageStream::MessageStream(const std::string& path) : path_(path), buffer_(kStreamBufferBytes) {
  in_.rdbuf()->pubsetbuf(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
  in_.open(path, std::ios::binary);
  if (!in_) throw InputError(path, 0, "", "cannot open file");
  std::uint8_t header[kHeaderSize];
  in_.read(reinterpret_cast<char*>(header), kHeaderSize);
  const std::size_t got = static_cast<std::size_t>(in_.gcount());
  if (got == 0) throw InputError::AtByte(path, 0, "header", "empty file");
  if (std::memcmp(header, kMagic, std::min(got, sizeof kMagic)) != 0) {
    throw InputError::AtByte(path, 0, "magic", "not a ULog file (expected 'ULog' 01 12 35)");
  }
  if (got < kHeaderSize) {
    throw InputError::AtByte(path, 0, "header", "file ends inside the 16-byte header");
  }
  version_ = header[7];
  start_time_us_ = DecodeUnsigned(header + 8, 8);
  pos_ = kHeaderSize;
}

bool MessageStream::ReadExactly(std::uint8_t* out, std::size_t n) {
  in_.read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(n));
  pos_ += in_.gcount();
  return static_cast<std::size_t>(in_.gcount()) == n;
}

void MessageStream::SeekTo(long long offset) {
  in_.clear();
  in_.seekg(offset);
  pos_ = offset;
}

void MessageStream::SetAppendedOffsets(std::vector<long long> offsets) {
  segment_ends_ = std::move(offsets);
}

bool MessageStream::Next(Message* message) {
  if (truncated_at_ >= 0) return false;
  for (;;) {
    if (!segment_ends_.empty() && pos_ >= segment_ends_.front()) {
      segment_ends_.erase(segment_ends_.begin());
      continue;
    }
    const long long start = pos_;
    std::uint8_t header[3];
    if (!ReadExactly(header, sizeof header)) {
      if (pos_ > start) truncated_at_ = start;  // 1 or 2 header bytes: cut short
      return false;
    }
    const std::size_t size = static_cast<std::size_t>(DecodeUnsigned(header, 2));
    if (!segment_ends_.empty() &&
        start + 3 + static_cast<long long>(size) > segment_ends_.front()) {
      // The logger stopped inside this message and appended data after it: drop it.
      SeekTo(segment_ends_.front());
      continue;
    }
    message->type = static_cast<char>(header[2]);
    message->byte_offset = start;
    message->payload.resize(size);
    if (!ReadExactly(message->payload.data(), size)) {
      truncated_at_ = start;
      return false;
    }
    return true;
  }
}

}  // namespace navtwin::ulog
