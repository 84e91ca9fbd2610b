// IMU time gaps, shared by every command that integrates an IMU record: an interval longer
// than kGapFactor nominal intervals is a gap; gaps up to a limit are bridged by spreading
// the increments of the sample after the gap evenly over round(dt / nominal) intervals (the
// time tags say the increments cover the whole gap: an IMU that accumulates while its output
// is dropped; for an IMU that lost the samples instead, the lost increments are an error that
// short gaps keep small). Longer gaps are an InputError naming the file and the time.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "core/io/sample_reader.h"

namespace navtwin::ins {

/// An interval longer than this many nominal intervals is a gap.
constexpr double kGapFactor = 1.5;

/// Median of the sample intervals (the nominal interval; robust to gaps and jitter).
/// `imu` must not be empty.
double MedianInterval(const std::vector<ImuSample>& imu);

/// Bridges the gaps of a stream of samples one sample at a time.
class ImuGapBridge {
 public:
  /// `path`: the file (for messages); `nominal_s`: the nominal interval; `max_gap_s`: the
  /// longest gap bridged; `time_offset_s`: what was added to the file's time tags (messages
  /// give file time); `limit_name`: the setting that sets max_gap_s (for messages).
  ImuGapBridge(std::string path, double nominal_s, double max_gap_s, double time_offset_s,
               std::string limit_name);
  /// Appends `s`, or the pieces that bridge the gap it closes, to *out; InputError for a
  /// gap longer than max_gap_s.
  void Add(const ImuSample& s, std::vector<ImuSample>* out);
  std::size_t bridged() const { return bridged_; }
  double nominal_s() const { return nominal_s_; }

 private:
  std::string path_;
  double nominal_s_;
  double max_gap_s_;
  double time_offset_s_;
  std::string limit_name_;
  std::size_t bridged_ = 0;
};

/// A reader that bridges the gaps of `reader` while streaming: the nominal interval is the
/// median of the first kGapLookahead samples. `time_offset_s`: what was added to the file's
/// time tags (messages give file time). When `bridged` is not null, *bridged holds the
/// number of gaps bridged so far.
constexpr std::size_t kGapLookahead = 1000;
std::unique_ptr<ImuReader> GapBridgingImuReader(std::unique_ptr<ImuReader> reader, double max_gap_s,
                                                const std::string& limit_name, double time_offset_s = 0.0,
                                                std::size_t* bridged = nullptr);

}  // namespace navtwin::ins
