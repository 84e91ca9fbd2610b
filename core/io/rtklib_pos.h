// RTKLIB solution files (.pos, as written by rtkpost/rnx2rtkp/rtknavi).
//
// Header lines start with '%'; the column-name line (the one naming "latitude(deg)")
// tells which columns exist, and its first name is the time system (GPST or UTC).
// Data lines: time as "yyyy/mm/dd hh:mm:ss.sss" or "week tow", then the named columns
// separated by blanks or commas. Used: latitude(deg) longitude(deg) height(m) Q ns
// sdn sde sdu, and when present vn ve vu sdvn sdve sdvu (velocity up -> v_D = -vu);
// other columns (sdne..., age, ratio, covariances) are ignored.
// Refused with a clear message: ECEF xyz or ENU baseline output, latitude/longitude in
// deg-min-sec, UTC time without the leap seconds stated in the header, JST.
// Output: GnssSample with gps_week = the GPS week of the FIRST epoch and t_s = seconds
// since the start of that week (so t_s runs past 604800 if a file crosses a week
// boundary and stays strictly increasing), quality = Q, num_sats = ns.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/io/file_summary.h"
#include "core/io/sample_reader.h"

namespace navtwin {

std::unique_ptr<GnssReader> OpenRtklibPos(const std::string& path);

/// Reads the file and summarises it; notes give the time system and the epochs per Q.
FileSummary DescribeRtklibPos(const std::string& path);

/// A GPS time as week and seconds of week.
struct GpsWeekTime {
  int week = 0;
  double sow_s = 0.0;
};

/// Days from 1970-01-01 to the proleptic Gregorian date (negative before 1970).
std::int64_t DaysFromCivil(int year, int month, int day);

/// GPS week and seconds of week of an instant given like RTKLIB's gtime_t in GPST:
/// whole seconds since 1970-01-01 00:00:00 counted in the GPS time scale, plus a fraction.
/// The week must fit an int: readers of outside input use the checked form below.
GpsWeekTime GpsTimeFromGpst1970(std::int64_t seconds, double fraction_s);

/// The same, for a time read from `path`: InputError(path, line, field) unless the instant
/// lies in GPS weeks 0 ... 10000 (1980-01-06 to 2171), the range every reader accepts.
GpsWeekTime GpsTimeFromGpst1970(std::int64_t seconds, double fraction_s, const std::string& path,
                                long line, const char* field);

/// InputError(path, line, field) unless 0 <= week <= 10000.
void CheckGpsWeek(long long week, const std::string& path, long line, const char* field);

}  // namespace navtwin
