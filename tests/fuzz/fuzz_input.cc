#include "tests/fuzz/fuzz_input.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

namespace navtwin::fuzz {

namespace fuzz_input {

std::string TempDir() {
  const char* dir = std::getenv("TEST_TMPDIR");
  return dir != nullptr && *dir != '\0' ? std::string(dir) : std::string("/tmp");
}

void WriteBytes(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) {
    // Not a finding about the reader: the harness itself cannot run.
    std::fprintf(stderr, "fuzz harness: cannot write %s\n", path.c_str());
    std::abort();
  }
}

}  // namespace fuzz_input

FuzzFile::FuzzFile(const std::uint8_t* data, std::size_t size, const std::string& name)
    : path_(fuzz_input::TempDir() + "/navtwin-fuzz-" + std::to_string(getpid()) + "-" + name) {
  fuzz_input::WriteBytes(path_, data, size);
}

FuzzFile::~FuzzFile() {
  std::remove(path_.c_str());
  if (!companion_.empty()) std::remove(companion_.c_str());
}

void FuzzFile::WriteCompanion(const std::string& suffix, const std::uint8_t* data, std::size_t size) {
  companion_ = path_ + suffix;
  fuzz_input::WriteBytes(companion_, data, size);
}

}  // namespace navtwin::fuzz
