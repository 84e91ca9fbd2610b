// The IMU record of a run, held in memory or streamed from its file. A streamed record
// keeps only its head (the samples an initialisation asked for with Head) and reads the
// file again on every pass (Read): memory independent of the record's length. What a
// streamed record cannot know before a pass has reached its end (its last sample, its
// length, the gaps bridged) is available once one has.
#pragma once

#include <cstddef>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "core/io/sample_reader.h"

namespace navtwin::ins {

class ImuRecord {
 public:
  /// A reader of the whole record from its first sample; it adds the gaps it bridges to
  /// *bridged (which the record sets to 0 before each pass).
  using Opener = std::function<std::unique_ptr<ImuReader>(std::size_t* bridged)>;

  /// An empty record in memory.
  ImuRecord();
  /// Every sample in memory; `bridged_gaps` were bridged while reading them.
  explicit ImuRecord(std::vector<ImuSample> samples, std::size_t bridged_gaps = 0);
  /// Streamed: nothing is read until Head or Read asks.
  static ImuRecord Streamed(Opener open);

  bool streamed() const;

  /// At least the samples up to and including the first one at or after t_s (all of them
  /// when the record ends before): every sample in memory; streamed, read on demand and kept.
  const std::vector<ImuSample>& Head(double t_s) const;
  /// A reader of every sample from the first (a streamed record reads its file again,
  /// except on the first pass, which goes on from the head already read). The record must
  /// outlive the reader.
  std::unique_ptr<ImuReader> Read() const;

  bool empty() const;
  const ImuSample& front() const;
  /// Start of the first sample's interval.
  double begin_s() const;
  /// True in memory, and for a streamed record once a pass has reached its end.
  bool end_known() const;
  /// The last sample's time, or +infinity while end_known() is false.
  double known_end_s() const;
  /// The last sample (std::logic_error while end_known() is false).
  const ImuSample& back() const;
  /// The number of samples (std::logic_error while end_known() is false).
  std::size_t size() const;
  /// The gaps bridged (std::logic_error while end_known() is false).
  std::size_t bridged_gaps() const;

  /// In memory only (std::logic_error when streamed).
  const std::vector<ImuSample>& samples() const;
  void push_back(const ImuSample& s);
  const ImuSample& operator[](std::size_t k) const { return samples()[k]; }
  std::vector<ImuSample>::const_iterator begin() const { return samples().begin(); }
  std::vector<ImuSample>::const_iterator end() const { return samples().end(); }

 private:
  struct Stream;
  class PassReader;
  std::vector<ImuSample> samples_;  ///< in memory
  std::size_t bridged_gaps_ = 0;    ///< in memory
  std::shared_ptr<Stream> stream_;  ///< streamed (head, reader, what the passes found); shared by copies
};

}  // namespace navtwin::ins
