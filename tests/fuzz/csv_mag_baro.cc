// Fuzz target: the navtwin CSV magnetometer and barometer readers (core/io/csv_mag_baro.h).
#include <cstddef>
#include <cstdint>

#include "core/io/csv_mag_baro.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const navtwin::fuzz::FuzzFile file(data, size, "mag_baro.csv");
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenCsvMag(file.path())); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenCsvBaro(file.path())); });
  return 0;
}
