// Inputs of transfer alignment (inputs.h): read from files or simulated from a scenario
// with a master INS, and checked once before any method runs.
//
// Frames: the slave IMU measures in its own axes s; the misalignment is R_b_s (slave axes
// to the master's body FRD), so the slave's attitude is R_n_s = R_n_b R_b_s. The
// simulator mounts the IMU with imu.mounting_rpy_rad = (r, p, y) such that
// v_b = DcmFromEuler(r, p, y) v_imu (core/sim/imu_simulator.cc rotates body increments by
// the transpose), hence R_b_s_true = DcmFromEuler(r, p, y).
#include "problems/transfer_alignment/inputs.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/calibration_file.h"
#include "core/io/input_error.h"
#include "core/io/open.h"
#include "core/rotation.h"
#include "core/sim/simulator.h"

namespace navtwin::transfer {
namespace {

std::string Name(const std::string& path, const char* fallback) { return path.empty() ? fallback : path; }

// Samples and records are counted from 1 in messages ("sample N" where a text file has a line:
// the inputs may come from any reader, or from memory).
[[noreturn]] void Fail(const std::string& file, const char* what, std::size_t index, const std::string& field,
                       const std::string& reason) {
  throw InputError(file, 0, std::string(what) + " " + std::to_string(index + 1) + ": " + field, reason);
}

bool FiniteNav(const NavState& x) {
  return std::isfinite(x.t_s) && std::isfinite(x.lat_rad) && std::isfinite(x.lon_rad) && std::isfinite(x.h_m) &&
         x.v_n_mps.allFinite() && x.q_n_b.coeffs().allFinite() && x.q_n_b.norm() > 0.5;
}

/// Checks a navigation stream: finite fields, strictly increasing times.
void CheckNavStream(const std::vector<NavState>& s, const std::string& file, const char* what) {
  for (std::size_t i = 0; i < s.size(); ++i) {
    const NavState& x = s[i];
    if (!std::isfinite(x.t_s)) Fail(file, what, i, "t_s", "not finite");
    if (!std::isfinite(x.lat_rad) || std::abs(x.lat_rad) >= M_PI / 2) Fail(file, what, i, "latitude", "not a latitude");
    if (!std::isfinite(x.lon_rad)) Fail(file, what, i, "longitude", "not finite");
    if (!std::isfinite(x.h_m)) Fail(file, what, i, "height", "not finite");
    if (!x.v_n_mps.allFinite()) Fail(file, what, i, "velocity", "not finite");
    if (!x.q_n_b.coeffs().allFinite() || !(x.q_n_b.norm() > 0.5)) Fail(file, what, i, "attitude", "not a rotation");
    if (i > 0 && !(x.t_s > s[i - 1].t_s)) Fail(file, what, i, "t_s", "time does not increase");
  }
}

}  // namespace

void ValidateInputs(const TransferInputs& in) {
  const std::string imu = Name(in.slave_path, "slave IMU input");
  const std::string master = Name(in.master_path, "master input");
  if (in.slave_imu.empty()) throw InputError(imu, 0, "imu", "no slave IMU samples");
  for (std::size_t i = 0; i < in.slave_imu.size(); ++i) {
    const ImuSample& s = in.slave_imu[i];
    if (!std::isfinite(s.t_s)) Fail(imu, "sample", i, "t_s", "not finite");
    if (!(s.dt_s > 0.0) || !std::isfinite(s.dt_s)) Fail(imu, "sample", i, "dt_s", "must be positive and finite");
    if (!s.dtheta_b_rad.allFinite()) Fail(imu, "sample", i, "dtheta_b_rad", "not finite");
    if (!s.dv_b_mps.allFinite()) Fail(imu, "sample", i, "dv_b_mps", "not finite");
    if (i > 0 && !(s.t_s > in.slave_imu[i - 1].t_s)) Fail(imu, "sample", i, "t_s", "time does not increase");
  }
  // The delay compensation differentiates the master twice: three records at least.
  if (in.master.size() < 3)
    throw InputError(master, 0, "master", "needs at least 3 master records, got " + std::to_string(in.master.size()));
  CheckNavStream(in.master, master, "record");
  if (!in.truth.empty()) CheckNavStream(in.truth, "truth", "record");

  if (!FiniteNav(in.slave_initial)) throw InputError("initial state", 0, "slave_initial", "not finite");
  if (!in.misalignment_guess.coeffs().allFinite() || std::abs(in.misalignment_guess.norm() - 1.0) > 1e-6)
    throw InputError("initial state", 0, "misalignment_guess", "not a unit quaternion");
  if (in.true_misalignment && (!in.true_misalignment->coeffs().allFinite() ||
                               std::abs(in.true_misalignment->norm() - 1.0) > 1e-6))
    throw InputError("truth", 0, "true_misalignment", "not a unit quaternion");
  if (in.true_delay_s && !(std::isfinite(*in.true_delay_s) && *in.true_delay_s >= 0.0))
    throw InputError("truth", 0, "true_delay_s", "must be finite and >= 0");

  const double t_first = in.slave_imu.front().t_s - in.slave_imu.front().dt_s;
  const double t_last = in.slave_imu.back().t_s;
  const double t0 = in.slave_initial.t_s;
  if (t0 < t_first - 1e-6 || t0 >= t_last)
    throw InputError(imu, 0, "t_s",
                     "the initial state's time " + std::to_string(t0) + " s is outside the slave IMU span [" +
                         std::to_string(t_first) + ", " + std::to_string(t_last) + "] s");
  // Overlap: the filter updates at master records between the initial state and the end of
  // the IMU data; fewer than 3 leaves nothing to align on.
  const auto overlap = std::count_if(in.master.begin(), in.master.end(),
                                     [&](const NavState& m) { return m.t_s > t0 && m.t_s <= t_last; });
  if (overlap < 3)
    throw InputError(master, 0, "t_s",
                     "only " + std::to_string(overlap) + " master records fall between the initial state (" +
                         std::to_string(t0) + " s) and the end of the slave IMU data (" + std::to_string(t_last) +
                         " s); 3 needed (are both on the same time scale?)");
}

TransferInputs LoadTransferInputs(const TransferFiles& files) {
  if (files.slave_imu.empty()) throw std::invalid_argument("a slave IMU file is needed");
  if (files.master.empty()) throw std::invalid_argument("a master navigation file is needed");
  if (files.init.empty()) throw std::invalid_argument("a navigation file with the slave's initial state is needed");
  TransferInputs in;
  in.slave_path = files.slave_imu;
  in.master_path = files.master;
  in.slave_imu = ReadAll<ImuSample>(*OpenImu(files.slave_imu, files.calibration, files.imu_temperature_degC));
  in.master = ReadAll<NavState>(*OpenNav(files.master));
  if (in.slave_imu.empty()) throw InputError(files.slave_imu, 0, "imu", "no IMU samples");
  {
    // The first record at or after the start: --start_s, or the start of the slave IMU
    // data (init.nav's single record of a simulation; the first master record when the
    // master file itself initialises the slave).
    const double start_s = files.init_time_s >= 0.0
                               ? files.init_time_s
                               : in.slave_imu.front().t_s - in.slave_imu.front().dt_s;
    auto reader = OpenNav(files.init);
    NavState s;
    bool found = false;
    while (reader->Next(&s)) {
      if (s.t_s >= start_s - 1e-9) {
        found = true;
        break;
      }
    }
    if (!found)
      throw InputError(files.init, 0, "t_s", "no navigation record at or after " + std::to_string(start_s) + " s");
    // The slave INS starts from the body attitude (its mounting unknown): R_n_s = R_n_b M_guess.
    s.q_n_b = (s.q_n_b * in.misalignment_guess).normalized();
    in.slave_initial = s;
  }
  if (!files.truth.empty()) in.truth = ReadAll<NavState>(*OpenNav(files.truth));
  ValidateInputs(in);
  return in;
}

TransferInputs SimulateTransferInputs(const sim::Scenario& scenario, std::uint64_t seed,
                                      std::optional<double> delay_override_s, bool perfect) {
  if (!scenario.master) throw std::invalid_argument("scenario " + scenario.name + " has no master section");
  sim::Scenario s = scenario;
  if (delay_override_s) {
    if (!(std::isfinite(*delay_override_s) && *delay_override_s >= 0.0))
      throw std::invalid_argument("the transfer delay must be finite and >= 0 s");
    s.master->transfer_delay_s = *delay_override_s;
  }
  sim::SimulationOptions options;
  options.seed = seed;
  options.perfect = perfect;
  const sim::TemporarySimulation simulated(s, options, "navtwin_transfer_");

  TransferFiles files;
  files.slave_imu = simulated.path("imu.txt");
  files.master = simulated.path("master.nav");
  files.init = simulated.path("init.nav");  // one record at the start: truth + init_errors (body attitude)
  files.truth = simulated.path("truth.nav");
  TransferInputs in = LoadTransferInputs(files);
  const Eigen::Vector3d& rpy = s.imu.mounting_rpy_rad;
  in.true_misalignment = Eigen::Quaterniond(DcmFromEuler(rpy.x(), rpy.y(), rpy.z())).normalized();
  in.true_delay_s = s.master->transfer_delay_s;
  in.slave_path = "simulated " + s.name + " imu.txt";
  in.master_path = "simulated " + s.name + " master.nav";
  return in;
}

}  // namespace navtwin::transfer
