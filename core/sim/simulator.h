// Runs a scenario and writes its files (formats in docs/formats.md):
//   imu.txt    KF-GINS IMU increments (the simulated IMU, its own axes and time tags)
//   truth.nav  KF-GINS navigation format at the IMU rate (body reference point)
//   init.nav   the initial state an estimator is given (truth + init_errors), one record
//   gnss.txt   KF-GINS GNSS with velocity (13 columns)       when the scenario has gnss
//   mag.csv    t_s,mx_uT,my_uT,mz_uT                           when it has mag
//   baro.csv   t_s,pressure_pa,altitude_m,temperature_degC     when it has baro
//   master.nav KF-GINS navigation format, delivered late        when it has master
//   angle.csv  t_s,theta_rad: the pivot encoder, one reading per IMU sample (its time tag),
//              the angle at that sample's truth time              when it is a pendulum rig
//   temperature.csv t_s,temperature_degC: the IMU's temperature sensor, one reading per
//              IMU sample (its time tag), the profile at that sample's truth time
//                                             when imu.errors.temperature_profile is not constant
//   errors.yaml every drawn error value, with units in the keys, and the seed
// All files appear whole or not at all. Times start at 0 s (GPS week 0).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/sim/scenario.h"

namespace navtwin::sim {

struct SimulationOptions {
  std::uint64_t seed = 1;
  bool perfect = false;  ///< every sensor error off (noise, biases, iron, outliers, vibration)
  /// Called about every 5 % of the run with the fraction done (may be empty).
  std::function<void(double)> progress;
};

struct SimulationReport {
  std::vector<std::string> files;  ///< paths written
  std::size_t imu_samples = 0;
  std::size_t gnss_samples = 0;
  std::size_t mag_samples = 0;
  std::size_t baro_samples = 0;
  std::size_t odometer_samples = 0;
  std::size_t master_samples = 0;
  double run_time_s = 0.0;
};

/// Simulates `scenario` into the folder out_dir (which must exist).
SimulationReport Simulate(const Scenario& scenario, const SimulationOptions& options,
                          const std::string& out_dir);

/// A scenario simulated into a fresh temporary folder (under the system's temporary
/// directory, named prefix + random suffix), removed with this object: for commands that
/// simulate and then read the files back as a user would. Throws std::runtime_error when
/// the folder cannot be created, and what Simulate throws.
class TemporarySimulation {
 public:
  TemporarySimulation(const Scenario& scenario, const SimulationOptions& options, const std::string& prefix);
  ~TemporarySimulation();
  TemporarySimulation(const TemporarySimulation&) = delete;
  TemporarySimulation& operator=(const TemporarySimulation&) = delete;

  const std::string& dir() const { return dir_; }
  /// dir() + "/" + file (e.g. "imu.txt").
  std::string path(const std::string& file) const { return dir_ + "/" + file; }
  const SimulationReport& report() const { return report_; }

 private:
  std::string dir_;
  SimulationReport report_;
};

}  // namespace navtwin::sim
