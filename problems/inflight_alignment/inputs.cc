#include "problems/inflight_alignment/inputs.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "core/calibration_file.h"
#include "core/io/input_error.h"
#include "core/io/open.h"
#include "core/sim/simulator.h"

namespace navtwin::inflight {
namespace {

std::string Name(const std::string& path, const char* fallback) { return path.empty() ? fallback : path; }

// Samples are counted from 1 in messages ("sample N" stands where a text file has a line).
[[noreturn]] void Fail(const std::string& file, std::size_t index, const std::string& field,
                       const std::string& reason) {
  throw InputError(file, 0, "sample " + std::to_string(index + 1) + ": " + field, reason);
}

bool Finite3(const Eigen::Vector3d& v) { return v.allFinite(); }

}  // namespace

void ValidateInputs(const InflightInputs& in) {
  const std::string imu = Name(in.imu_path, "IMU input");
  const std::string gnss = Name(in.gnss_path, "GNSS input");
  const std::string baro = Name(in.baro_path, "barometer input");
  if (in.imu.empty()) throw InputError(imu, 0, "imu", "no IMU samples");
  if (in.gnss.empty()) throw InputError(gnss, 0, "gnss", "no GNSS fixes");
  for (std::size_t i = 0; i < in.imu.size(); ++i) {
    const ImuSample& s = in.imu[i];
    if (!std::isfinite(s.t_s)) Fail(imu, i, "t_s", "not finite");
    if (!(s.dt_s > 0.0) || !std::isfinite(s.dt_s)) Fail(imu, i, "dt_s", "must be positive and finite");
    if (!Finite3(s.dtheta_b_rad)) Fail(imu, i, "dtheta_b_rad", "not finite");
    if (!Finite3(s.dv_b_mps)) Fail(imu, i, "dv_b_mps", "not finite");
    if (i > 0 && !(s.t_s > in.imu[i - 1].t_s)) Fail(imu, i, "t_s", "time does not increase");
  }
  for (std::size_t i = 0; i < in.gnss.size(); ++i) {
    const GnssSample& g = in.gnss[i];
    if (!std::isfinite(g.t_s)) Fail(gnss, i, "t_s", "not finite");
    if (!std::isfinite(g.lat_rad) || std::abs(g.lat_rad) >= M_PI / 2) Fail(gnss, i, "latitude", "not a latitude");
    if (!std::isfinite(g.lon_rad)) Fail(gnss, i, "longitude", "not finite");
    if (!std::isfinite(g.h_m)) Fail(gnss, i, "height", "not finite");
    if (i > 0 && !(g.t_s > in.gnss[i - 1].t_s)) Fail(gnss, i, "t_s", "time does not increase");
  }
  for (std::size_t i = 0; i < in.baro.size(); ++i) {
    if (!std::isfinite(in.baro[i].t_s)) Fail(baro, i, "t_s", "not finite");
    if (!std::isfinite(in.baro[i].altitude_m)) Fail(baro, i, "altitude_m", "not finite (the barometer file needs altitudes)");
    if (i > 0 && !(in.baro[i].t_s > in.baro[i - 1].t_s)) Fail(baro, i, "t_s", "time does not increase");
  }
  const NavState& x = in.initial;
  if (!std::isfinite(x.t_s) || !std::isfinite(x.lat_rad) || !std::isfinite(x.lon_rad) || !std::isfinite(x.h_m) ||
      !x.v_n_mps.allFinite() || !x.q_n_b.coeffs().allFinite())
    throw InputError("initial state", 0, "initial", "not finite");
  const double t_first = in.imu.front().t_s - in.imu.front().dt_s;
  if (x.t_s < t_first - 1e-6 || x.t_s >= in.imu.back().t_s)
    throw InputError(imu, 0, "t_s",
                     "the initial state's time " + std::to_string(x.t_s) + " s is outside the IMU span [" +
                         std::to_string(t_first) + ", " + std::to_string(in.imu.back().t_s) + "] s");
  const auto fixes_after = std::count_if(in.gnss.begin(), in.gnss.end(), [&](const GnssSample& g) {
    return g.t_s > x.t_s && g.t_s <= in.imu.back().t_s;
  });
  if (fixes_after < 10)
    throw InputError(gnss, 0, "t_s",
                     "only " + std::to_string(fixes_after) +
                         " GNSS fixes fall between the initial state and the end of the IMU data (10 needed)");
}

double BaroAltitudeAt(const std::vector<BaroSample>& baro, double t_s) {
  if (baro.empty()) return std::nan("");
  if (t_s <= baro.front().t_s) return baro.front().altitude_m;
  if (t_s >= baro.back().t_s) return baro.back().altitude_m;
  const auto it = std::lower_bound(baro.begin(), baro.end(), t_s,
                                   [](const BaroSample& b, double t) { return b.t_s < t; });
  const BaroSample& b1 = *it;
  const BaroSample& b0 = *(it - 1);
  const double w = (t_s - b0.t_s) / (b1.t_s - b0.t_s);
  return b0.altitude_m + w * (b1.altitude_m - b0.altitude_m);
}

InflightInputs LoadInflightInputs(const InflightFiles& files) {
  if (files.imu.empty()) throw std::invalid_argument("an IMU file is needed");
  if (files.gnss.empty()) throw std::invalid_argument("a GNSS file is needed");
  if (files.init.empty()) throw std::invalid_argument("a navigation file with the initial state is needed");
  InflightInputs in;
  in.imu_path = files.imu;
  in.gnss_path = files.gnss;
  in.baro_path = files.baro;
  in.imu = ReadAll<ImuSample>(*OpenImu(files.imu, files.calibration, files.imu_temperature_degC));
  in.gnss = ReadAll<GnssSample>(*OpenGnss(files.gnss));
  if (!files.baro.empty()) in.baro = ReadAll<BaroSample>(*OpenBaro(files.baro));
  {
    auto reader = OpenNav(files.init);
    NavState s;
    bool found = false;
    while (reader->Next(&s)) {
      if (files.init_time_s < 0.0 || s.t_s >= files.init_time_s - 1e-9) {
        found = true;
        break;
      }
    }
    if (!found)
      throw InputError(files.init, 0, "t_s",
                       files.init_time_s < 0.0 ? std::string("no navigation record")
                                               : "no record at or after " + std::to_string(files.init_time_s) + " s");
    in.initial = s;
  }
  if (!files.truth.empty()) in.truth = ReadAll<NavState>(*OpenNav(files.truth));
  ValidateInputs(in);
  return in;
}

InflightInputs SimulateInflightInputs(const sim::Scenario& scenario, std::uint64_t seed, bool perfect) {
  if (!scenario.gnss) throw std::invalid_argument("scenario " + scenario.name + " has no GNSS");
  sim::SimulationOptions options;
  options.seed = seed;
  options.perfect = perfect;
  const sim::TemporarySimulation simulated(scenario, options, "navtwin_inflight_");
  InflightFiles files;
  files.imu = simulated.path("imu.txt");
  files.gnss = simulated.path("gnss.txt");
  if (scenario.baro) files.baro = simulated.path("baro.csv");
  files.init = simulated.path("init.nav");
  files.truth = simulated.path("truth.nav");
  InflightInputs in = LoadInflightInputs(files);
  in.imu_path = "simulated " + scenario.name + " imu.txt";
  in.gnss_path = "simulated " + scenario.name + " gnss.txt";
  in.baro_path = scenario.baro ? "simulated " + scenario.name + " baro.csv" : "";
  return in;
}

}  // namespace navtwin::inflight
