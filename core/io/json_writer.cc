#include "core/io/json_writer.h"

#include <cmath>
#include <cstdio>

namespace navtwin {

std::string JsonEscape(const std::string& s) {
  std::string r;
  r.reserve(s.size() + 2);
  for (const char c : s) {
    switch (c) {
      case '"': r += "\\\""; break;
      case '\\': r += "\\\\"; break;
      case '\n': r += "\\n"; break;
      case '\r': r += "\\r"; break;
      case '\t': r += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
          r += buf;
        } else {
          r += c;
        }
    }
  }
  return r;
}

void JsonWriter::Separator() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (!first_in_scope_.empty()) {
    if (!first_in_scope_.back()) out_ << ',';
    first_in_scope_.back() = false;
  }
}

JsonWriter& JsonWriter::BeginObject() {
  Separator();
  out_ << '{';
  first_in_scope_.push_back(true);
  return *this;
}

JsonWriter& JsonWriter::EndObject() {
  first_in_scope_.pop_back();
  out_ << '}';
  return *this;
}

JsonWriter& JsonWriter::BeginArray() {
  Separator();
  out_ << '[';
  first_in_scope_.push_back(true);
  return *this;
}

JsonWriter& JsonWriter::EndArray() {
  first_in_scope_.pop_back();
  out_ << ']';
  return *this;
}

JsonWriter& JsonWriter::Key(const std::string& key) {
  Separator();
  out_ << '"' << JsonEscape(key) << "\":";
  after_key_ = true;
  return *this;
}

JsonWriter& JsonWriter::Value(const std::string& s) {
  Separator();
  out_ << '"' << JsonEscape(s) << '"';
  return *this;
}

JsonWriter& JsonWriter::Value(double x) {
  Separator();
  if (!std::isfinite(x)) {
    out_ << "null";
  } else {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", x);
    out_ << buf;
  }
  return *this;
}

JsonWriter& JsonWriter::Value(long long x) {
  Separator();
  out_ << x;
  return *this;
}

JsonWriter& JsonWriter::Value(bool b) {
  Separator();
  out_ << (b ? "true" : "false");
  return *this;
}

}  // namespace navtwin
