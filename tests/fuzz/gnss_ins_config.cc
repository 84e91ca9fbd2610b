// Fuzz target: the GNSS/INS YAML configuration, navtwin's own and KF-GINS'
// (problems/gnss_ins/config.h).
#include <cstddef>
#include <cstdint>

#include "problems/gnss_ins/config.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const navtwin::fuzz::FuzzFile file(data, size, "config.yaml");
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::gnss_ins::LoadGnssInsConfig(file.path()); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::gnss_ins::LoadGnssInsConfig(file.path(), true); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::gnss_ins::LoadKfginsConfig(file.path()); });
  return 0;
}
