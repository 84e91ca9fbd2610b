// LoadInputs (inputs.h): reads the IMU, GNSS, magnetometer and barometer records, applies
// the installation, cuts to the configured time span, bridges short IMU gaps, injects the
// scoring outages and checks what the estimators rely on (docs/gnss-ins.md "Bad input").
#include "problems/gnss_ins/inputs.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <utility>

#include "core/calibration_file.h"
#include "core/io/input_error.h"
#include "core/io/open.h"
#include "core/rotation.h"
#include "problems/ins/imu_gaps.h"
#include "problems/ins/ins_state.h"

namespace navtwin::gnss_ins {
namespace {

std::string Num(double x) {
  std::ostringstream s;
  s.precision(12);
  s << x;
  return s.str();
}

void RequireFinite(bool ok, const std::string& file, const std::string& field, double t_s) {
  if (!ok) throw InputError(file, 0, field, "not a finite number (sample at t = " + Num(t_s) + " s)");
}

/// Barometric altitude from pressure in the ISA troposphere (ISO 2533):
/// h = T0/L (1 - (p/p0)^(1/5.255877)), T0 = 288.15 K, L = 0.0065 K/m, p0 = 101325 Pa.
/// Only height differences matter (the offset to the ellipsoid is estimated).
double IsaAltitude_m(double pressure_pa) {
  return 288.15 / 0.0065 * (1.0 - std::pow(pressure_pa / 101325.0, 1.0 / 5.255877));
}

/// The calibration file's parts that apply to a run, and the installation in force.
struct RunCalibration {
  std::optional<ImuCalibration> imu;
  std::optional<MagCorrection> mag;  ///< only when a magnetometer file is read
  Installation installation;         ///< the configuration's, or the calibration file's
  bool installation_from_file = false;
};

/// Reads paths.calibration (empty: the configuration's installation, nothing else). The
/// file must hold something for this run: an imu or installation section, or a mag section
/// when a magnetometer is read. Its installation replaces the configuration's mounting and
/// time offset, which must then be zero: a mounting or offset given twice is refused
/// rather than composed or overridden silently.
RunCalibration ReadRunCalibration(const InputPaths& paths, const Installation& configured) {
  RunCalibration c;
  c.installation = configured;
  if (paths.calibration.empty()) return c;
  const CalibrationFile file = ReadCalibrationFile(paths.calibration);
  c.imu = file.imu;
  if (!paths.mag.empty()) c.mag = file.mag;
  if (!c.imu && !c.mag && !file.installation) {
    throw InputError(paths.calibration, 0, "imu",
                     paths.mag.empty() ? "neither an imu nor an installation section: nothing applies to the IMU"
                                       : "no imu, mag or installation section: nothing to calibrate");
  }
  if (file.installation) {
    if (!configured.imu_mounting_rpy_rad.isZero(0.0) || configured.imu_time_offset_s != 0.0) {
      throw InputError(paths.calibration, 0, "installation",
                       "the configuration sets installation.imu_mounting_deg or imu_time_offset_s as well: give the "
                       "IMU's mounting and time offset in one place (set them to 0 in the configuration)");
    }
    c.installation.imu_mounting_rpy_rad = file.installation->mounting_rpy_rad;
    c.installation.imu_time_offset_s = file.installation->time_offset_s;
    c.installation_from_file = true;
  }
  return c;
}

std::vector<ImuSample> ReadImu(const std::string& path, const RunCalibration& calibration, double temperature_degC,
                               const GnssInsConfig& config) {
  const Installation& inst = calibration.installation;
  const Eigen::Vector3d& rpy = inst.imu_mounting_rpy_rad;
  // v_b = R_b_imu v_imu (config.h, Installation).
  const Eigen::Matrix3d R_b_imu = DcmFromEuler(rpy[0], rpy[1], rpy[2]);
  auto reader = OpenImu(path);
  if (calibration.imu) reader = CalibratedImuReader(std::move(reader), *calibration.imu, temperature_degC);
  std::vector<ImuSample> out;
  ImuSample s;
  while (reader->Next(&s)) {
    RequireFinite(std::isfinite(s.t_s) && std::isfinite(s.dt_s), path, "time", s.t_s);
    RequireFinite(s.dtheta_b_rad.allFinite(), path, "dtheta", s.t_s);
    RequireFinite(s.dv_b_mps.allFinite(), path, "dv", s.t_s);
    s.t_s += inst.imu_time_offset_s;
    if (s.t_s - s.dt_s < config.start_time_s - ins::kSameEpoch_s) continue;
    if (s.t_s > config.end_time_s + ins::kSameEpoch_s) break;
    s.dtheta_b_rad = R_b_imu * s.dtheta_b_rad;
    s.dv_b_mps = R_b_imu * s.dv_b_mps;
    out.push_back(s);
  }
  if (out.size() < 2) {
    throw InputError(path, 0, "time",
                     "fewer than 2 IMU samples inside the configured span [" +
                         Num(config.start_time_s) + ", " + Num(config.end_time_s) + "] s");
  }
  return out;
}

std::vector<GnssSample> ReadGnss(const std::string& path, double t_begin, double t_end) {
  auto reader = OpenGnss(path);
  std::vector<GnssSample> out;
  GnssSample g;
  double previous_t = -std::numeric_limits<double>::infinity();
  while (reader->Next(&g)) {
    // The readers check these already (and name the line); kept as a safety net for
    // every format.
    RequireFinite(std::isfinite(g.t_s), path, "time", g.t_s);
    RequireFinite(std::isfinite(g.lat_rad) && std::isfinite(g.lon_rad) && std::isfinite(g.h_m), path,
                  "position", g.t_s);
    if (!(g.t_s > previous_t)) {
      throw InputError(path, 0, "time",
                       "GNSS epoch t = " + Num(g.t_s) + " s is not after the previous one (" +
                           Num(previous_t) + " s): epochs out of order or duplicated");
    }
    previous_t = g.t_s;
    for (int i = 0; i < 3; ++i) {
      const double ps = g.pos_std_ned_m[i];
      if (!std::isnan(ps) && !(ps > 0.0 && std::isfinite(ps))) {
        throw InputError(path, 0, "position sigma",
                         "must be > 0 and finite (epoch t = " + Num(g.t_s) + " s)");
      }
      const double vs = g.vel_std_ned_mps[i];
      if (g.has_velocity && !std::isnan(vs) && !(vs > 0.0 && std::isfinite(vs))) {
        throw InputError(path, 0, "velocity sigma",
                         "must be > 0 and finite (epoch t = " + Num(g.t_s) + " s)");
      }
    }
    if (g.has_velocity) RequireFinite(g.v_n_mps.allFinite(), path, "velocity", g.t_s);
    if (g.t_s < t_begin - ins::kSameEpoch_s) continue;
    if (g.t_s > t_end + ins::kSameEpoch_s) continue;  // keep reading: later lines are still checked
    out.push_back(g);
  }
  return out;
}

std::vector<MagSample> ReadMag(const std::string& path, const std::optional<MagCorrection>& calibration,
                               double t_begin, double t_end) {
  auto reader = OpenMag(path);
  if (calibration) reader = CalibratedMagReader(std::move(reader), *calibration);
  std::vector<MagSample> out;
  MagSample m;
  while (reader->Next(&m)) {
    RequireFinite(std::isfinite(m.t_s), path, "time", m.t_s);
    RequireFinite(m.m_b_uT.allFinite(), path, "field", m.t_s);
    if (m.t_s < t_begin - ins::kSameEpoch_s) continue;
    if (m.t_s > t_end + ins::kSameEpoch_s) break;
    out.push_back(m);
  }
  return out;
}

/// Odometer speeds inside [t_begin, t_end]; none there is an InputError.
std::vector<OdometerSample> ReadOdometerSpan(const std::string& path, double t_begin, double t_end) {
  std::vector<OdometerSample> out;
  for (const OdometerSample& s : ReadOdometer(path)) {
    if (s.t_s >= t_begin - ins::kSameEpoch_s && s.t_s <= t_end + ins::kSameEpoch_s) out.push_back(s);
  }
  if (out.empty()) {
    throw InputError(path, 0, "t", "no odometer sample inside the IMU record [" + Num(t_begin) + ", " +
                                       Num(t_end) + "] s");
  }
  return out;
}

std::vector<BaroSample> ReadBaro(const std::string& path, double t_begin, double t_end) {
  auto reader = OpenBaro(path);
  std::vector<BaroSample> out;
  BaroSample b;
  while (reader->Next(&b)) {
    RequireFinite(std::isfinite(b.t_s), path, "time", b.t_s);
    if (!std::isfinite(b.altitude_m)) {
      if (!(std::isfinite(b.pressure_pa) && b.pressure_pa > 0.0)) {
        throw InputError(path, 0, "altitude_m",
                         "neither an altitude nor a positive pressure (sample at t = " + Num(b.t_s) +
                             " s)");
      }
      b.altitude_m = IsaAltitude_m(b.pressure_pa);
    }
    if (b.t_s < t_begin - ins::kSameEpoch_s) continue;
    if (b.t_s > t_end + ins::kSameEpoch_s) break;
    out.push_back(b);
  }
  return out;
}

}  // namespace

Inputs LoadInputs(const InputPaths& paths, const GnssInsConfig& config) {
  if (paths.imu.empty()) throw InputError("(no file)", 0, "imu", "no IMU file given");
  if (paths.gnss.empty()) throw InputError("(no file)", 0, "gnss", "no GNSS file given");
  // The calibration file's sections that apply (an empty path: none).
  const RunCalibration calibration = ReadRunCalibration(paths, config.installation);
  Inputs in;
  in.paths = paths;
  in.installation = calibration.installation;
  in.installation_from_calibration = calibration.installation_from_file;
  in.imu = ins::BridgeGaps(ReadImu(paths.imu, calibration, paths.imu_temperature_degC, config), paths.imu,
                           calibration.installation.imu_time_offset_s, config.filter.max_bridge_gap_s,
                           "filter.max_bridge_gap_s", &in.bridged_imu_gaps);
  const double t_begin = in.imu.front().t_s - in.imu.front().dt_s;
  const double t_end = in.imu.back().t_s;

  in.gnss = ReadGnss(paths.gnss, t_begin, t_end);
  if (in.gnss.empty()) {
    throw InputError(paths.gnss, 0, "time",
                     "no GNSS epoch inside the IMU span [" + Num(t_begin) + ", " + Num(t_end) +
                         "] s (check the time scales: GPS seconds of week vs. relative time, "
                         "installation.imu_time_offset_s)");
  }

  // Injected outages: [t_begin + start + k period, ... + len), k = 0, 1, ... .
  const OutageConfig& o = config.outages;
  if (!std::isnan(o.start_s)) {
    if (!(o.len_s > 0.0) || o.start_s < 0.0 || o.period_s < 0.0 ||
        (o.period_s > 0.0 && o.period_s <= o.len_s)) {
      throw std::invalid_argument("outages: need start_s >= 0, len_s > 0 and period_s 0 or > len_s");
    }
    for (double a = t_begin + o.start_s; a < t_end; a += o.period_s) {
      in.outages.emplace_back(a, a + o.len_s);
      if (o.period_s <= 0.0) break;
    }
    std::vector<GnssSample> kept;
    kept.reserve(in.gnss.size());
    std::size_t k = 0;
    for (const GnssSample& g : in.gnss) {
      while (k < in.outages.size() && g.t_s >= in.outages[k].second) ++k;
      if (k < in.outages.size() && g.t_s >= in.outages[k].first) {
        ++in.gnss_removed_by_outages;
        in.gnss_removed.push_back(g);
      } else {
        kept.push_back(g);
      }
    }
    in.gnss = std::move(kept);
    if (in.gnss.empty()) {
      throw InputError(paths.gnss, 0, "time", "the injected outages remove every GNSS epoch");
    }
  }

  if (!paths.mag.empty()) in.mag = ReadMag(paths.mag, calibration.mag, t_begin, t_end);
  if (!paths.baro.empty()) in.baro = ReadBaro(paths.baro, t_begin, t_end);
  if (config.odometer.enabled()) {
    in.odometer = ReadOdometerSpan(config.odometer.from_imu_file ? paths.imu : config.odometer.file, t_begin, t_end);
  }
  return in;
}

}  // namespace navtwin::gnss_ins
