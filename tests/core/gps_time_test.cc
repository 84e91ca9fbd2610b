// GPS time from UTC (core/gps_time.h): the epoch, the leap-second table, week and
// seconds of week of a known date.
#include "core/gps_time.h"

#include <gtest/gtest.h>

#include <cstdint>

namespace navtwin {
namespace gps_time_test {

constexpr std::int64_t kDay_s = 86400;

TEST(GpsTime, EpochAndLeapSecondTable) {
  EXPECT_EQ(DaysSinceUnixEpoch(1980, 1, 6) * kDay_s, kGpsEpochUnix_s);
  EXPECT_EQ(DaysSinceUnixEpoch(2000, 3, 1), 11017);  // across a century leap day
  EXPECT_EQ(DaysSinceUnixEpoch(1969, 12, 31), -1);
  const std::int64_t jan2017_s = DaysSinceUnixEpoch(2017, 1, 1) * kDay_s;
  EXPECT_EQ(GpsMinusUtc_s(jan2017_s - 1), 17);
  EXPECT_EQ(GpsMinusUtc_s(jan2017_s), 18);
  EXPECT_EQ(GpsMinusUtc_s(DaysSinceUnixEpoch(1981, 6, 30) * kDay_s), 0);
  EXPECT_EQ(GpsMinusUtc_s(DaysSinceUnixEpoch(2012, 7, 1) * kDay_s), 16);
  // 2025-02-10 13:56:29.2 UTC, a Monday: GPS week 2353 (from Sunday 2025-02-09),
  // 86400 s + 13:56:29.2 + 18 leap seconds = 136607.2 s of week.
  const std::int64_t utc_us =
      (DaysSinceUnixEpoch(2025, 2, 10) * kDay_s + 13 * 3600 + 56 * 60 + 29) * 1000000 + 200000;
  int leap = 0;
  const std::int64_t gps_us = GpsMicrosecondsFromUtc(utc_us, &leap);
  EXPECT_EQ(leap, kGpsMinusUtcSince2017_s);
  constexpr std::int64_t kWeek_us = 604800LL * 1000000LL;
  EXPECT_EQ(gps_us / kWeek_us, 2353);
  // Exact in integer microseconds.
  EXPECT_EQ(gps_us - 2353 * kWeek_us, 136607200000);
  EXPECT_EQ(DaysSinceUnixEpoch(1980, 1, 6) + 7 * 2353, DaysSinceUnixEpoch(2025, 2, 9));
}

}  // namespace gps_time_test
}  // namespace navtwin
