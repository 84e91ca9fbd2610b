#include "core/io/ulog_topic.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include "core/units.h"

namespace navtwin::ulog {
namespace {

// PX4's marker for "no sample" in *_timestamp_relative fields (INT32_MAX).
constexpr double kRelativeTimestampInvalid = 2147483647.0;

}  // namespace

std::string FormatNumber(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

bool SubscriptionHasField(const ULogSubscription& sub, const std::string& field) {
  for (const ULogField& f : sub.fields) {
    if (f.name == field) return true;
  }
  return false;
}

const ULogSubscription* FindSubscription(const std::vector<ULogSubscription>& subs,
                                         const Candidate& candidate) {
  for (const ULogSubscription& sub : subs) {
    if (sub.topic == candidate.topic && sub.multi_id == 0 &&
        SubscriptionHasField(sub, candidate.needed_field)) {
      return &sub;
    }
  }
  return nullptr;
}

Candidate ChooseTopic(const std::string& path, const std::vector<Candidate>& candidates,
                      const std::string& what) {
  const std::vector<ULogSubscription> subs = ListULogSubscriptions(path);
  std::string names;
  for (const Candidate& c : candidates) {
    if (FindSubscription(subs, c) != nullptr) return c;
    names += (names.empty() ? "" : " or ") + std::string(c.topic) + "." + c.needed_field;
  }
  throw InputError(path, 0, what, "no " + names + " in this log");
}

std::vector<Candidate> GnssCandidates() {
  return {{"vehicle_gps_position", "fix_type", ""}, {"sensor_gps", "fix_type", ""}};
}

GnssFields GnssFieldsOf(const ULogSubscription& sub) {
  const bool new_names = SubscriptionHasField(sub, "latitude_deg");
  GnssFields f;
  f.lat = new_names ? "latitude_deg" : "lat";
  f.lon = new_names ? "longitude_deg" : "lon";
  f.deg_per_unit = new_names ? 1.0 : 1e-7;
  f.m_per_unit = new_names ? 1.0 : 1e-3;
  const std::string ellipsoid = new_names ? "altitude_ellipsoid_m" : "alt_ellipsoid";
  f.ellipsoid = SubscriptionHasField(sub, ellipsoid);
  f.height = f.ellipsoid ? ellipsoid : (new_names ? "altitude_msl_m" : "alt");
  return f;
}

// ---------------------------------------------------------------------------------------
TimeOrderedTopic::TimeOrderedTopic(const std::string& path, const Candidate& source,
                                   const ULogClock& clock, SampleTime sample_time)
    : log_(path),
      topic_(source.topic),
      relative_field_(source.relative_time_field),
      sample_time_(sample_time),
      clock_(clock) {}

// The current message's time in microseconds since boot; -1 for "no sample".
std::int64_t TimeOrderedTopic::RawTime_us() const {
  std::int64_t t_us = static_cast<std::int64_t>(log_.timestamp_us());
  if (sample_time_ == SampleTime::kTimestampSample && log_.HasField("timestamp_sample")) {
    const double sample_us = log_.GetDouble("timestamp_sample");
    if (sample_us > 0.0) t_us = static_cast<std::int64_t>(sample_us);
  }
  if (!relative_field_.empty()) {
    const double relative_us = log_.GetDouble(relative_field_);
    if (relative_us == kRelativeTimestampInvalid) return -1;  // no new sample of this sensor
    t_us += static_cast<std::int64_t>(relative_us);
  }
  return t_us;
}

bool TimeOrderedTopic::Next() {
  while (log_.NextOf(topic_)) {
    const std::int64_t t_us = RawTime_us();
    if (t_us < 0) continue;
    if (has_time_ && t_us == time_us_) continue;
    if (has_time_ && t_us < time_us_) {
      const std::string field = !relative_field_.empty() ? relative_field_
                                : sample_time_ == SampleTime::kTimestampSample &&
                                        log_.HasField("timestamp_sample")
                                    ? "timestamp_sample"
                                    : "timestamp";
      throw ErrorAt(field, "time goes backwards: " + std::to_string(t_us) + " us after " +
                               std::to_string(time_us_) + " us");
    }
    has_previous_ = has_time_;
    previous_us_ = time_us_;
    time_us_ = t_us;
    has_time_ = true;
    return true;
  }
  return false;
}

double TimeOrderedTopic::dt_s() const {
  return static_cast<double>(time_us_ - previous_us_) * kMicrosecond_s;
}

InputError TimeOrderedTopic::ErrorAt(const std::string& field, const std::string& reason) const {
  return InputError::AtByte(log_.path(), log_.byte_offset(), topic_ + "." + field, reason);
}

double TimeOrderedTopic::Finite(const std::string& field, int index) const {
  const double v = index < 0 ? log_.GetDouble(field) : log_.GetArray(field, index);
  if (!std::isfinite(v)) throw ErrorAt(field, "not finite");
  return v;
}

double TimeOrderedTopic::FiniteOrNaN(const std::string& field) const {
  return log_.HasField(field) ? Finite(field) : std::numeric_limits<double>::quiet_NaN();
}

Eigen::Vector3d TimeOrderedTopic::Vector(const std::string& field) const {
  return {Finite(field, 0), Finite(field, 1), Finite(field, 2)};
}

double TimeOrderedTopic::Sigma(const std::string& field) const {
  const double v = Finite(field);
  if (v <= 0.0) throw ErrorAt(field, "standard deviation must be positive, got " + FormatNumber(v));
  return v;
}

}  // namespace navtwin::ulog
