// The navtwin configuration (docs/gnss-ins.md) a user of a simulated scenario would write:
// the scenario's IMU specification (noise densities, turn-on bias and scale-factor
// sigmas), the installation (lever arm; a GNSS latency as gnss.time_offset_s), the initial
// state from init.nav, and, for the magnetometer,
// the calibration and Earth field the simulation drew (errors.yaml) — what a user gets
// from a magnetometer calibration and a field model. Used by `navtwin smooth --demo`.
#pragma once

#include <cstdint>
#include <string>

#include "core/sim/scenario.h"

namespace navtwin::gnss_ins {

/// YAML text for the scenario simulated into sim_dir (which holds errors.yaml and
/// init.nav) with the given seed. mag_mode: off, vector, heading or heading_2axis
/// (anything but off needs a scenario with a magnetometer). Throws std::invalid_argument
/// for an unknown mode or a scenario without GNSS, std::runtime_error when errors.yaml
/// lacks the magnetometer's values.
std::string ConfigYamlForSimulation(const sim::Scenario& scenario, const std::string& sim_dir,
                                    std::uint64_t seed, const std::string& mag_mode);

}  // namespace navtwin::gnss_ins
