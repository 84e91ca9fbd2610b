// The rtklib-walk IMU recording (rtklibexplorer/GNSS_IMU, data/walk_0827; BSD-3-Clause).
//
// Raw file (e.g. imu_1730.csv): lines "ax,ay,az,gx,gy,gz,t" with specific force in g
// (x 9.80665 m/s^2), angular rate in deg/s and t in integer milliseconds of the IMU's
// clock since power-up. The capture was started and stopped in the middle of a line:
// a FIRST line with too few fields is skipped, and so is a LAST line with too few fields
// and no line break (the byte stream simply ended); any other malformed line is an error.
// Axes are the IMU's own (z up at rest: az ~ +1 g), not rotated.
//
// RTKLIB time-tag file "<raw>.tag" beside it: 60-byte text header starting
// "TIMETAG RTKLIB", uint32 tick_f, uint32 file-open time (whole seconds since 1970 in
// the GPS time scale), double fraction of that second, then records (uint32 tick_ms =
// host milliseconds since the file was opened, uint32 file position = bytes written by
// then); little endian. The recorded file was later converted from CRLF to LF line ends:
// the tag positions then exceed the file size by the number of line breaks, which is
// detected and accounted for (positions are counted with CRLF line ends).
//
// Mapping device ms -> GPS time (FitRtklibWalkClock): each complete line is paired with
// the first tag record whose position covers its end, i.e. the host tick at which the
// line had been received. A sample cannot be received before it was measured, so the
// points y = tick - (t - t0) lie above a line c + b (t - t0) = device offset + smallest
// delay - tick flooring; that lower envelope is found as the lower convex hull edge that minimises
// the mean height of the points above it (a linear program: offset and clock drift b). The host
// tick is floored to its period q, so a receipt can be up to q after its tick; q is measured from
// the tag steps when records often share a tick (Windows: ~15.6 ms, written as steps of 15 and 16),
// else taken as 0 (tick finer than the writes). Then
//   t_GPS = sow(file open) + ((t - t0)(1 + b) + c + q) / 1000.
// These are the latest sampling times consistent with every tag (the true ones are
// earlier by the smallest transport delay, a few ms for a serial link).
//
// The source project's converted file (e.g. imu_1730_sf.csv): no header; time [s since
// 1970 in GPST, like the tag header], ax ay az [g], gx gy gz [rad/s], then extra columns
// (ignored; the count must stay the same). Its values are smoothed, not the raw ones,
// and its time stretches the device clock so that the first sample falls on the tag
// file's open time and the last on the last tag tick (docs/formats.md compares it with
// the mapping above).
//
// Both readers give t_s = seconds since the start of the GPS week of the first sample
// (the week is in the summary notes) and increments by the trapezoid rule
// (rate_to_increment.h: the first rate row only starts the series).
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "core/io/file_summary.h"
#include "core/io/sample_reader.h"

namespace navtwin {

/// Device clock -> GPS time mapping of a raw rtklib-walk IMU file.
struct RtklibWalkClock {
  int gps_week = 0;              ///< of the tag file's open time
  double open_sow_s = 0.0;       ///< GPS seconds of week when the file was opened
  double first_device_ms = 0.0;  ///< t0: device time of the first complete line
  double offset_ms = 0.0;        ///< c: envelope at t0, ms after the file opened
  double drift = 0.0;            ///< b: device clock rate error against the host's
  double tick_period_ms = 0.0;   ///< q: host tick period measured from the tags
  double mean_delay_ms = 0.0;    ///< mean height of the points above the envelope
  std::size_t paired_lines = 0;  ///< lines with a receipt tick
  bool crlf_positions = false;   ///< tag positions count CRLF line ends (file converted)

  /// GPS seconds of week (of gps_week) of a device time in ms.
  double GpsSow(double device_ms) const;
};

/// Reads the raw file and "<path>.tag" (streaming) and fits the mapping above.
RtklibWalkClock FitRtklibWalkClock(const std::string& path);

std::unique_ptr<ImuReader> OpenRtklibWalkImu(const std::string& path);
std::unique_ptr<ImuReader> OpenRtklibWalkImuSf(const std::string& path);

FileSummary DescribeRtklibWalkImu(const std::string& path);
FileSummary DescribeRtklibWalkImuSf(const std::string& path);

}  // namespace navtwin
