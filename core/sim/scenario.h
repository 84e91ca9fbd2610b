// A simulation scenario: where it starts, how the vehicle moves, and which sensors it
// carries with which errors. Read from a YAML file or a named preset (core/sim/presets.h);
// the schema is in docs/scenarios.md.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "core/earth.h"
#include "core/sim/aiding.h"
#include "core/sim/analytic_trajectory.h"
#include "core/sim/imu_simulator.h"
#include "core/config/yaml_config.h"

namespace navtwin::sim {

/// Errors of the initial state an estimator is given (written as init.nav): fixed values,
/// estimate minus truth, attitude as an attitude error rotation (roll, pitch, yaw axes of
/// NED: phi_n, R_true = Exp(phi_n) R_init).
struct InitErrorConfig {
  Eigen::Vector3d position_ned_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_ned_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d attitude_phi_n_rad = Eigen::Vector3d::Zero();
};

struct Scenario {
  std::string name;
  std::string description;
  double duration_s = 0.0;
  wgs84::Geodetic start;
  std::shared_ptr<const AnalyticTrajectory> trajectory;
  /// What the trajectory writes into errors.yaml (rigs: their truth); may be empty.
  std::function<void(YAML::Emitter&)> emit_trajectory;
  ImuSimConfig imu;
  std::optional<GnssSimConfig> gnss;
  std::optional<MagSimConfig> mag;
  std::optional<BaroSimConfig> baro;
  std::optional<OdometerSimConfig> odometer;
  std::optional<MasterSimConfig> master;
  InitErrorConfig init_errors;
};

/// Parses a scenario from a YAML root (file or preset). Throws InputError with file,
/// line and key path.
Scenario ParseScenario(const ConfigNode& root);

/// A preset name or a YAML file path.
Scenario LoadScenario(const std::string& preset_or_path);

}  // namespace navtwin::sim
