// Where the real recorded data live, and the rule for tests that need them:
// they fail (not skip) when the CI variable is set and the data are missing.
#pragma once

#include <cstdlib>
#include <string>
#include <sys/stat.h>

#include <gtest/gtest.h>

namespace navtwin::testing {

/// $NAVTWIN_DATA, else ../shared/data beside the project (set at configure time).
inline std::string DataDir() {
  const char* env = std::getenv("NAVTWIN_DATA");
  if (env != nullptr && env[0] != '\0') return env;
  return NAVTWIN_DEFAULT_DATA_DIR;
}

inline std::string DataPath(const std::string& relative) { return DataDir() + "/" + relative; }

inline bool FileExists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

inline bool InCi() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && ci[0] != '\0' && std::string(ci) != "0" && std::string(ci) != "false";
}

}  // namespace navtwin::testing

/// Use at the top of a test: skips when the file is absent on a developer machine,
/// fails when CI is set.
#define NAVTWIN_REQUIRE_DATA(path)                                                   \
  do {                                                                               \
    if (!::navtwin::testing::FileExists(path)) {                                     \
      if (::navtwin::testing::InCi()) {                                              \
        FAIL() << "real data missing in CI: " << (path)                              \
               << " (set NAVTWIN_DATA or put shared/ beside the project)";           \
      }                                                                              \
      GTEST_SKIP() << "real data not found: " << (path);                             \
    }                                                                                \
  } while (0)
