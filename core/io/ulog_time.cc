#include "core/io/ulog_time.h"

#include <algorithm>
#include <cstdio>
#include <vector>

#include "core/gps_time.h"
#include "core/io/ulog.h"
#include "core/io/ulog_topic.h"
#include "core/units.h"

namespace navtwin {
namespace {

constexpr std::int64_t kWeek_us = 604800LL * 1000000LL;
constexpr std::int64_t kUs_per_s = 1000000;
// A fix whose receiver has solved its clock: PX4 fix_type 2 (2D) and up.
constexpr double kMinTimeFixType = 2;

std::int64_t FloorDivideWeeks(std::int64_t a_us) {
  return a_us / kWeek_us - (a_us % kWeek_us < 0 ? 1 : 0);
}

/// The median of the offsets (the upper middle one for an even count: a sample's own
/// offset, so integer microseconds).
std::int64_t MedianOffset(std::vector<std::int64_t> offsets) {
  const auto middle = offsets.begin() + static_cast<std::ptrdiff_t>(offsets.size() / 2);
  std::nth_element(offsets.begin(), middle, offsets.end());
  return *middle;
}

std::string ClockFixed(double v, int decimals) {
  char text[48];
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  return text;
}

}  // namespace

double ULogClock::Seconds(std::uint64_t boot_us) const {
  return static_cast<double>(static_cast<std::int64_t>(boot_us) + shift_us) * kMicrosecond_s;
}

double ULogClock::SecondsOfWeek(std::int64_t gps_us) const {
  return static_cast<double>(gps_us - static_cast<std::int64_t>(gps_week) * kWeek_us) *
         kMicrosecond_s;
}

std::string ULogClock::Describe() const {
  if (!gps) {
    return "no GNSS fix with a valid UTC time (vehicle_gps_position/sensor_gps time_utc_usec): "
           "times stay seconds since boot, GPS week unknown";
  }
  std::string text = "boot time -> GPS week " + std::to_string(gps_week) +
                     " seconds of week: + " + ClockFixed(static_cast<double>(shift_us) * 1e-6, 6) +
                     " s (median over " + std::to_string(fixes) + " fixes of " + source +
                     " + " + std::to_string(leap_s) + " leap s - timestamp; per-fix spread " +
                     ClockFixed(jitter_min_s * 1e3, 1) + " .. +" + ClockFixed(jitter_max_s * 1e3, 1) +
                     " ms); GNSS fixes at their own UTC";
  if (gps_delay_param_s >= 0.0) {
    text += "; boot-time streams are early by the GNSS output latency (PX4 assumed " +
            ClockFixed(gps_delay_param_s * 1e3, 0) + " ms, EKF2_GPS_DELAY)";
  }
  return text;
}

namespace {

// The GNSS topic whose fixes carry UTC: the first of the GNSS reader's candidates
// that logs time_utc_usec; nullptr if none.
const ulog::Candidate* ClockTopic(const std::vector<ULogSubscription>& subs,
                                  const std::vector<ulog::Candidate>& candidates) {
  for (const ulog::Candidate& c : candidates) {
    const ULogSubscription* sub = ulog::FindSubscription(subs, c);
    if (sub != nullptr && ulog::SubscriptionHasField(*sub, "time_utc_usec")) return &c;
  }
  return nullptr;
}

}  // namespace

ULogClock FindULogClock(const std::string& path) {
  ULogClock clock;
  const std::vector<ulog::Candidate> candidates = ulog::GnssCandidates();
  const ulog::Candidate* topic = ClockTopic(ListULogSubscriptions(path), candidates);
  ULogFile log(path);
  std::vector<std::int64_t> offsets;
  int leap_s = 0;
  while (topic != nullptr && log.NextOf(topic->topic)) {
    const double utc_us = log.GetDouble("time_utc_usec");
    if (!(log.GetDouble("fix_type") >= kMinTimeFixType) ||
        !(utc_us > static_cast<double>(kGpsEpochUnix_s * kUs_per_s))) {
      continue;
    }
    const std::int64_t gps_us = GpsMicrosecondsFromUtc(static_cast<std::int64_t>(utc_us), &leap_s);
    offsets.push_back(gps_us - static_cast<std::int64_t>(log.timestamp_us()));
  }
  while (log.Next()) {  // the parameters are complete at the end of the file
  }
  const auto delay = log.parameters().find("EKF2_GPS_DELAY");
  if (delay != log.parameters().end()) clock.gps_delay_param_s = delay->second * kMillisecond_s;
  if (offsets.empty()) return clock;
  const std::int64_t offset_us = MedianOffset(offsets);
  const auto [lo, hi] = std::minmax_element(offsets.begin(), offsets.end());
  clock.gps = true;
  clock.gps_week = static_cast<int>(
      FloorDivideWeeks(static_cast<std::int64_t>(log.start_time_us()) + offset_us));
  clock.shift_us = offset_us - static_cast<std::int64_t>(clock.gps_week) * kWeek_us;
  clock.source = std::string(topic->topic) + ".time_utc_usec";
  clock.fixes = offsets.size();
  clock.leap_s = leap_s;
  clock.jitter_min_s = static_cast<double>(*lo - offset_us) * kMicrosecond_s;
  clock.jitter_max_s = static_cast<double>(*hi - offset_us) * kMicrosecond_s;
  return clock;
}

}  // namespace navtwin
