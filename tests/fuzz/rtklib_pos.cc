// Fuzz target: the RTKLIB .pos reader and its summary (core/io/rtklib_pos.h).
#include <cstddef>
#include <cstdint>

#include "core/io/rtklib_pos.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const navtwin::fuzz::FuzzFile file(data, size, "rtklib.pos");
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenRtklibPos(file.path())); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::DescribeRtklibPos(file.path()); });
  return 0;
}
