// LoadInputs (inputs.h): reads the IMU, GNSS, magnetometer and barometer records, applies
// the installation, cuts to the configured time span, bridges short IMU gaps, injects the
// scoring outages and checks what the estimators rely on (docs/gnss-ins.md "Bad input").
#include "problems/gnss_ins/inputs.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
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

/// The IMU samples of a reader in the run's terms: finite, on the GNSS time scale (the
/// installation's time offset added), inside [start_time_s, end_time_s] (the sample holding
/// the start included), in the body axes (the mounting applied).
class InstalledImuReader final : public ImuReader {
 public:
  InstalledImuReader(std::unique_ptr<ImuReader> reader, const Installation& installation, const GnssInsConfig& config)
      : reader_(std::move(reader)),
        // v_b = R_b_imu v_imu (config.h, Installation).
        R_b_imu_(DcmFromEuler(installation.imu_mounting_rpy_rad[0], installation.imu_mounting_rpy_rad[1],
                              installation.imu_mounting_rpy_rad[2])),
        time_offset_s_(installation.imu_time_offset_s),
        start_s_(config.start_time_s),
        end_s_(config.end_time_s) {}

  bool Next(ImuSample* out) override {
    ImuSample s;
    while (!ended_ && reader_->Next(&s)) {
      const std::string& file = reader_->path();
      RequireFinite(std::isfinite(s.t_s) && std::isfinite(s.dt_s), file, "time", s.t_s);
      RequireFinite(s.dtheta_b_rad.allFinite(), file, "dtheta", s.t_s);
      RequireFinite(s.dv_b_mps.allFinite(), file, "dv", s.t_s);
      s.t_s += time_offset_s_;
      if (s.t_s - s.dt_s < start_s_ - ins::kSameEpoch_s) continue;
      if (s.t_s > end_s_ + ins::kSameEpoch_s) break;
      s.dtheta_b_rad = R_b_imu_ * s.dtheta_b_rad;
      s.dv_b_mps = R_b_imu_ * s.dv_b_mps;
      *out = s;
      return true;
    }
    ended_ = true;  // the rest of the file lies after end_time_s
    return false;
  }
  const std::string& path() const override { return reader_->path(); }

 private:
  std::unique_ptr<ImuReader> reader_;
  Eigen::Matrix3d R_b_imu_;
  double time_offset_s_, start_s_, end_s_;
  bool ended_ = false;
};

/// The IMU record: the file (any format), its calibration, the installation, the span,
/// the gaps bridged; in memory or streamed. Fewer than two samples in the span is an
/// InputError.
ins::ImuRecord ReadImu(const std::string& path, const RunCalibration& calibration, double temperature_degC,
                       const GnssInsConfig& config, ImuStorage storage) {
  const ins::ImuRecord::Opener open = [=](std::size_t* bridged) {
    auto reader = OpenImu(path);
    if (calibration.imu) reader = CalibratedImuReader(std::move(reader), *calibration.imu, temperature_degC);
    reader = std::make_unique<InstalledImuReader>(std::move(reader), calibration.installation, config);
    return ins::GapBridgingImuReader(std::move(reader), config.filter.max_bridge_gap_s, "filter.max_bridge_gap_s",
                                     calibration.installation.imu_time_offset_s, bridged);
  };
  ins::ImuRecord record = ins::ImuRecord::Streamed(open);
  if (storage == ImuStorage::kInMemory) {
    std::size_t bridged = 0;
    std::vector<ImuSample> samples = ReadAll(*open(&bridged));
    record = ins::ImuRecord(std::move(samples), bridged);
  }
  const std::vector<ImuSample>& head = record.Head(-std::numeric_limits<double>::infinity());
  if (head.empty() || record.Head(head.front().t_s + ins::kSameEpoch_s).size() < 2) {
    throw InputError(path, 0, "time",
                     "fewer than 2 IMU samples inside the configured span [" +
                         Num(config.start_time_s) + ", " + Num(config.end_time_s) + "] s");
  }
  return record;
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

InputError NoOdometerInSpan(const std::string& path, double t_begin_s, double t_end_s) {
  return InputError(path, 0, "t", "no odometer sample inside the IMU record [" + Num(t_begin_s) + ", " +
                                      Num(t_end_s) + "] s");
}

/// Odometer speeds inside [t_begin, t_end]; none there is an InputError.
std::vector<OdometerSample> ReadOdometerSpan(const std::string& path, double t_begin, double t_end) {
  std::vector<OdometerSample> out;
  for (const OdometerSample& s : ReadOdometer(path)) {
    if (s.t_s >= t_begin - ins::kSameEpoch_s && s.t_s <= t_end + ins::kSameEpoch_s) out.push_back(s);
  }
  if (out.empty()) throw NoOdometerInSpan(path, t_begin, t_end);
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

/// Injected outages: [t_begin + start + k period, ... + len), k = 0, 1, ..., up to the last
/// GNSS epoch; the epochs inside them move from in->gnss to in->gnss_removed.
void InjectOutages(const OutageConfig& o, double t_begin, Inputs* in) {
  if (std::isnan(o.start_s)) return;
  if (!(o.len_s > 0.0) || o.start_s < 0.0 || o.period_s < 0.0 || (o.period_s > 0.0 && o.period_s <= o.len_s)) {
    throw std::invalid_argument("outages: need start_s >= 0, len_s > 0 and period_s 0 or > len_s");
  }
  const double last_gnss_s = in->gnss.back().t_s;
  for (double a = t_begin + o.start_s; a <= last_gnss_s; a += o.period_s) {
    in->outages.emplace_back(a, a + o.len_s);
    if (o.period_s <= 0.0) break;
  }
  std::vector<GnssSample> kept;
  kept.reserve(in->gnss.size());
  std::size_t k = 0;
  for (const GnssSample& g : in->gnss) {
    while (k < in->outages.size() && g.t_s >= in->outages[k].second) ++k;
    if (k < in->outages.size() && g.t_s >= in->outages[k].first) {
      ++in->gnss_removed_by_outages;
      in->gnss_removed.push_back(g);
    } else {
      kept.push_back(g);
    }
  }
  in->gnss = std::move(kept);
  if (in->gnss.empty()) throw InputError(in->paths.gnss, 0, "time", "the injected outages remove every GNSS epoch");
}

/// The samples of `v` up to t_end_s (a record's samples are in time order).
template <typename Sample>
void CutAfter(double t_end_s, std::vector<Sample>* v) {
  const auto after = std::upper_bound(v->begin(), v->end(), t_end_s + ins::kSameEpoch_s,
                                      [](double t, const Sample& x) { return t < x.t_s; });
  v->erase(after, v->end());
}

std::string NoGnssInSpan(double t_begin, double t_end) {
  return "no GNSS epoch inside the IMU span [" + Num(t_begin) + ", " + Num(t_end) +
         "] s (check the time scales: GPS seconds of week vs. relative time, installation.imu_time_offset_s)";
}

}  // namespace

Inputs LoadInputs(const InputPaths& paths, const GnssInsConfig& config, ImuStorage storage) {
  if (paths.imu.empty()) throw InputError("(no file)", 0, "imu", "no IMU file given");
  if (paths.gnss.empty()) throw InputError("(no file)", 0, "gnss", "no GNSS file given");
  // The calibration file's sections that apply (an empty path: none).
  const RunCalibration calibration = ReadRunCalibration(paths, config.installation);
  Inputs in;
  in.paths = paths;
  in.installation = calibration.installation;
  in.installation_from_calibration = calibration.installation_from_file;
  in.imu = ReadImu(paths.imu, calibration, paths.imu_temperature_degC, config, storage);
  const double t_begin = in.imu.begin_s();
  const double t_end = in.imu.known_end_s();  // +infinity for a streamed record

  in.gnss = ReadGnss(paths.gnss, t_begin, t_end);
  if (in.gnss.empty()) throw InputError(paths.gnss, 0, "time", NoGnssInSpan(t_begin, t_end));
  InjectOutages(config.outages, t_begin, &in);
  if (!paths.mag.empty()) in.mag = ReadMag(paths.mag, calibration.mag, t_begin, t_end);
  if (!paths.baro.empty()) in.baro = ReadBaro(paths.baro, t_begin, t_end);
  if (config.odometer.enabled()) {
    in.odometer_file = config.odometer.from_imu_file ? paths.imu : config.odometer.file;
    in.odometer = ReadOdometerSpan(in.odometer_file, t_begin, t_end);
  }
  if (in.imu.end_known()) CutToImuEnd(&in);
  return in;
}

void CutToImuEnd(Inputs* in) {
  const double t_end = in->imu.back().t_s;
  CutAfter(t_end, &in->gnss);
  if (in->gnss.empty()) throw InputError(in->paths.gnss, 0, "time", NoGnssInSpan(in->imu.begin_s(), t_end));
  CutAfter(t_end, &in->gnss_removed);
  in->gnss_removed_by_outages = in->gnss_removed.size();
  while (!in->outages.empty() && in->outages.back().first >= t_end) in->outages.pop_back();
  CutAfter(t_end, &in->mag);
  CutAfter(t_end, &in->baro);
  if (!in->odometer.empty()) {
    CutAfter(t_end, &in->odometer);
    if (in->odometer.empty()) throw NoOdometerInSpan(in->odometer_file, in->imu.begin_s(), t_end);
  }
}

}  // namespace navtwin::gnss_ins
