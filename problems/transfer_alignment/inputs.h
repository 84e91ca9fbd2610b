// Inputs of transfer alignment: the slave IMU, the master records as received, the slave
// INS's initial state, and (simulated or reference data) the truth to score against.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/sim/scenario.h"
#include "core/types.h"

namespace navtwin::transfer {

struct TransferInputs {
  std::vector<ImuSample> slave_imu;  ///< slave IMU axes (s), on the master's time scale
  std::vector<NavState> master;      ///< t_s = time tag (arrival); attitude = R_n_b (master body)
  /// The slave INS's initial navigation state; its attitude is R_n_s (slave axes), e.g.
  /// the master's first record times the initial misalignment guess, plus errors.
  NavState slave_initial;
  /// Initial guess of the misalignment R_b_s (identity when nothing is known).
  Eigen::Quaterniond misalignment_guess = Eigen::Quaterniond::Identity();
  // Reference (optional): the vehicle body truth at the IMU rate, the true misalignment
  // R_b_s and the true delay, to score against.
  std::vector<NavState> truth;
  std::optional<Eigen::Quaterniond> true_misalignment;
  std::optional<double> true_delay_s;
  std::string slave_path, master_path;  ///< for messages
};

/// Checks non-empty, increasing, finite, overlapping streams. Throws InputError naming
/// the file, the sample ("sample N") and the field.
void ValidateInputs(const TransferInputs& in);

/// Files of `navtwin transfer-align` (file mode).
struct TransferFiles {
  std::string slave_imu;  ///< the slave IMU (any format core/io reads), on the master's time scale
  std::string master;     ///< the master's navigation records as received (t = time tag)
  /// Navigation file whose record at or after init_time_s is the slave's initial state
  /// (its attitude the body attitude; R_n_s = R_n_b x the identity misalignment guess).
  std::string init;
  double init_time_s = -1.0;  ///< < 0: the start of the slave IMU data (first sample minus its dt)
  std::string truth;          ///< optional body truth (navigation file)
  /// Calibration file (core/calibration_file.h) applied to the slave IMU, or empty; its
  /// temperature terms at imu_temperature_degC (NaN: the file's reference temperature).
  std::string calibration;
  double imu_temperature_degC = std::numeric_limits<double>::quiet_NaN();
};

/// Reads the files with the core/io readers and validates (InputError: file, line, field).
/// No true misalignment or delay is known from files.
TransferInputs LoadTransferInputs(const TransferFiles& files);

/// Simulates a scenario with a master (e.g. transfer-alignment-high-maneuver) with a seed,
/// optionally overriding the transfer delay, and reads it back as a user would: imu.txt
/// (slave), master.nav, init.nav rotated into the slave axes by the identity guess (the
/// slave INS starts from the body attitude with the init errors: its mounting is unknown),
/// truth.nav; the true misalignment from the scenario's imu.mounting_deg, the true delay
/// from master.transfer_delay_s. `perfect`: every sensor error off (sim::SimulationOptions),
/// the scenario's mounting and delay kept.
TransferInputs SimulateTransferInputs(const sim::Scenario& scenario, std::uint64_t seed,
                                      std::optional<double> delay_override_s = std::nullopt, bool perfect = false);

}  // namespace navtwin::transfer
