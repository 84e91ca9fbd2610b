// Internal pieces of the typed ULog readers (ulog_readers.cc, ulog_estimate.cc,
// ulog_time.cc): choosing a topic among candidates, walking one topic instance in time
// order, the GNSS topic's field names. Not meant for other callers; the public API is
// core/io/ulog.h and core/io/ulog_time.h.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/io/input_error.h"
#include "core/io/ulog.h"
#include "core/io/ulog_time.h"

namespace navtwin::ulog {

/// A topic a typed reader can take its samples from, in order of preference.
struct Candidate {
  const char* topic;
  const char* needed_field;         ///< the candidate counts only if it has this field
  const char* relative_time_field;  ///< "" or a *_timestamp_relative field (old sensor_combined)
};

bool SubscriptionHasField(const ULogSubscription& sub, const std::string& field);

/// The subscription (instance 0) that matches a candidate, or nullptr.
const ULogSubscription* FindSubscription(const std::vector<ULogSubscription>& subs,
                                         const Candidate& candidate);

/// The first candidate subscribed in the file; InputError (field `what`) if none is.
Candidate ChooseTopic(const std::string& path, const std::vector<Candidate>& candidates,
                      const std::string& what);

/// The GNSS topics, in order of preference (vehicle_gps_position, sensor_gps).
std::vector<Candidate> GnssCandidates();

/// Position field names and scales of a GNSS topic: new float names (deg, m) or old
/// integer names (1e-7 deg, mm). Height: the ellipsoid field when logged, else MSL.
struct GnssFields {
  std::string lat, lon, height;
  double deg_per_unit = 1.0;
  double m_per_unit = 1.0;
  bool ellipsoid = true;
};
GnssFields GnssFieldsOf(const ULogSubscription& sub);

/// Where a topic's sample time comes from.
enum class SampleTime {
  kTimestamp,        ///< `timestamp` (+ the candidate's relative field, if any)
  kTimestampSample,  ///< `timestamp_sample` where the format has it and it is not 0 (the
                     ///< time the data refer to, e.g. the IMU sample of an estimate), else
                     ///< `timestamp`
};

/// One topic instance in time order. Repeated times are skipped (real logs repeat a
/// sample now and then); a time that goes backwards is an InputError at its byte offset.
/// t_s() maps the boot time through the log's clock (GPS seconds of week, or boot time).
class TimeOrderedTopic {
 public:
  TimeOrderedTopic(const std::string& path, const Candidate& source, const ULogClock& clock,
                   SampleTime sample_time = SampleTime::kTimestamp);

  bool Next();

  const ULogFile& log() const { return log_; }
  const std::string& topic() const { return topic_; }
  const ULogClock& clock() const { return clock_; }
  std::int64_t time_us() const { return time_us_; }  ///< boot time of the current sample
  double t_s() const { return clock_.Seconds(static_cast<std::uint64_t>(time_us_)); }
  bool has_previous() const { return has_previous_; }
  double dt_s() const;  ///< from the previous sample's boot time

  /// A finite field value; InputError naming the field otherwise.
  double Finite(const std::string& field, int index = -1) const;
  /// As Finite(), NaN when the format has no such field.
  double FiniteOrNaN(const std::string& field) const;
  Eigen::Vector3d Vector(const std::string& field) const;
  /// A standard deviation, which must be positive and finite.
  double Sigma(const std::string& field) const;
  /// An InputError at the current message, naming topic.field.
  InputError ErrorAt(const std::string& field, const std::string& reason) const;

 private:
  std::int64_t RawTime_us() const;

  ULogFile log_;
  std::string topic_;
  std::string relative_field_;
  SampleTime sample_time_;
  ULogClock clock_;
  bool has_time_ = false;
  bool has_previous_ = false;
  std::int64_t time_us_ = 0;
  std::int64_t previous_us_ = 0;
};

/// "%.9g" of a number, for messages.
std::string FormatNumber(double v);

}  // namespace navtwin::ulog
