// Fuzz target: the one-value CSV series reader (core/io/csv_series.h), with a
// single column (the pendulum encoder's theta) and with alternatives (the odometer's).
#include <cstddef>
#include <cstdint>

#include "core/io/csv_series.h"
#include "core/units.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const navtwin::fuzz::FuzzFile file(data, size, "series.csv");
  navtwin::fuzz::ReadOrRefuse([&] {
    navtwin::ReadScalarSeriesCsv(file.path(), "theta", {{"_rad", 1.0}, {"_deg", navtwin::kDegToRad}});
  });
  navtwin::fuzz::ReadOrRefuse([&] {
    navtwin::ReadScalarSeriesCsv(file.path(), {navtwin::SeriesColumn{"speed", {{"_mps", 1.0}}},
                                               navtwin::SeriesColumn{"distance", {{"_m", 1.0}}}},
                                 0.0);
  });
  return 0;
}
