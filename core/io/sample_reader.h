// Streaming sample readers: one sample at a time, never the whole file in memory.
// Every reader validates as it goes and throws InputError (file, line or byte, field).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/types.h"

namespace navtwin {

template <typename Sample>
class SampleReader {
 public:
  virtual ~SampleReader() = default;
  /// Fills *sample with the next sample and returns true, or returns false at the end.
  /// Throws InputError on bad input; times are checked to increase strictly.
  virtual bool Next(Sample* sample) = 0;
  /// The file being read (for messages).
  virtual const std::string& path() const = 0;
};

/// Every remaining sample of a reader, in order (the reader's checks apply): for records
/// that fit in memory.
template <typename Sample>
std::vector<Sample> ReadAll(SampleReader<Sample>& reader) {
  std::vector<Sample> out;
  Sample s;
  while (reader.Next(&s)) out.push_back(s);
  return out;
}

using ImuReader = SampleReader<ImuSample>;
using GnssReader = SampleReader<GnssSample>;
using MagReader = SampleReader<MagSample>;
using BaroReader = SampleReader<BaroSample>;
using NavReader = SampleReader<NavState>;

}  // namespace navtwin
