// KF-GINS-compatible text files (the i2Nav KF-GINS formats, so users bring their files
// unchanged). Fields are separated by blanks and/or commas; blank lines and lines
// starting with '#' are skipped. Columns (docs/formats.md has the full description):
//   IMU   t dtheta_x dtheta_y dtheta_z dv_x dv_y dv_z        (s, rad, m/s; IMU axes, FRD)
//         increments over (t_{k-1}, t_k]; dt from the time tags; the FIRST sample's dt is
//         the second sample's interval (one-sample look-ahead), so a file needs 2 lines.
//         ... odo                                             (8 columns, OB_GINS: + the
//         odometer's forward speed at t, m/s; the IMU reader ignores it)
//   GNSS  t lat lon h sigma_n sigma_e sigma_d                 (7 columns: s, deg, deg, m, m)
//         ... v_n v_e v_d sigma_vn sigma_ve sigma_vd          (13 columns: + m/s)
//   NAV   week sow lat lon h v_n v_e v_d roll pitch yaw       (11 columns: deg, m, m/s, deg)
// Time t is GPS seconds of week in KF-GINS files; the GNSS reader sets gps_week = -1 (the
// file does not say), the NAV reader takes the week from the file. Every reader checks
// the column count, finite numbers, sigma > 0, |lat| <= 90 deg and strictly increasing
// time, and throws InputError naming file, line and field.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/atomic_file.h"
#include "core/io/text_line.h"
#include "core/io/csv_odometer.h"
#include "core/io/sample_reader.h"

namespace navtwin {

std::unique_ptr<ImuReader> OpenKfginsImu(const std::string& path);
std::unique_ptr<GnssReader> OpenKfginsGnss(const std::string& path);
std::unique_ptr<NavReader> OpenKfginsNav(const std::string& path);

/// The odometer column of an 8-column (OB_GINS) IMU file: {t, speed_mps} per line, in
/// time order. An IMU file without it is an InputError naming the file.
std::vector<OdometerSample> ReadKfginsImuOdometer(const std::string& path);

/// Writes the KF-GINS IMU format with 17 significant digits (doubles round-trip exactly).
/// Nothing appears at `path` until Commit() (see AtomicFile).
class KfginsImuWriter {
 public:
  explicit KfginsImuWriter(const std::string& path);
  /// Throws std::invalid_argument on a non-finite value.
  void Write(const ImuSample& sample);
  void Commit();

 private:
  AtomicFile file_;
};

/// Writes 7 columns, or 13 when the first sample has velocity (all samples must agree).
/// sigma must be > 0 and finite (std::invalid_argument otherwise): the reader requires it.
class KfginsGnssWriter {
 public:
  explicit KfginsGnssWriter(const std::string& path);
  void Write(const GnssSample& sample);
  void Commit();

 private:
  AtomicFile file_;
  int columns_ = 0;  ///< 0 until the first sample fixes 7 or 13
};

/// The navigation record's fields after the week, "t lat lon h vn ve vd roll pitch yaw" (s,
/// deg, m, m/s, deg; attitude the ZYX Euler angles of q_n_b), each in the shortest form
/// that reads back exactly, separated by `separator`; the longitude wrapped into
/// (-180, 180]. Throws std::invalid_argument for a non-finite or impossible state: |lat| >
/// 90 deg, a height or a velocity outside the limits of core/io/plausibility.h.
void AppendNavFields(const NavState& s, char separator, TextLine* line);

/// Throws the std::invalid_argument AppendNavFields would throw for `s`, if any (a writer
/// that formats later, on another thread, refuses a state when it is handed over).
void RequireWritableNavState(const NavState& s);

/// Writes the navigation format; gps_week = -1 (unknown) is written as week 0. Attitude
/// as ZYX Euler angles (roll, pitch, yaw) of q_n_b in degrees.
class KfginsNavWriter {
 public:
  explicit KfginsNavWriter(const std::string& path);
  void Write(const NavState& state);
  /// Writes the record "week <fields>" from fields formatted by AppendNavFields with ','
  /// (a writer of nav.csv formats each number once for both files).
  void WriteFields(int gps_week, std::string_view comma_separated_fields);
  void Commit();
  void Revoke() { file_.Revoke(); }  ///< AtomicFile::Revoke

 private:
  AtomicFile file_;
};

}  // namespace navtwin
