#include "core/gps_time.h"

#include <iterator>

namespace navtwin {
namespace {

bool IsGregorianLeapYear(int year) { return (year % 4 == 0 && year % 100 != 0) || year % 400 == 0; }

int DaysInGregorianMonth(int year, int month) {
  static const int kDays[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return month == 2 && IsGregorianLeapYear(year) ? 29 : kDays[month - 1];
}

/// UTC dates (first of the month, 00:00:00) from which GPS - UTC equals `gps_minus_utc_s`
/// (IERS Bulletin C; header comment).
struct LeapSecondStep {
  int year;
  int month;
  int gps_minus_utc_s;
};
constexpr LeapSecondStep kLeapSecondSteps[] = {
    {1981, 7, 1},  {1982, 7, 2},  {1983, 7, 3},  {1985, 7, 4},  {1988, 1, 5},  {1990, 1, 6},
    {1991, 1, 7},  {1992, 7, 8},  {1993, 7, 9},  {1994, 7, 10}, {1996, 1, 11}, {1997, 7, 12},
    {1999, 1, 13}, {2006, 1, 14}, {2009, 1, 15}, {2012, 7, 16}, {2015, 7, 17}, {2017, 1, 18}};
static_assert(std::size(kLeapSecondSteps) == 18 &&
                  kLeapSecondSteps[17].gps_minus_utc_s == kGpsMinusUtcSince2017_s,
              "the table ends with the 2017 leap second");

/// Floor division for a positive divisor.
std::int64_t FloorDivideInt64(std::int64_t a, std::int64_t b) { return a / b - (a % b < 0 ? 1 : 0); }

}  // namespace

bool IsGregorianDate(int year, int month, int day) {
  return month >= 1 && month <= 12 && day >= 1 && day <= DaysInGregorianMonth(year, month);
}

std::int64_t DaysSinceUnixEpoch(int year, int month, int day) {
  std::int64_t days = 0;
  for (int y = 1970; y < year; ++y) days += IsGregorianLeapYear(y) ? 366 : 365;
  for (int y = year; y < 1970; ++y) days -= IsGregorianLeapYear(y) ? 366 : 365;
  for (int m = 1; m < month; ++m) days += DaysInGregorianMonth(year, m);
  return days + day - 1;
}

int GpsMinusUtc_s(std::int64_t utc_unix_s) {
  constexpr std::int64_t kDay_s = 86400;
  int leap = 0;
  for (const LeapSecondStep& step : kLeapSecondSteps) {
    if (utc_unix_s < DaysSinceUnixEpoch(step.year, step.month, 1) * kDay_s) break;
    leap = step.gps_minus_utc_s;
  }
  return leap;
}

std::int64_t GpsMicrosecondsFromUtc(std::int64_t utc_unix_us, int* leap_s) {
  constexpr std::int64_t kUsPerS = 1000000;
  const int leap = GpsMinusUtc_s(FloorDivideInt64(utc_unix_us, kUsPerS));
  if (leap_s != nullptr) *leap_s = leap;
  return utc_unix_us - kGpsEpochUnix_s * kUsPerS + leap * kUsPerS;
}

}  // namespace navtwin
