// The test programs' main. Every run of a test program gets its own temporary folder
// under $TEST_TMPDIR (or /tmp), made here and exported as TEST_TMPDIR, so that
// ::testing::TempDir() in any test names a folder no other run shares: two ctest runs in
// one build folder, or `ctest -j --repeat`, never write to the same path. The folder is
// removed when every test passed and kept (and named on stderr) when one failed.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  std::string pattern = ::testing::TempDir() + "run_XXXXXX";
  if (::mkdtemp(pattern.data()) == nullptr) {
    std::fprintf(stderr, "navtwin tests: cannot make a temporary folder %s\n", pattern.c_str());
    return 1;
  }
  ::setenv("TEST_TMPDIR", pattern.c_str(), 1);
  const int result = RUN_ALL_TESTS();
  if (result == 0) {
    std::error_code ignored;
    std::filesystem::remove_all(pattern, ignored);
  } else {
    std::fprintf(stderr, "navtwin tests: the failed run's files are kept in %s\n", pattern.c_str());
  }
  return result;
}
