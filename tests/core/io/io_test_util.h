// Helpers shared by the file-reader tests: temporary files named after the running test,
// checks of InputError messages, and reading every sample of a reader.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <fstream>
#include <initializer_list>
#include <string>
#include <vector>

#include "core/io/input_error.h"
#include "core/io/sample_reader.h"

namespace navtwin::testing {

/// "<suite>_<test>" of the running test ('/' of parameterised names replaced by '_'), so
/// that temporary names never collide between tests. Call only from inside a test.
inline std::string CurrentTestName() {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "_" + info->name();
  std::replace(name.begin(), name.end(), '/', '_');
  return name;
}

/// A path under the test temp folder for a file called `name`, unique to the running test.
inline std::string TempFilePath(const std::string& name) {
  return ::testing::TempDir() + "navtwin_" + CurrentTestName() + "_" + name;
}

/// Writes `text` to `path` byte for byte (binary: no newline translation); returns `path`.
inline std::string WriteFile(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

/// Writes `text` to TempFilePath(name); returns that path.
inline std::string WriteTempFile(const std::string& name, const std::string& text) {
  return WriteFile(TempFilePath(name), text);
}

/// A new empty folder under the test temp folder (for tests where the file names matter,
/// e.g. format detection by name or files read beside each other); returns its path.
inline std::string MakeTempDir() {
  std::string pattern = ::testing::TempDir() + "navtwin_" + CurrentTestName() + "_XXXXXX";
  if (mkdtemp(pattern.data()) == nullptr) ADD_FAILURE() << "mkdtemp failed for " << pattern;
  return pattern;
}

/// Runs f, which must throw InputError whose message contains every one of `parts`.
template <typename F>
void ExpectInputError(F f, std::initializer_list<std::string> parts) {
  try {
    f();
  } catch (const InputError& e) {
    for (const std::string& p : parts) {
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what() << " lacks: " << p;
    }
    return;
  }
  ADD_FAILURE() << "no InputError";
}

/// Every remaining sample of `reader`, in order (InputError from the reader propagates).
template <typename Sample>
std::vector<Sample> ReadAllSamples(SampleReader<Sample>& reader) {
  std::vector<Sample> out;
  Sample s;
  while (reader.Next(&s)) out.push_back(s);
  return out;
}

}  // namespace navtwin::testing
