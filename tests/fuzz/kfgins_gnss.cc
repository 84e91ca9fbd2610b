// Fuzz target: the KF-GINS GNSS reader (core/io/kfgins.h).
#include <cstddef>
#include <cstdint>

#include "core/io/kfgins.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const navtwin::fuzz::FuzzFile file(data, size, "kfgins_gnss.txt");
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenKfginsGnss(file.path())); });
  return 0;
}
