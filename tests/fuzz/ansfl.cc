// Fuzz target: the ANSFL readers: IMU_k.csv, raw Xsens DOT files (IMU and magnetometer),
// GT.csv and GTExtended.csv (core/io/ansfl.h).
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/io/ansfl.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const navtwin::fuzz::FuzzFile file(data, size, "ansfl.csv");
  const std::string& path = file.path();
  navtwin::AnsflGtOptions gt_options;
  gt_options.origin = navtwin::AnsflSiteOrigin();  // no GTExtended.csv is looked up beside the file
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenAnsflImu(path)); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenAnsflDotRawImu(path)); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenAnsflDotRawMag(path)); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenAnsflGt(path, gt_options)); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::fuzz::Drain(*navtwin::OpenAnsflGtExtended(path)); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::DescribeAnsflImu(path); });
  navtwin::fuzz::ReadOrRefuse([&] { navtwin::DescribeAnsflDotRaw(path); });
  return 0;
}
