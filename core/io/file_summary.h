// What a file holds, for `navtwin info`: its kind and, per stream (an IMU, a ULog
// topic, a GNSS solution), the sample count, time span, rate, gaps and fields.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace navtwin {

/// Streaming statistics of one time series' time tags (keeps the intervals as floats
/// to take a median: 4 bytes a sample, not the file).
class TimeTagStats {
 public:
  void Add(double t_s);
  std::size_t count() const { return count_; }
  double first_s() const { return first_s_; }
  double last_s() const { return last_s_; }
  double span_s() const { return count_ > 1 ? last_s_ - first_s_ : 0.0; }
  /// Median sample interval (0 with fewer than two samples).
  double median_dt_s() const;
  /// 1 / median interval (0 with fewer than two samples).
  double rate_hz() const;
  /// (count - 1) / span (0 with fewer than two samples or a zero span).
  double mean_rate_hz() const;
  /// Intervals longer than gap_factor times the median.
  std::size_t gap_count(double gap_factor = 2.0) const;
  double max_dt_s() const;

 private:
  std::size_t count_ = 0;
  double first_s_ = 0.0;
  double last_s_ = 0.0;
  std::vector<float> dt_s_;
};

struct StreamSummary {
  std::string name;                 ///< e.g. "imu", "gnss", "sensor_combined"
  std::size_t count = 0;
  double t_first_s = 0.0;
  double t_last_s = 0.0;
  double rate_hz = 0.0;             ///< from the median interval (the nominal rate)
  double mean_rate_hz = 0.0;        ///< (count - 1) / span: lower than rate_hz when samples drop
  std::size_t gaps = 0;             ///< intervals > 2x the median
  double max_gap_s = 0.0;           ///< longest interval
  std::vector<std::string> fields;  ///< columns or message fields, with units where known

  static StreamSummary FromStats(const std::string& name, const TimeTagStats& stats,
                                 std::vector<std::string> fields);
};

struct FileSummary {
  std::string path;
  std::string kind;                 ///< format name, e.g. "kfgins-imu", "ulog", "rtklib-pos"
  std::vector<StreamSummary> streams;
  std::vector<std::string> notes;   ///< anything else worth saying (e.g. ULog dropouts)
};

}  // namespace navtwin
