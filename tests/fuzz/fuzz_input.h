// Shared pieces of the fuzz targets: the input bytes as a temporary file (the readers take
// paths), a reader drained to its end, and the refusals a reader is allowed to make.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/io/input_error.h"
#include "core/io/sample_reader.h"

namespace navtwin::fuzz {

/// The bytes written to "<dir>/navtwin-fuzz-<pid>-<name>" (dir: $TEST_TMPDIR, else /tmp),
/// one path per process and target, so that concurrent runs never share a file. The file,
/// and a companion written with WriteCompanion, are removed on destruction.
class FuzzFile {
 public:
  FuzzFile(const std::uint8_t* data, std::size_t size, const std::string& name);
  ~FuzzFile();
  FuzzFile(const FuzzFile&) = delete;
  FuzzFile& operator=(const FuzzFile&) = delete;

  const std::string& path() const { return path_; }
  /// Writes "<path><suffix>" (e.g. the ".tag" beside an rtklib-walk IMU file).
  void WriteCompanion(const std::string& suffix, const std::uint8_t* data, std::size_t size);

 private:
  std::string path_;
  std::string companion_;
};

/// Every sample of a reader, discarded: the reader's checks run to the end of the file.
template <typename Sample>
std::size_t Drain(SampleReader<Sample>& reader) {
  std::size_t count = 0;
  Sample sample;
  while (reader.Next(&sample)) ++count;
  return count;
}

/// Runs `read`; a refusal of the input (InputError, std::runtime_error, std::invalid_argument)
/// is an expected outcome and is swallowed. Anything else propagates and is a finding.
template <typename Read>
void ReadOrRefuse(Read&& read) {
  try {
    read();
  } catch (const InputError&) {
  } catch (const std::runtime_error&) {
  } catch (const std::invalid_argument&) {
  }
}

}  // namespace navtwin::fuzz
