// Fuzz target: the ULog readers: every stream, PX4's own estimate and the summary
// (core/io/ulog.h).
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/io/ulog.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const navtwin::fuzz::FuzzFile file(data, size, "log.ulg");
  const std::string& path = file.path();
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenULogImu(path)); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenULogGnss(path)); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenULogMag(path)); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenULogBaro(path)); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenULogPx4Estimate(path)); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::DescribeULog(path); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::ListULogSubscriptions(path); });
  return 0;
}
