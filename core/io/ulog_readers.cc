// The typed ULog readers of core/io/ulog.h: IMU, GNSS, magnetometer, barometer. Every
// reader maps its times through the log's clock (core/io/ulog_time.h): GPS seconds of
// week when the log has GPS fixes with UTC, else seconds since boot.
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "core/gps_time.h"
#include "core/io/input_error.h"
#include "core/io/plausibility.h"
#include "core/io/ulog.h"
#include "core/io/ulog_time.h"
#include "core/io/ulog_topic.h"
#include "core/units.h"

namespace navtwin {
namespace {

using ulog::Candidate;
using ulog::ChooseTopic;
using ulog::TimeOrderedTopic;

constexpr double kMinFixType = 3;  // PX4 fix_type: 0-1 none, 2 2D, 3 3D, 4+ DGPS/RTK
// sensor_baro.pressure: Pa in current PX4, millibar (hPa) in old logs. Any pressure an
// aircraft meets is above 2000 Pa (about 26 km) and below 2000 hPa, so the two do not mix.
constexpr double kBaroPascalFloor_pa = 2000.0;
constexpr double kHectopascal_pa = 100.0;

/// A plausibility check of core/io/plausibility.h (which names a line) turned into the
/// ULog error that names the record's byte offset and field.
template <typename Check>
void Plausible(const TimeOrderedTopic& topic, const std::string& field, Check check) {
  try {
    check(topic.log().path(), 0L, field);
  } catch (const InputError& e) {
    throw topic.ErrorAt(field, e.reason());
  }
}

/// Each component of a vector field within the limits of `check`.
template <typename Check>
void PlausibleVector(const TimeOrderedTopic& topic, const std::string& field, const Eigen::Vector3d& v, Check check) {
  for (int k = 0; k < 3; ++k) {
    Plausible(topic, field, [&](const std::string& path, long line, const std::string& name) {
      check(v[k], path, line, name);
    });
  }
}

class ULogImuReader final : public ImuReader {
 public:
  explicit ULogImuReader(const std::string& path)
      : path_(path),
        topic_(path, ChooseTopic(path, {{"sensor_combined", "gyro_rad", ""}}, "imu"),
               FindULogClock(path)) {}

  bool Next(ImuSample* sample) override {
    while (topic_.Next()) {
      const double gyro_dt_s = IntegralSeconds("gyro_integral_dt");
      const double accel_dt_s = IntegralSeconds("accelerometer_integral_dt");
      double dt_s = gyro_dt_s;
      if (topic_.has_previous()) {
        dt_s = topic_.dt_s();
      } else if (gyro_dt_s <= 0.0) {
        continue;  // no interval for the first sample: it only starts the clock
      }
      sample->t_s = topic_.t_s();
      sample->dt_s = dt_s;
      // The rates are averages over the integration time; without one, over dt_s.
      const Eigen::Vector3d gyro_radps = topic_.Vector("gyro_rad");
      const Eigen::Vector3d acc_mps2 = topic_.Vector("accelerometer_m_s2");
      PlausibleVector(topic_, "gyro_rad", gyro_radps, plausible::AngularRate);
      PlausibleVector(topic_, "accelerometer_m_s2", acc_mps2, plausible::SpecificForce);
      sample->dtheta_b_rad = gyro_radps * (gyro_dt_s > 0.0 ? gyro_dt_s : dt_s);
      sample->dv_b_mps = acc_mps2 * (accel_dt_s > 0.0 ? accel_dt_s : dt_s);
      return true;
    }
    return false;
  }
  const std::string& path() const override { return path_; }

 private:
  // Integration time in seconds: integers are microseconds, floats seconds (old PX4);
  // 0 when the field is absent.
  double IntegralSeconds(const std::string& field) const {
    if (!topic_.log().HasField(field)) return 0.0;
    const double v = topic_.Finite(field);
    if (v < 0.0) throw topic_.ErrorAt(field, "negative integration time");
    const std::string type = topic_.log().FieldType(field);
    return type == "float" || type == "double" ? v : v * kMicrosecond_s;
  }

  std::string path_;
  TimeOrderedTopic topic_;
};

class ULogGnssReader final : public GnssReader {
 public:
  explicit ULogGnssReader(const std::string& path)
      : path_(path),
        topic_(path, ChooseTopic(path, ulog::GnssCandidates(), "gnss"), FindULogClock(path)) {}

  bool Next(GnssSample* s) override {
    while (topic_.Next()) {
      const double fix_type = topic_.Finite("fix_type");
      if (fix_type < kMinFixType) continue;  // no 3D fix: position not usable
      const double t_s = FixTime_s();
      if (has_last_ && t_s == last_t_s_) continue;  // the same fix again
      if (has_last_ && t_s < last_t_s_) {
        throw topic_.ErrorAt("time_utc_usec", "fix time goes backwards: " +
                                                  ulog::FormatNumber(t_s) + " s after " +
                                                  ulog::FormatNumber(last_t_s_) + " s");
      }
      has_last_ = true;
      last_t_s_ = t_s;
      s->t_s = t_s;
      s->gps_week = topic_.clock().gps_week;
      FillPosition(s);
      FillVelocity(s);
      s->quality = static_cast<int>(fix_type);
      s->num_sats = topic_.log().HasField("satellites_used")
                        ? static_cast<int>(topic_.Finite("satellites_used"))
                        : 0;
      return true;
    }
    return false;
  }
  const std::string& path() const override { return path_; }

 private:
  // The fix's own UTC time on the GPS scale where the clock is GPS time and the message
  // has one (the measurement epoch); else the mapped message time.
  double FixTime_s() const {
    const ULogClock& clock = topic_.clock();
    if (!clock.gps || !topic_.log().HasField("time_utc_usec")) return topic_.t_s();
    const double utc_us = topic_.log().GetDouble("time_utc_usec");
    if (!(utc_us > static_cast<double>(kGpsEpochUnix_s) * 1e6)) return topic_.t_s();
    return clock.SecondsOfWeek(GpsMicrosecondsFromUtc(static_cast<std::int64_t>(utc_us)));
  }

  void FillPosition(GnssSample* s) const {
    const ulog::GnssFields f = ulog::GnssFieldsOf(topic_.log().subscription());
    const double lat_deg = topic_.Finite(f.lat) * f.deg_per_unit;
    const double lon_deg = topic_.Finite(f.lon) * f.deg_per_unit;
    if (std::abs(lat_deg) > 90.0 || std::abs(lon_deg) > 180.0) {
      throw topic_.ErrorAt(f.lat, "latitude/longitude out of range");
    }
    s->lat_rad = lat_deg * kDegToRad;
    s->lon_rad = lon_deg * kDegToRad;
    s->h_m = topic_.Finite(f.height) * f.m_per_unit;
    Plausible(topic_, f.height, [&](const std::string& path, long line, const std::string& name) {
      plausible::Height(s->h_m, path, line, name);
    });
    const double eph = topic_.Sigma("eph");
    s->pos_std_ned_m = {eph, eph, topic_.Sigma("epv")};
  }

  void FillVelocity(GnssSample* s) const {
    s->has_velocity =
        !topic_.log().HasField("vel_ned_valid") || topic_.Finite("vel_ned_valid") != 0.0;
    if (s->has_velocity) {
      s->v_n_mps = {topic_.Finite("vel_n_m_s"), topic_.Finite("vel_e_m_s"),
                    topic_.Finite("vel_d_m_s")};
      PlausibleVector(topic_, "vel_n_m_s", s->v_n_mps, plausible::Velocity);
      s->vel_std_ned_mps = Eigen::Vector3d::Constant(topic_.Sigma("s_variance_m_s"));
    } else {
      s->v_n_mps.setZero();
      s->vel_std_ned_mps.setConstant(std::numeric_limits<double>::quiet_NaN());
    }
  }

  std::string path_;
  TimeOrderedTopic topic_;
  bool has_last_ = false;
  double last_t_s_ = 0.0;
};

class ULogMagReader final : public MagReader {
 public:
  explicit ULogMagReader(const std::string& path)
      : path_(path),
        source_(
            ChooseTopic(path,
                        {{"vehicle_magnetometer", "magnetometer_ga", ""},
                         {"sensor_mag", "x", ""},
                         {"sensor_combined", "magnetometer_ga", "magnetometer_timestamp_relative"}},
                        "magnetometer")),
        topic_(path, source_, FindULogClock(path)) {}

  bool Next(MagSample* s) override {
    if (!topic_.Next()) return false;
    const bool xyz = std::string(source_.topic) == "sensor_mag";
    const Eigen::Vector3d gauss =
        xyz ? Eigen::Vector3d(topic_.Finite("x"), topic_.Finite("y"), topic_.Finite("z"))
            : topic_.Vector("magnetometer_ga");
    s->t_s = topic_.t_s();
    s->m_b_uT = kGauss_uT * gauss;
    const char* axes[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      Plausible(topic_, xyz ? axes[k] : "magnetometer_ga", [&](const std::string& p, long line, const std::string& name) {
        plausible::MagneticField(s->m_b_uT[k], p, line, name);
      });
    }
    return true;
  }
  const std::string& path() const override { return path_; }

 private:
  std::string path_;
  Candidate source_;
  TimeOrderedTopic topic_;
};

class ULogBaroReader final : public BaroReader {
 public:
  explicit ULogBaroReader(const std::string& path)
      : path_(path),
        source_(ChooseTopic(path,
                            {{"vehicle_air_data", "baro_alt_meter", ""},
                             {"sensor_combined", "baro_alt_meter", "baro_timestamp_relative"},
                             {"sensor_baro", "pressure", ""}},
                            "barometer")),
        topic_(path, source_, FindULogClock(path)) {}

  bool Next(BaroSample* s) override {
    if (!topic_.Next()) return false;
    s->t_s = topic_.t_s();
    if (std::string(source_.topic) == "sensor_baro") {
      ReadSensorBaro(s);
      return true;
    }
    s->altitude_m = topic_.Finite("baro_alt_meter");
    s->pressure_pa = topic_.FiniteOrNaN("baro_pressure_pa");
    s->temperature_degC = topic_.log().HasField("baro_temp_celcius")
                              ? topic_.Finite("baro_temp_celcius")
                              : topic_.FiniteOrNaN("ambient_temperature");
    return true;
  }
  const std::string& path() const override { return path_; }

 private:
  // sensor_baro: raw pressure (Pa, or hPa in old logs) and temperature; no altitude.
  void ReadSensorBaro(BaroSample* s) const {
    const double p = topic_.Finite("pressure");
    if (!(p > 0.0)) throw topic_.ErrorAt("pressure", "must be > 0, got " + ulog::FormatNumber(p));
    s->pressure_pa = p >= kBaroPascalFloor_pa ? p : p * kHectopascal_pa;
    s->altitude_m = std::numeric_limits<double>::quiet_NaN();
    s->temperature_degC = topic_.FiniteOrNaN("temperature");
  }

  std::string path_;
  Candidate source_;
  TimeOrderedTopic topic_;
};

}  // namespace

std::unique_ptr<ImuReader> OpenULogImu(const std::string& path) {
  return std::make_unique<ULogImuReader>(path);
}

std::unique_ptr<GnssReader> OpenULogGnss(const std::string& path) {
  return std::make_unique<ULogGnssReader>(path);
}

std::unique_ptr<MagReader> OpenULogMag(const std::string& path) {
  return std::make_unique<ULogMagReader>(path);
}

std::unique_ptr<BaroReader> OpenULogBaro(const std::string& path) {
  return std::make_unique<ULogBaroReader>(path);
}

}  // namespace navtwin
