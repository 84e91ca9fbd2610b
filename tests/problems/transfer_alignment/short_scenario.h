// A short transfer-alignment flight for the tests: 2 s of cruise and a wing rock (30 deg
// roll at 0.5 Hz, pitch and yaw 5 deg at 0.25 Hz) at 200 m/s, a 100 Hz slave with a known
// mounting and small IMU errors, a 50 Hz master with its attitude error and velocity noise.
#pragma once

#include <string>

#include "core/config/yaml_config.h"
#include "core/sim/scenario.h"

namespace navtwin::transfer::test_scenarios {

inline sim::Scenario ShortTransferScenario(double wing_rock_s, double transfer_delay_s) {
  const std::string yaml = R"(name: transfer-short
start: {lat_deg: 36.0, lon_deg: 127.5, h_m: 3000}
trajectory:
  initial: {speed_mps: 200, heading_deg: 0}
  segments:
    - {kind: cruise, duration_s: 2}
    - {kind: wing_rock, duration_s: )" + std::to_string(wing_rock_s) +
                           R"(, roll_amplitude_deg: 30, roll_frequency_hz: 0.5, pitch_amplitude_deg: 5, pitch_frequency_hz: 0.25, yaw_amplitude_deg: 5, yaw_frequency_hz: 0.25}
imu:
  rate_hz: 100
  mounting_deg: [0.5, -0.3, 0.8]
  errors:
    gyro: {bias_deg_h: 1.0, arw_deg_sqrt_h: 0.05}
    accel: {bias_ug: 200, vrw_m_s_sqrt_h: 0.05}
master:
  rate_hz: 50
  transfer_delay_s: )" + std::to_string(transfer_delay_s) + R"(
  attitude_error_sigma_mrad: 0.05
  velocity_noise_mps: 0.01
init_errors: {velocity_ned_mps: [0.5, -0.5, 0.2], attitude_deg: [0.5, -0.5, 1.0]}
)";
  return sim::ParseScenario(ParseYaml(yaml, "transfer-short.yaml"));
}

}  // namespace navtwin::transfer::test_scenarios
