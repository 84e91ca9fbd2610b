// PX4 ULog reader (binary): header, flag bits, definitions (formats, nested formats,
// info, multi-info, parameters), subscriptions, data, dropouts, logged messages.
// Streaming: the file is read message by message, never held whole in memory.
// Errors name the file, the byte offset of the message and the field.
//
// Times: PX4 "timestamp" fields are microseconds since boot. The typed readers (Open*)
// map them to GPS time with the log's clock (core/io/ulog_time.h: the median offset of
// the GNSS fixes' UTC time to their timestamp, plus the leap seconds): t_s = GPS seconds
// of week (GnssSample/NavState gps_week set), or seconds since boot (gps_week -1) when
// the log has no fix with a valid UTC time. Typed readers need strictly increasing times:
// a sample whose time equals the previous one is skipped (DescribeULog counts them),
// a sample whose time goes backwards is an InputError at its byte offset.
// A file that ends inside a message (power loss) is accepted: the cut message is
// dropped and DescribeULog notes it. See docs/formats.md (ULog section) for details.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/io/file_summary.h"
#include "core/io/sample_reader.h"

namespace navtwin {

/// sensor_combined -> IMU increments (gyro_rad * gyro_integral_dt, accelerometer_m_s2 *
/// accelerometer_integral_dt), t_s = the timestamp through the log's clock, PX4 body FRD.
/// dt_s comes from consecutive time tags (the first sample: gyro_integral_dt). Integral
/// times are microseconds when logged as integers, seconds when logged as float (old
/// PX4). Where an integral time is zero or absent, the increment is rate * dt_s (and a
/// first sample without one only starts the clock).
std::unique_ptr<ImuReader> OpenULogImu(const std::string& path);
/// vehicle_gps_position, else sensor_gps (instance 0); old integer (lat/lon 1e-7 deg,
/// alt/alt_ellipsoid mm) and new float (latitude_deg, altitude_ellipsoid_m, ...) field
/// names. Height: the ellipsoid field when logged, else MSL (DescribeULog says which).
/// pos_std_ned_m = (eph, eph, epv); velocity sigma = s_variance_m_s on each axis;
/// quality = fix_type, num_sats = satellites_used. Samples with fix_type < 3 are skipped.
/// Time: the fix's own time_utc_usec on the GPS scale where the clock is GPS time (the
/// measurement epoch, not the message's arrival), else the timestamp through the clock.
std::unique_ptr<GnssReader> OpenULogGnss(const std::string& path);
/// vehicle_magnetometer.magnetometer_ga (body FRD, calibrated), else sensor_mag x/y/z
/// (instance 0, sensor axes), else the old sensor_combined.magnetometer_ga (time =
/// timestamp + magnetometer_timestamp_relative). Gauss in the log, microtesla out.
std::unique_ptr<MagReader> OpenULogMag(const std::string& path);
/// vehicle_air_data (baro_alt_meter, baro_pressure_pa, baro_temp_celcius or
/// ambient_temperature), else the old sensor_combined.baro_alt_meter/baro_temp_celcius,
/// else sensor_baro (instance 0: pressure in Pa, or hPa when below 2000 as old PX4 logged
/// it, and temperature; no altitude, which the GNSS/INS inputs take from the pressure).
std::unique_ptr<BaroReader> OpenULogBaro(const std::string& path);

/// What the PX4 estimate reader did, complete once Next() has returned false.
struct Px4EstimateStats {
  std::size_t epochs = 0;             ///< states returned
  std::size_t invalid = 0;            ///< epochs skipped: a validity flag false
  std::size_t outside = 0;            ///< epochs outside the velocity or attitude record
  std::size_t gaps = 0;               ///< epochs skipped: bracketing samples too far apart
  std::size_t across_reset = 0;       ///< epochs that took the nearer sample across a reset
  std::string height_field;           ///< "alt_ellipsoid", or "alt" (AMSL)
  bool ellipsoid = true;              ///< false: heights are AMSL, not WGS84 ellipsoidal
};

/// PX4's own EKF2 solution as navigation states, at the epochs of vehicle_global_position
/// (its timestamp_sample: the IMU time the estimate refers to):
///  - position: lat, lon (deg) and height alt_ellipsoid (WGS84) when the format has it,
///    else alt (AMSL; Px4EstimateStats says so: heights are then off from WGS84 by the
///    geoid undulation, tens of metres);
///  - velocity: vehicle_local_position vx, vy, vz (NED, m/s), linear interpolation;
///  - attitude: vehicle_attitude q = (w, x, y, z), Hamilton, rotating body FRD into NED
///    (q_n_b; checked on ekf_failure.ulg against the gyro increments), spherical
///    interpolation.
/// Velocity and attitude are interpolated between their two samples around the epoch
/// (each topic by its timestamp_sample); when the two straddle a reset of that quantity
/// (vxy/vz_reset_counter, quat_reset_counter) the nearer one is taken instead. An epoch
/// is skipped (and counted) when lat_lon_valid, alt_valid, v_xy_valid or v_z_valid is
/// false, when it lies outside the velocity or attitude record, or when the two samples
/// around it are more than 0.5 s apart. Times through the log's clock (gps_week set).
class Px4EstimateReader : public NavReader {
 public:
  virtual const Px4EstimateStats& stats() const = 0;
};
std::unique_ptr<Px4EstimateReader> OpenULogPx4Estimate(const std::string& path);
/// Every (topic, multi_id) with count, rate, gaps and fields; dropouts and logged
/// messages in notes.
FileSummary DescribeULog(const std::string& path);

/// One field of a subscribed topic, nested formats flattened ("q", "esc[1].esc_rpm");
/// padding fields are left out.
struct ULogField {
  std::string name;
  std::string type;      ///< basic type: "float", "uint64_t", "char", ...
  int array_length = 0;  ///< 0 for a scalar
  /// "name:type" as in the format, e.g. "gyro_rad:float[3]".
  std::string Describe() const;
};

/// One subscription ('A' message): a topic instance and its flattened fields.
struct ULogSubscription {
  std::string topic;  ///< format name, e.g. "sensor_accel"
  int multi_id = 0;
  int msg_id = 0;
  std::vector<ULogField> fields;
  /// "sensor_accel" for multi_id 0, "sensor_accel[1]" otherwise.
  std::string Label() const;
};

/// A logged string ('L', or 'C' with a tag).
struct ULogLoggedString {
  int level = 0;  ///< Linux kernel levels: 0 emergency .. 7 debug
  int tag = -1;   ///< -1 for untagged 'L' messages
  std::uint64_t timestamp_us = 0;
  std::string text;
};

/// Streaming cursor over the data messages of a ULog file, with typed field access
/// by name. Definitions, parameters and dropouts are gathered as they go by; they are
/// complete once Next() has returned false.
///
///   ULogFile log(path);
///   while (log.NextOf("vehicle_attitude")) use(log.timestamp_us(), log.GetArray("q", 0));
class ULogFile {
 public:
  /// Opens the file and reads the header; throws InputError (bad magic: byte 0).
  explicit ULogFile(const std::string& path);
  ~ULogFile();
  ULogFile(ULogFile&&) noexcept;
  ULogFile& operator=(ULogFile&&) noexcept;

  /// Advances to the next data message of any topic; false at the end of the file.
  bool Next();
  /// Advances to the next data message of `topic` instance `multi_id`.
  bool NextOf(const std::string& topic, int multi_id = 0);

  // The current data message (valid after Next/NextOf returned true).
  const ULogSubscription& subscription() const;
  long long byte_offset() const;  ///< of the current message's header
  std::uint64_t timestamp_us() const;
  bool HasField(const std::string& field) const;
  /// The field's basic type ("float", "uint32_t", ...); InputError if absent.
  std::string FieldType(const std::string& field) const;
  /// A scalar field as double; InputError (byte offset, field) if absent or an array.
  double GetDouble(const std::string& field) const;
  /// Element `index` of an array field; InputError if absent or out of range.
  double GetArray(const std::string& field, int index) const;
  /// A char[n] field as text (up to the first NUL).
  std::string GetString(const std::string& field) const;

  // What the file said so far.
  const std::string& path() const;
  int version() const;                                      ///< header format version
  std::uint64_t start_time_us() const;  ///< header: logging start, microseconds since boot
  const std::map<std::string, std::string>& info() const;   ///< 'I': name -> value as text
  const std::map<std::string, double>& parameters() const;  ///< 'P': name -> latest value
  const std::vector<ULogSubscription>& subscriptions() const;
  const std::vector<ULogLoggedString>& logged_strings() const;
  std::size_t dropout_count() const;
  double dropout_total_s() const;
  /// Byte offset of a final record cut short by the end of the file, -1 if none.
  long long truncated_at_byte() const;
  /// Offsets where appended data start (flag bits); messages cut there are dropped.
  const std::vector<long long>& appended_offsets() const;
  std::size_t unknown_message_count() const;  ///< message types this reader skips

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

/// All subscriptions of a file (reads it through once).
std::vector<ULogSubscription> ListULogSubscriptions(const std::string& path);

}  // namespace navtwin
