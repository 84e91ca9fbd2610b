// GPS time from UTC: the GPS time scale started at 1980-01-06 00:00:00 UTC and counts
// SI seconds without leap seconds, so GPS = UTC + (leap seconds inserted into UTC since).
// Weeks of 604800 s from that epoch; files carry GPS week + seconds of week.
//
// The leap seconds are a table (UTC dates from which GPS - UTC takes each value), from
// IERS Bulletin C (https://hpiers.obspm.fr/eoppc/bul/bulc/): 1 s from 1981-07-01 up to
// 18 s from 2017-01-01, the last one inserted as of 2025 (Bulletin C 69 and 70 announce
// none up to the end of 2025). A date after a future leap second would come out one
// second off until the table is extended.
#pragma once

#include <cstdint>

namespace navtwin {

/// The GPS epoch 1980-01-06 00:00:00 UTC as seconds since 1970-01-01 00:00:00 UTC
/// (3657 days).
constexpr std::int64_t kGpsEpochUnix_s = 315964800;
/// GPS - UTC since 2017-01-01 (IERS Bulletin C 52), the value of the table's last entry.
constexpr int kGpsMinusUtcSince2017_s = 18;

/// True when the date exists in the proleptic Gregorian calendar: month 1..12 and day
/// 1..the length of that month (February 29 only in leap years).
bool IsGregorianDate(int year, int month, int day);

/// Days from 1970-01-01 to the given proleptic Gregorian date (negative before 1970).
std::int64_t DaysSinceUnixEpoch(int year, int month, int day);

/// GPS - UTC in whole seconds at a UTC time given as seconds since 1970 (Unix time);
/// 0 before the first leap second after the GPS epoch (1981-07-01).
int GpsMinusUtc_s(std::int64_t utc_unix_s);

/// Microseconds of GPS time since the GPS epoch for a UTC time in microseconds since
/// 1970; *leap_s (if given) receives the leap seconds applied.
std::int64_t GpsMicrosecondsFromUtc(std::int64_t utc_unix_us, int* leap_s = nullptr);

}  // namespace navtwin
