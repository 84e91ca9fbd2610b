#include "core/io/json_writer.h"

#include <limits>
#include <sstream>

#include <gtest/gtest.h>

namespace navtwin {
namespace core_json_writer_test {

TEST(JsonWriter, NestedObjectsArraysAndEscapes) {
  std::ostringstream out;
  JsonWriter w(out);
  w.BeginObject().Field("name", "a\"b\\c\n").Field("n", 3).Field("x", 0.25);
  w.Key("list").BeginArray().Value(1).Value(std::numeric_limits<double>::quiet_NaN()).EndArray();
  w.Key("inner").BeginObject().Field("ok", true).EndObject();
  w.EndObject();
  EXPECT_EQ(out.str(),
            R"({"name":"a\"b\\c\n","n":3,"x":0.25,"list":[1,null],"inner":{"ok":true}})");
}

}  // namespace core_json_writer_test
}  // namespace navtwin
