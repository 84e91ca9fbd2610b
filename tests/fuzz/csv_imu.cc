// Fuzz target: the navtwin CSV IMU reader (core/io/csv_imu.h).
#include <cstddef>
#include <cstdint>

#include "core/io/csv_imu.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const navtwin::fuzz::FuzzFile file(data, size, "imu.csv");
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenCsvImu(file.path())); });
  return 0;
}
