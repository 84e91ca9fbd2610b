// GPS time for PX4 ULog streams. PX4 stamps every message with microseconds since
// boot; its GNSS topic also logs the receiver's UTC time of each fix (time_utc_usec).
// The clock maps boot time to GPS time with one offset per log:
//
//   offset = median over the fixes with valid UTC of (GPS(time_utc_usec) - timestamp)
//   GPS(utc) = utc - GPS epoch (1980-01-06) + leap seconds (core/gps_time.h; 18 s since
//              2017; PX4 logs do not carry the leap-second count, so the table gives it)
//   t_s      = timestamp + offset - gps_week * 604800 s   (GPS seconds of week)
//
// Fixes: the GNSS reader's topic (vehicle_gps_position, else sensor_gps instance 0),
// messages with fix_type >= 2 (the receiver has solved its clock) and time_utc_usec after
// the GPS epoch. gps_week is the week of the log's start (ULog header time) on the GPS
// scale; a log that crosses a week boundary keeps counting beyond 604800 s, so times stay
// increasing. The median makes the offset robust to single late messages.
//
// What the offset holds: `timestamp` is when the GNSS message reached the autopilot, after
// the fix epoch by the receiver's output latency plus transport (tens of ms, jittering by
// the message arrival). The median absorbs the typical latency, so boot-time streams
// (IMU, magnetometer, barometer, PX4's estimate) map to GPS time that is early by that
// typical latency; the fixes themselves are timed by their own UTC (exact). PX4's EKF
// assumes this latency as its parameter EKF2_GPS_DELAY (Describe() prints it when logged);
// installation.imu_time_offset_s can shift the IMU by it. The spread of the per-fix
// offsets around the median is kept as the arrival jitter.
//
// Without a fix with valid UTC the clock stays in boot time (gps == false, gps_week -1):
// Describe() says so, and callers print it on stderr.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace navtwin {

struct ULogClock {
  bool gps = false;           ///< true: times are GPS seconds of week gps_week
  int gps_week = -1;          ///< -1: boot time, no week
  std::int64_t shift_us = 0;  ///< t = boot time + shift (0 for boot time)
  std::string source;         ///< "vehicle_gps_position.time_utc_usec", or "" without GPS
  std::size_t fixes = 0;      ///< fixes with valid UTC used for the median
  int leap_s = 0;             ///< GPS - UTC applied
  double jitter_min_s = 0.0;  ///< smallest per-fix offset minus the median (<= 0)
  double jitter_max_s = 0.0;  ///< largest per-fix offset minus the median (>= 0)
  double gps_delay_param_s = -1.0;  ///< PX4's EKF2_GPS_DELAY when logged, else -1

  /// Seconds (of gps_week when gps) of a PX4 timestamp in microseconds since boot.
  double Seconds(std::uint64_t boot_us) const;
  /// Seconds of gps_week of a GPS time in microseconds since the GPS epoch (gps only).
  double SecondsOfWeek(std::int64_t gps_us) const;
  /// One line for stderr and `navtwin info`: the mapping, or that times stay boot time.
  std::string Describe() const;
};

/// Reads the log's GNSS topic once and builds its clock. Throws InputError for a file
/// that is not a readable ULog; a log without GNSS, or without a fix with valid UTC,
/// gives a boot-time clock.
ULogClock FindULogClock(const std::string& path);

}  // namespace navtwin
