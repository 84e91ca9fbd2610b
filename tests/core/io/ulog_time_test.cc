// GPS time for ULog streams (core/io/ulog_time.h, core/gps_time.h) and PX4's own
// estimate as navigation states (OpenULogPx4Estimate): synthetic logs with known
// answers, then the real logs in px4-ulog/.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/gps_time.h"
#include "core/io/ulog.h"
#include "core/io/ulog_time.h"
#include "core/units.h"
#include "tests/core/io/io_test_util.h"
#include "tests/core/io/ulog_writer.h"
#include "tests/test_data.h"

namespace navtwin {
namespace ulog_time_test {

using testing::ReadAllSamples;
using ulog_writer::Bytes;
using ulog_writer::ULogWriter;

constexpr std::int64_t kDay_s = 86400;
// 2025-02-10 13:56:29.2 UTC (a Monday) in microseconds since 1970: the first fix of
// ekf_failure.ulg, rounded.
const std::int64_t kUtc0_us = (DaysSinceUnixEpoch(2025, 2, 10) * kDay_s + 13 * 3600 + 56 * 60 + 29) *
                                  1000000 +
                              200000;
// Its GPS time: week 2353, Monday 13:56:29.2 + 18 s = 86400 + 50189.2 + 18 s of week.
constexpr int kWeek0 = 2353;
constexpr double kSow0_s = 136607.2;

// ---------------------------------------------------------------------------------------
// A log with five fixes whose messages arrive 40..300 ms after their UTC epochs, a fix
// without a solution (fix_type 1, a wrong UTC) and a 3D fix without UTC, plus an IMU.
std::string GpsClockLog() {
  ULogWriter w;
  w.Format(
       "vehicle_gps_position:uint64_t timestamp;uint64_t time_utc_usec;double latitude_deg;"
       "double longitude_deg;double altitude_msl_m;double altitude_ellipsoid_m;"
       "float s_variance_m_s;float eph;float epv;float vel_n_m_s;float vel_e_m_s;"
       "float vel_d_m_s;uint8_t fix_type;bool vel_ned_valid;uint8_t satellites_used;"
       "uint8_t[5] _padding0;")
      .Format(
          "sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;"
          "float[3] accelerometer_m_s2;uint32_t accelerometer_integral_dt;")
      .Subscribe(0, 0, "vehicle_gps_position")
      .Subscribe(0, 1, "sensor_combined");
  const auto fix = [&](std::uint64_t t_us, std::uint64_t utc_us, std::uint8_t fix_type) {
    Bytes b;
    b.U64(t_us).U64(utc_us).F64(53.7).F64(9.8).F64(11.0).F64(56.0);
    b.F32(0.2f).F32(0.6f).F32(0.9f).F32(1.f).F32(0.f).F32(0.f).U8(fix_type).U8(1).U8(12);
    w.Data(0, b);
  };
  const std::uint64_t delays_us[5] = {40000, 60000, 50000, 45000, 300000};
  for (int k = 0; k < 5; ++k) {
    fix(40'000'000 + 200'000 * k + delays_us[k], kUtc0_us + 200'000 * k, 3);
    if (k == 2) {  // two IMU samples in between
      w.Data(1, Bytes().U64(40'500'000).F32(0.f).F32(0.f).F32(0.f).U32(5000).F32(0.f).F32(0.f).F32(-9.8f).U32(5000));
      w.Data(1, Bytes().U64(40'505'000).F32(0.f).F32(0.f).F32(0.f).U32(5000).F32(0.f).F32(0.f).F32(-9.8f).U32(5000));
    }
  }
  fix(41'200'000, DaysSinceUnixEpoch(2020, 1, 1) * kDay_s * 1000000, 1);
  fix(41'300'000, 0, 3);
  return w.Save("gps_clock.ulg");
}

TEST(ULogClockTest, MedianOffsetMapsBootTimeAndFixesKeepTheirOwnUtc) {
  const std::string path = GpsClockLog();
  const ULogClock clock = FindULogClock(path);
  ASSERT_TRUE(clock.gps);
  EXPECT_EQ(clock.gps_week, kWeek0);
  EXPECT_EQ(clock.fixes, 5u);  // the fix_type 1 and the UTC-less fix are not used
  EXPECT_EQ(clock.leap_s, 18);
  EXPECT_EQ(clock.source, "vehicle_gps_position.time_utc_usec");
  // Offsets GPS - timestamp = G0 - 40 s - delay: median at the 50 ms delay; the 300 ms
  // message is 250 ms below it, the 40 ms one 10 ms above. 1e-9 s: integer microseconds
  // through doubles.
  EXPECT_NEAR(static_cast<double>(clock.shift_us) * 1e-6, kSow0_s - 40.05, 1e-9);
  EXPECT_NEAR(clock.jitter_min_s, -0.250, 1e-9);
  EXPECT_NEAR(clock.jitter_max_s, 0.010, 1e-9);
  EXPECT_NE(clock.Describe().find("GPS week 2353"), std::string::npos) << clock.Describe();

  const std::vector<ImuSample> imu = ReadAllSamples(*OpenULogImu(path));
  ASSERT_EQ(imu.size(), 2u);
  EXPECT_NEAR(imu[0].t_s, kSow0_s - 40.05 + 40.5, 1e-9);
  EXPECT_NEAR(imu[1].dt_s, 0.005, 1e-12);  // intervals from boot time, unchanged

  const std::vector<GnssSample> gnss = ReadAllSamples(*OpenULogGnss(path));
  ASSERT_EQ(gnss.size(), 6u);  // fix_type 1 skipped
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR(gnss[k].t_s, kSow0_s + 0.2 * k, 1e-9) << k;  // own UTC, whatever the delay
    EXPECT_EQ(gnss[k].gps_week, kWeek0);
  }
  EXPECT_NEAR(gnss[5].t_s, kSow0_s - 40.05 + 41.3, 1e-9);  // no UTC: the mapped timestamp
}

TEST(ULogClockTest, WithoutUtcTimesStayBootTime) {
  ULogWriter w;
  w.Format("vehicle_gps_position:uint64_t timestamp;uint64_t time_utc_usec;uint8_t fix_type;")
      .Format("vehicle_magnetometer:uint64_t timestamp;float[3] magnetometer_ga;")
      .Subscribe(0, 0, "vehicle_gps_position")
      .Subscribe(0, 1, "vehicle_magnetometer")
      .Data(0, Bytes().U64(1'000'000).U64(kUtc0_us).U8(0))  // no fix: its UTC is not trusted
      .Data(1, Bytes().U64(2'000'000).F32(0.2f).F32(0.f).F32(0.4f));
  const std::string path = w.Save("no_utc.ulg");
  const ULogClock clock = FindULogClock(path);
  EXPECT_FALSE(clock.gps);
  EXPECT_EQ(clock.gps_week, -1);
  EXPECT_NE(clock.Describe().find("times stay seconds since boot"), std::string::npos);
  MagSample m;
  ASSERT_TRUE(OpenULogMag(path)->Next(&m));
  EXPECT_DOUBLE_EQ(m.t_s, 2.0);
}

// ---------------------------------------------------------------------------------------
// Real logs.

TEST(ULogClockRealDataTest, EkfFailureMapsToTheLogsDateAndAgreesWithTheFixesOwnUtc) {
  const std::string path = testing::DataPath("px4-ulog/ekf_failure.ulg");
  NAVTWIN_REQUIRE_DATA(path);
  const ULogClock clock = FindULogClock(path);
  std::printf("ekf_failure: %s\n", clock.Describe().c_str());
  ASSERT_TRUE(clock.gps);
  // The log's folder and name say 2025-02-10 13:56:28 UTC: GPS week 2353 began on
  // Sunday 2025-02-09 (1980-01-06 + 2353 weeks).
  EXPECT_EQ(clock.gps_week, 2353);
  EXPECT_EQ(DaysSinceUnixEpoch(1980, 1, 6) + 7 * 2353, DaysSinceUnixEpoch(2025, 2, 9));
  EXPECT_EQ(clock.fixes, 397u);  // every vehicle_gps_position message has fix 3 or 4
  EXPECT_EQ(clock.leap_s, 18);
  EXPECT_NEAR(clock.gps_delay_param_s, 0.110, 1e-6);  // EKF2_GPS_DELAY = 110 ms

  // The first IMU sample: boot 46.942329 s -> Monday (86400 s into the week) 13:56:29.3
  // UTC, 1 s either way for the minute of the file name.
  ImuSample imu;
  ASSERT_TRUE(OpenULogImu(path)->Next(&imu));
  const double utc_of_day_s = imu.t_s - kDay_s - 18.0;
  EXPECT_NEAR(utc_of_day_s, 13 * 3600 + 56 * 60 + 29.3, 1.0);

  // Every fix: its own UTC against its timestamp through the clock. The median offset
  // makes the median difference zero; 1 ms allows the rounding to whole microseconds.
  // Single messages arrive up to a few tens of ms off the median (measured -15.6 ..
  // +34.2 ms); 100 ms bounds them.
  ULogFile log(path);
  std::vector<double> diffs;
  while (log.NextOf("vehicle_gps_position")) {
    const auto utc_us = static_cast<std::int64_t>(log.GetDouble("time_utc_usec"));
    const double own_s = clock.SecondsOfWeek(GpsMicrosecondsFromUtc(utc_us));
    diffs.push_back(clock.Seconds(log.timestamp_us()) - own_s);
  }
  ASSERT_EQ(diffs.size(), 397u);
  std::sort(diffs.begin(), diffs.end());
  EXPECT_LT(std::abs(diffs[diffs.size() / 2]), 1e-3);
  EXPECT_LT(std::abs(diffs.front()), 0.1);
  EXPECT_LT(std::abs(diffs.back()), 0.1);
  std::printf("mapped timestamp - own UTC: median %.6f s, %.4f .. %.4f s\n",
              diffs[diffs.size() / 2], diffs.front(), diffs.back());

  // The GNSS stream carries the fixes' own times and the week.
  const std::vector<GnssSample> gnss = ReadAllSamples(*OpenULogGnss(path));
  ASSERT_EQ(gnss.size(), 397u);
  EXPECT_EQ(gnss.front().gps_week, 2353);
  EXPECT_NEAR(gnss.front().t_s, kSow0_s - 0.000198, 1e-6);  // 13:56:29.199802 UTC
}

TEST(ULogClockRealDataTest, LogsWithoutGpsKeepBootTimeWithAStatedMessage) {
  for (const char* file : {"sample.ulg", "gps_interference.ulg"}) {
    const std::string path = testing::DataPath(std::string("px4-ulog/") + file);
    NAVTWIN_REQUIRE_DATA(path);
    SCOPED_TRACE(file);
    const ULogClock clock = FindULogClock(path);
    EXPECT_FALSE(clock.gps);
    EXPECT_EQ(clock.shift_us, 0);
    EXPECT_NE(clock.Describe().find("times stay seconds since boot, GPS week unknown"),
              std::string::npos);
    const FileSummary summary = DescribeULog(path);
    EXPECT_TRUE(std::any_of(summary.notes.begin(), summary.notes.end(), [](const std::string& n) {
      return n.find("times stay seconds since boot") != std::string::npos;
    }));
    const StreamSummary* imu = nullptr;
    for (const StreamSummary& s : summary.streams) {
      if (s.name == "sensor_combined") imu = &s;
    }
    ASSERT_NE(imu, nullptr);
    ImuSample first;
    ASSERT_TRUE(OpenULogImu(path)->Next(&first));
    EXPECT_LT(first.t_s, 1000.0);  // seconds since boot, not a time of week
  }
}

}  // namespace ulog_time_test
}  // namespace navtwin
