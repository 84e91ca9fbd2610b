// Fuzz target: the IMU calibration file (core/calibration_file.h).
#include <cstddef>
#include <cstdint>

#include "core/calibration_file.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const navtwin::fuzz::FuzzFile file(data, size, "calibration.yaml");
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::ReadCalibrationFile(file.path()); });
  return 0;
}
