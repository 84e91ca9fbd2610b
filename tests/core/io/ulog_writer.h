// A tiny ULog writer for the reader tests: builds files message by message as the PX4
// "ULog File Format" lays them out (little endian; {uint16 size, uint8 type, payload}).
#pragma once

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

#include "tests/core/io/io_test_util.h"

namespace navtwin::ulog_writer {

// Little-endian payload builder.
class Bytes {
 public:
  Bytes& U8(std::uint8_t v) { return Raw(&v, 1); }
  Bytes& U16(std::uint16_t v) { return Int(v, 2); }
  Bytes& U32(std::uint32_t v) { return Int(v, 4); }
  Bytes& I32(std::int32_t v) { return Int(static_cast<std::uint32_t>(v), 4); }
  Bytes& I16(std::int16_t v) { return Int(static_cast<std::uint16_t>(v), 2); }
  Bytes& U64(std::uint64_t v) { return Int(v, 8); }
  Bytes& F32(float v) {
    std::uint32_t u;
    std::memcpy(&u, &v, 4);
    return Int(u, 4);
  }
  Bytes& F64(double v) {
    std::uint64_t u;
    std::memcpy(&u, &v, 8);
    return Int(u, 8);
  }
  Bytes& Str(const std::string& s) { return Raw(s.data(), s.size()); }
  Bytes& Zeros(std::size_t n) {
    data_.append(n, '\0');
    return *this;
  }
  const std::string& data() const { return data_; }

 private:
  Bytes& Int(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) data_.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
    return *this;
  }
  Bytes& Raw(const void* p, std::size_t n) {
    data_.append(static_cast<const char*>(p), n);
    return *this;
  }
  std::string data_;
};

// Writes ULog messages as the PX4 spec lays them out ({uint16 size, uint8 type, payload}).
class ULogWriter {
 public:
  explicit ULogWriter(std::uint8_t version = 1) {
    bytes_.Str("ULog").U8(0x01).U8(0x12).U8(0x35).U8(version).U64(1000);
  }
  /// Byte offset where the next message starts.
  long long offset() const { return static_cast<long long>(bytes_.data().size()); }

  ULogWriter& Message(char type, const std::string& payload) {
    bytes_.U16(static_cast<std::uint16_t>(payload.size()))
        .U8(static_cast<std::uint8_t>(type))
        .Str(payload);
    return *this;
  }
  ULogWriter& FlagBits(std::uint8_t incompat0, std::uint64_t appended = 0) {
    return Message('B', Bytes().Zeros(8).U8(incompat0).Zeros(7).U64(appended).U64(0).U64(0).data());
  }
  ULogWriter& Format(const std::string& text) { return Message('F', text); }
  ULogWriter& Info(const std::string& key, const std::string& value) {
    return Message('I',
                   Bytes().U8(static_cast<std::uint8_t>(key.size())).Str(key).Str(value).data());
  }
  ULogWriter& InfoText(const std::string& name, const std::string& value) {
    return Info("char[" + std::to_string(value.size()) + "] " + name, value);
  }
  ULogWriter& Param(const std::string& key, const std::string& value4) {
    return Message('P',
                   Bytes().U8(static_cast<std::uint8_t>(key.size())).Str(key).Str(value4).data());
  }
  ULogWriter& Subscribe(std::uint8_t multi_id, std::uint16_t msg_id, const std::string& topic) {
    return Message('A', Bytes().U8(multi_id).U16(msg_id).Str(topic).data());
  }
  ULogWriter& Data(std::uint16_t msg_id, const Bytes& data) {
    return Message('D', Bytes().U16(msg_id).Str(data.data()).data());
  }
  ULogWriter& Logged(char level, std::uint64_t t_us, const std::string& text) {
    return Message('L', Bytes().U8(static_cast<std::uint8_t>(level)).U64(t_us).Str(text).data());
  }
  ULogWriter& Tagged(char level, std::uint16_t tag, std::uint64_t t_us, const std::string& text) {
    return Message(
        'C', Bytes().U8(static_cast<std::uint8_t>(level)).U16(tag).U64(t_us).Str(text).data());
  }
  ULogWriter& Dropout(std::uint16_t ms) { return Message('O', Bytes().U16(ms).data()); }
  /// Appends raw bytes (e.g. the first part of a message cut by power loss).
  ULogWriter& Raw(const std::string& bytes) {
    bytes_.Str(bytes);
    return *this;
  }

  /// Writes the file under the test temp folder; returns its path.
  std::string Save(const std::string& name) const {
    const std::string path = testing::TempFilePath(name);
    std::ofstream out(path, std::ios::binary);
    out << bytes_.data();
    return path;
  }

 private:
  Bytes bytes_;
};

}  // namespace navtwin::ulog_writer
