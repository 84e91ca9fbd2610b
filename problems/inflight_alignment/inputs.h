// Inputs of the in-flight heading alignment (issue 7): read from files, or simulated from
// a scenario with a seed (`navtwin inflight-align --scenario`), and checked once.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/sim/scenario.h"
#include "core/types.h"

namespace navtwin::inflight {

/// Everything a run needs, read from files or produced by the simulator.
struct InflightInputs {
  std::vector<ImuSample> imu;    ///< body-axes increments; those after initial.t_s are used
  std::vector<GnssSample> gnss;  ///< raw fixes (the smoother is applied by the filter)
  std::vector<BaroSample> baro;  ///< altitude_m used; may be empty (then height is held)
  NavState initial;              ///< the INS initial state, at initial.t_s
  std::vector<NavState> truth;   ///< optional reference (heading errors); may be empty
  std::string imu_path, gnss_path, baro_path;  ///< for messages (may be empty)
};

/// Checks the inputs: IMU and GNSS non-empty, times increasing, finite values, the
/// initial state finite and inside the IMU span, at least 10 GNSS fixes after it, baro
/// altitudes finite. Throws InputError naming the file (the *_path members), the sample
/// ("sample N", counted from 1) and the field.
void ValidateInputs(const InflightInputs& inputs);

/// Barometric altitude at time t by linear interpolation (held at the ends); NaN if
/// there are no samples. Samples must be sorted by time.
double BaroAltitudeAt(const std::vector<BaroSample>& baro, double t_s);

struct InflightFiles {
  std::string imu, gnss, baro;  ///< baro may be empty
  std::string init;   ///< navigation file whose first record at or after init_time_s is the initial state
  double init_time_s = -1.0;  ///< < 0: the first record
  std::string truth;  ///< navigation file; may be empty
  /// Calibration file (core/calibration_file.h) applied to the IMU, or empty; its
  /// temperature terms at imu_temperature_degC (NaN: the file's reference temperature).
  std::string calibration;
  double imu_temperature_degC = std::numeric_limits<double>::quiet_NaN();
};

/// Reads the files with the core/io readers (any format they know) and validates.
InflightInputs LoadInflightInputs(const InflightFiles& files);

/// Simulates a scenario with a seed into a fresh temporary folder, reads it back as a
/// user would (init.nav the initial state, truth.nav the truth), removes the folder.
/// `perfect`: every sensor error off (sim::SimulationOptions).
InflightInputs SimulateInflightInputs(const sim::Scenario& scenario, std::uint64_t seed, bool perfect = false);

}  // namespace navtwin::inflight
