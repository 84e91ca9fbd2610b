// Fuzz target: format detection and the summary of a file of any kind (core/io/open.h).
#include <cstddef>
#include <cstdint>

#include "core/io/open.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const navtwin::fuzz::FuzzFile file(data, size, "input.txt");
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::FormatName(navtwin::DetectFormat(file.path())); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::DescribeFile(file.path()); });
  return 0;
}
