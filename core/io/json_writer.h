// A minimal streaming JSON writer for the one-object outputs of `--format=json` and for
// summary files: objects, arrays, strings (escaped), numbers (non-finite -> null), bools.
#pragma once

#include <ostream>
#include <string>
#include <vector>

namespace navtwin {

class JsonWriter {
 public:
  explicit JsonWriter(std::ostream& out) : out_(out) {}

  JsonWriter& BeginObject();
  JsonWriter& EndObject();
  JsonWriter& BeginArray();
  JsonWriter& EndArray();
  /// The key of the next value inside an object.
  JsonWriter& Key(const std::string& key);
  JsonWriter& Value(const std::string& s);
  JsonWriter& Value(const char* s) { return Value(std::string(s)); }
  JsonWriter& Value(double x);
  JsonWriter& Value(long long x);
  JsonWriter& Value(int x) { return Value(static_cast<long long>(x)); }
  JsonWriter& Value(std::size_t x) { return Value(static_cast<long long>(x)); }
  JsonWriter& Value(bool b);

  template <typename T>
  JsonWriter& Field(const std::string& key, const T& value) {
    Key(key);
    return Value(value);
  }

 private:
  void Separator();
  std::ostream& out_;
  std::vector<bool> first_in_scope_;  // one entry per open object/array
  bool after_key_ = false;
};

std::string JsonEscape(const std::string& s);

}  // namespace navtwin
