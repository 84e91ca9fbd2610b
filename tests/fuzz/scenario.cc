// Fuzz target: the simulation scenario (core/sim/scenario.h).
#include <cstddef>
#include <cstdint>

#include "core/sim/scenario.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const navtwin::fuzz::FuzzFile file(data, size, "scenario.yaml");
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::sim::LoadScenario(file.path()); });
  return 0;
}
