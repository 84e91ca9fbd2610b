// One entry point for every input format: detect a file's kind and open the stream a
// caller asks for (IMU, GNSS, navigation, magnetometer, barometer), or describe the file.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/io/csv_odometer.h"
#include "core/io/file_summary.h"
#include "core/io/sample_reader.h"

namespace navtwin {

enum class FileFormat {
  kKfginsImu,
  kKfginsGnss,
  kKfginsNav,
  kRtklibPos,
  kCsvImu,
  kAnsflImu,
  kAnsflDotRaw,
  kAnsflGt,
  kAnsflGtExtended,
  kRtklibWalkImu,
  kRtklibWalkImuSf,
  kULog,
  kCsvMag,
  kCsvBaro,
  kUnknown
};

/// Decides a file's kind from its extension and first lines (docs/formats.md, "Format
/// detection"): ".ulg" -> ULog; a first line starting with '%' -> RTKLIB .pos; a header
/// naming columns -> the CSV kinds; numeric lines with a "<path>.tag" beside -> the
/// rtklib-walk raw IMU; 11 numeric columns starting with a time above 1e8 s -> the
/// rtklib-walk converted IMU; 7/11/13 numeric columns -> KF-GINS (7: GNSS when the
/// second or third column is beyond 0.5 in magnitude, degrees rather than radian
/// increments, else IMU). Throws InputError when the file cannot be opened.
FileFormat DetectFormat(const std::string& path);

/// "kfgins-imu", "rtklib-pos", "ulog", ... ("unknown").
std::string FormatName(FileFormat format);

/// Readers by kind; InputError "cannot read X from a file of kind Y" where the kind
/// holds no such stream (and for unknown files).
std::unique_ptr<ImuReader> OpenImu(const std::string& path);
std::unique_ptr<GnssReader> OpenGnss(const std::string& path);
/// Navigation: KF-GINS, the ANSFL ground truth, and ULog (PX4's own estimate,
/// OpenULogPx4Estimate).
std::unique_ptr<NavReader> OpenNav(const std::string& path);
/// navtwin CSV magnetometer files, raw Xsens DOT files with Mag columns, and ULog.
std::unique_ptr<MagReader> OpenMag(const std::string& path);
/// Wheel-odometer speeds: navtwin CSV (t_s,speed_mps or t_s,distance_m) or the 8th column
/// of an OB_GINS IMU file.
std::vector<OdometerSample> ReadOdometer(const std::string& path);
/// navtwin CSV barometer files and ULog.
std::unique_ptr<BaroReader> OpenBaro(const std::string& path);

/// Kind, and per stream the count, span, rate, gaps and fields with units; notes on
/// anything the reader repaired or assumed. Reads the whole file (streaming).
FileSummary DescribeFile(const std::string& path);

}  // namespace navtwin
