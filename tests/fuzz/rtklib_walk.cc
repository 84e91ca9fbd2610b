// Fuzz target: the rtklib-walk IMU readers (core/io/rtklib_walk.h). The input is split at
// the first "TIMETAG" (the tag file's own magic): the bytes before it are the raw IMU file,
// the rest is "<file>.tag" beside it; without "TIMETAG" there is no tag file. The converted
// (_sf) reader gets the whole input.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "core/io/rtklib_walk.h"
#include "tests/fuzz/fuzz_input.h"

namespace rtklib_walk_fuzz {

std::size_t TagStart(const std::uint8_t* data, std::size_t size) {
  static constexpr char kMagic[] = "TIMETAG";
  const std::uint8_t* end = data + size;
  return static_cast<std::size_t>(std::search(data, end, kMagic, kMagic + std::strlen(kMagic)) - data);
}

}  // namespace rtklib_walk_fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::size_t tag = rtklib_walk_fuzz::TagStart(data, size);
  navtwin::fuzz::FuzzFile file(data, tag, "imu.csv");
  if (tag < size) file.WriteCompanion(".tag", data + tag, size - tag);
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::FitRtklibWalkClock(file.path()); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenRtklibWalkImu(file.path())); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::DescribeRtklibWalkImu(file.path()); });

  const navtwin::fuzz::FuzzFile whole(data, size, "imu_sf.csv");
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenRtklibWalkImuSf(whole.path())); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::DescribeRtklibWalkImuSf(whole.path()); });
  return 0;
}
