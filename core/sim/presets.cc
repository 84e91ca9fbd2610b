#include "core/sim/presets.h"

#include <utility>

namespace navtwin::sim {
namespace {

// Seed 000: stationary leveling under rotor vibration. 600 Hz, level, vibration on body x
// at 22-24 Hz with amplitude N(0, 1 g) and a uniform phase; accelerometer white noise
// 50 mg (1 sigma per 600 Hz sample) = 0.4903 m/s^2 * sqrt(1/600 s) * 60 = 1.2010 m/s/sqrt(h).
constexpr const char* kLeveling = R"(name: leveling-600hz-vibration
description: seed 000 - stationary leveling, 600 Hz IMU, body-x vibration 22-24 Hz of N(0, 1 g), accelerometer noise 50 mg
duration_s: 10
start: {lat_deg: 36.48, lon_deg: 127.29, h_m: 60}
trajectory:
  initial: {speed_mps: 0, heading_deg: 0}
  segments:
    - {kind: static, duration_s: 10}
imu:
  rate_hz: 600
  errors:
    accel: {vrw_m_s_sqrt_h: 1.2010}
  vibration:
    tones:
      - {axes: [x], frequency_hz: [22, 24], linear_g: 1.0, amplitude: normal}
)";

// Seed 002: transfer alignment under high manoeuvres with a 300 ms transfer delay. A
// tactical-grade slave IMU mounted with an unknown misalignment; the master INS delivers
// its solution 300 ms late at 50 Hz. Wing rock of +-30 deg at 0.5 Hz gives roll rates to
// 94 deg/s and angular accelerations to 300 deg/s^2.
constexpr const char* kTransferAlignment = R"(name: transfer-alignment-high-maneuver
description: seed 002 - transfer alignment, 300 ms master-to-slave delay, large angular rate and angular acceleration
start: {lat_deg: 36.0, lon_deg: 127.5, h_m: 3000}
trajectory:
  initial: {speed_mps: 200, heading_deg: 0}
  segments:
    - {kind: cruise, duration_s: 10}
    - {kind: wing_rock, duration_s: 40, roll_amplitude_deg: 30, roll_frequency_hz: 0.5, pitch_amplitude_deg: 5, pitch_frequency_hz: 0.25, yaw_amplitude_deg: 5, yaw_frequency_hz: 0.25}
    - {kind: turn, duration_s: 20, heading_change_deg: 90}
    - {kind: s_turns, duration_s: 40, heading_amplitude_deg: 30, period_s: 20}
    - {kind: climb, duration_s: 10, flight_path_deg: 10}
    - {kind: cruise, duration_s: 10}
    - {kind: wing_rock, duration_s: 40, roll_amplitude_deg: 20, roll_frequency_hz: 1.0, pitch_amplitude_deg: 3, pitch_frequency_hz: 0.5}
    - {kind: turn, duration_s: 20, heading_change_deg: -120}
    - {kind: cruise, duration_s: 10}
imu:
  rate_hz: 100
  mounting_deg: [0.5, -0.3, 0.8]
  errors:
    gyro: {bias_deg_h: 1.0, arw_deg_sqrt_h: 0.05, scale_factor_ppm: 100, misalignment_arcsec: 20}
    accel: {bias_ug: 200, vrw_m_s_sqrt_h: 0.05, scale_factor_ppm: 100, misalignment_arcsec: 20}
master:
  rate_hz: 50
  transfer_delay_s: 0.3
  attitude_error_sigma_mrad: 0.05
  velocity_noise_mps: 0.01
init_errors: {velocity_ned_mps: [0.5, -0.5, 0.2], attitude_deg: [0.5, -0.5, 1.0]}
)";

// Seed 003: in-flight heading alignment from flight distance. A 1 NM/h INS (the seed's
// table: gyro bias 0.01 deg/h, random walk 0.005 deg/sqrt(h), accelerometer bias 100 ug,
// scale factors 100 ppm, misalignments 5 arcsec; biases fixed at +1 sigma, the east gyro
// bias being what the seed says limits a Kalman-only heading to ~3 arcmin; issue 7 found
// it does not here, docs/inflight-alignment.md), GPS 17 m (1 sigma) at 1 Hz, a
// barometer for the vertical channel. The seed's INS is aligned at rest (levels on the
// accelerometers, heading input from outside) and launched: here 5 s at rest, a launch
// acceleration to 100 m/s, a few seconds of vertical acceleration (a pull-up to 40 m/s
// vertical speed), acceleration to Mach 0.7 (238 m/s), then south. Starting at rest
// matters: a heading error rotates only the velocity the INS gains after its velocity
// was set, so the seed's "17 m / 10 km" needs the whole distance to be gained.
// Initial heading error 20 arcmin; level errors at the accelerometer-bias limit
// (100 ug = 0.34 arcmin).
constexpr const char* kInflight = R"(name: inflight-mach07-south
description: seed 003 - 1 NM/h INS, GPS 17 m, launch from rest, pull-up, Mach 0.7 south, 20 arcmin initial heading error
start: {lat_deg: 36.5, lon_deg: 127.0, h_m: 1000}
trajectory:
  initial: {speed_mps: 0, heading_deg: 180}
  segments:
    - {kind: static, duration_s: 5}
    - {kind: accelerate, duration_s: 8, speed_mps: 100}
    - {kind: climb, duration_s: 5, vertical_speed_mps: 40, transition_s: 2}
    - {kind: accelerate, duration_s: 12, speed_mps: 238}
    - {kind: cruise, duration_s: 515, level: true}
imu:
  rate_hz: 100
  errors:
    gyro: {bias_fixed_deg_h: [0.01, 0.01, 0.01], arw_deg_sqrt_h: 0.005, scale_factor_ppm: 100, misalignment_arcsec: 5}
    accel: {bias_fixed_ug: [100, 100, 100], scale_factor_ppm: 100, misalignment_arcsec: 5}
gnss: {rate_hz: 1, position_sigma_m: 17, velocity_sigma_mps: 0.1}
baro: {rate_hz: 10, bias_m: 5, noise_m: 1}
init_errors: {attitude_arcmin: [0.34, -0.34, 20]}
)";

// Seed 001 section 4: MEMS IMU (ADXRS150 gyros, ADXL210 accelerometers) with a 4th-order
// Butterworth anti-alias filter sampled at 1.6 kHz, 200 Hz output. The extracted thesis
// text reads "5Hz" for the cutoff with its zeros lost; its own criterion (phase lag < 2 deg
// and delay < 1 ms at 5 Hz) holds for a 4th-order Butterworth only from about 500 Hz
// (1.5 deg, 0.83 ms; at 50 Hz it would be 15 deg, 8.3 ms), so the cutoff is 500 Hz; gyro bias
// 0.04 deg/s (144 deg/h), accelerometer bias 0.25 m/s^2 (25.5 mg) and white noise
// 0.2 m/s^2 per 200 Hz sample (0.2 * sqrt(0.005) * 60 = 0.849 m/s/sqrt(h)); gyro noise
// 0.05 deg/s/sqrt(Hz) (ADXRS150 data sheet) = 3 deg/sqrt(h); GPS 5 Hz, 5 m CEP
// (sigma = CEP / 1.1774 = 4.25 m horizontal), 0.05 m/s; magnetometer with 0.2 deg heading
// noise (0.1 uT of a 27 uT horizontal field) at the seed's 57 deg inclination.
constexpr const char* kMemsSensors = R"(imu:
  rate_hz: 200
  anti_alias: {cutoff_hz: 500, oversample: 8}
  errors:
    gyro: {bias_deg_h: 144, arw_deg_sqrt_h: 3, scale_factor_ppm: 2000, misalignment_arcsec: 1800}
    accel: {bias_ug: 25500, vrw_m_s_sqrt_h: 0.849, scale_factor_ppm: 2000, misalignment_arcsec: 1800}
gnss: {rate_hz: 5, position_sigma_m: [4.25, 6.4], velocity_sigma_mps: 0.05, lever_arm_b_m: [0.0, 0.0, -0.3]}
mag: {rate_hz: 50, declination_deg: -8.5, inclination_deg: 57, intensity_uT: 50, noise_uT: 0.1, hard_iron_uT: 5, soft_iron: 0.02}
)";

constexpr const char* kMemsLevel = R"(name: mems-gps-mag-level-flight
description: seed 001 section 4 - MEMS IMU, 5 Hz GPS, magnetometer; straight and level flight
start: {lat_deg: 37.45, lon_deg: 126.65, h_m: 300}
trajectory:
  initial: {speed_mps: 30, heading_deg: 45}
  segments:
    - {kind: cruise, duration_s: 300}
)";

constexpr const char* kMemsManeuver = R"(name: mems-gps-mag-maneuver
description: seed 001 section 4 - MEMS IMU, 5 Hz GPS, magnetometer; turns, climbs and S-turns
start: {lat_deg: 37.45, lon_deg: 126.65, h_m: 300}
trajectory:
  initial: {speed_mps: 30, heading_deg: 45}
  segments:
    - {kind: cruise, duration_s: 30}
    - {kind: turn, duration_s: 20, heading_change_deg: 90}
    - {kind: climb, duration_s: 20, vertical_speed_mps: 3}
    - {kind: cruise, duration_s: 30}
    - {kind: s_turns, duration_s: 80, heading_amplitude_deg: 30, period_s: 40}
    - {kind: descend, duration_s: 20, vertical_speed_mps: -3}
    - {kind: cruise, duration_s: 20}
    - {kind: turn, duration_s: 30, heading_change_deg: -180}
    - {kind: accelerate, duration_s: 20, speed_mps: 40}
    - {kind: wing_rock, duration_s: 30, roll_amplitude_deg: 10, roll_frequency_hz: 0.2}
    - {kind: cruise, duration_s: 30}
)";

// A navigation-grade IMU (gyro bias 0.005 deg/h, ARW 0.002 deg/sqrt(h); accelerometer
// bias 25 ug, VRW 0.01 m/s/sqrt(h)) at 200 Hz and 1 Hz RTK GNSS (2 cm / 4 cm, 1 cm/s) on
// a car-like drive: twelve 300 s laps of stops, accelerations, turns and S-bends.
constexpr const char* kNavGradeHead = R"(name: nav-grade-vehicle-1h
description: navigation-grade IMU at 200 Hz, 1 Hz RTK GNSS, one hour of car-like driving
start: {lat_deg: 37.5, lon_deg: 127.0, h_m: 50}
imu:
  rate_hz: 200
  errors:
    gyro: {bias_deg_h: 0.005, bias_instability_deg_h: 0.003, correlation_time_s: 3600, arw_deg_sqrt_h: 0.002, scale_factor_ppm: 5, misalignment_arcsec: 2}
    accel: {bias_ug: 25, bias_instability_ug: 10, correlation_time_s: 3600, vrw_m_s_sqrt_h: 0.01, scale_factor_ppm: 10, misalignment_arcsec: 2}
gnss: {rate_hz: 1, position_sigma_m: [0.02, 0.04], velocity_sigma_mps: 0.01, lever_arm_b_m: [0.5, 0.0, -1.5]}
trajectory:
  initial: {speed_mps: 0, heading_deg: 30}
  segments:
)";

constexpr const char* kNavGradeLap = R"(    - {kind: static, duration_s: 20}
    - {kind: accelerate, duration_s: 15, speed_mps: 15}
    - {kind: cruise, duration_s: 40}
    - {kind: turn, duration_s: 20, heading_change_deg: 90}
    - {kind: cruise, duration_s: 30}
    - {kind: s_turns, duration_s: 60, heading_amplitude_deg: 15, period_s: 30}
    - {kind: turn, duration_s: 15, heading_change_deg: -60}
    - {kind: cruise, duration_s: 40}
    - {kind: turn, duration_s: 20, heading_change_deg: 60}
    - {kind: decelerate, duration_s: 15, speed_mps: 0}
    - {kind: static, duration_s: 25}
)";

// A ground vehicle with an automotive MEMS IMU (gyro bias 10 deg/h, ARW 0.3 deg/sqrt(h);
// accelerometer bias 2 mg, VRW 0.1 m/s/sqrt(h)), 1 Hz GNSS (1.5 m / 3 m, 0.05 m/s) and a
// 10 Hz wheel odometer (0.5 % scale-factor error, 0.05 m/s noise) on three 300 s laps of
// the car-like drive. The trajectory keeps the body x axis along the velocity (no sideslip,
// no vertical velocity in the body frame), so the non-holonomic constraint holds exactly at
// the IMU, which is also the odometer's reference point.
constexpr const char* kMemsCarHead = R"(name: mems-car-odometer
description: automotive MEMS IMU at 100 Hz, 1 Hz GNSS, 10 Hz wheel odometer, 15 minutes of car-like driving
start: {lat_deg: 37.5, lon_deg: 127.0, h_m: 50}
imu:
  rate_hz: 100
  errors:
    gyro: {bias_deg_h: 10, arw_deg_sqrt_h: 0.3, scale_factor_ppm: 1000, misalignment_arcsec: 300}
    accel: {bias_ug: 2000, vrw_m_s_sqrt_h: 0.1, scale_factor_ppm: 1000, misalignment_arcsec: 300}
gnss: {rate_hz: 1, position_sigma_m: [1.5, 3.0], velocity_sigma_mps: 0.05, lever_arm_b_m: [0.0, 0.0, -1.0]}
odometer: {rate_hz: 10, scale_factor_fixed_ppm: 5000, noise_mps: 0.05}
init_errors: {position_ned_m: [1.0, -1.0, 2.0], velocity_ned_mps: [0.05, -0.05, 0.05], attitude_deg: [0.5, -0.5, 2.0]}
trajectory:
  initial: {speed_mps: 0, heading_deg: 30}
  segments:
)";

std::string MemsCar() {
  std::string yaml = kMemsCarHead;
  for (int lap = 0; lap < 3; ++lap) yaml += kNavGradeLap;
  return yaml;
}

std::string NavGradeVehicle() {
  std::string yaml = kNavGradeHead;
  for (int lap = 0; lap < 12; ++lap) yaml += kNavGradeLap;
  return yaml;
}

}  // namespace

std::vector<std::string> PresetNames() {
  return {"leveling-600hz-vibration", "transfer-alignment-high-maneuver", "inflight-mach07-south",
          "mems-gps-mag-level-flight", "mems-gps-mag-maneuver", "nav-grade-vehicle-1h", "mems-car-odometer"};
}

std::optional<std::string> PresetYaml(const std::string& name) {
  if (name == "leveling-600hz-vibration") return std::string(kLeveling);
  if (name == "transfer-alignment-high-maneuver") return std::string(kTransferAlignment);
  if (name == "inflight-mach07-south") return std::string(kInflight);
  if (name == "mems-gps-mag-level-flight") return std::string(kMemsLevel) + kMemsSensors;
  if (name == "mems-gps-mag-maneuver") return std::string(kMemsManeuver) + kMemsSensors;
  if (name == "nav-grade-vehicle-1h") return NavGradeVehicle();
  if (name == "mems-car-odometer") return MemsCar();
  return std::nullopt;
}

}  // namespace navtwin::sim
