// The configuration with the noise the batch's variance components found (the residual
// groups' sigma scales, solution.h ResidualStats), so the filter and its RTS smoother can run
// again with noise that fits the data, and a user can read the adapted values in their
// own units. Each group maps to the configuration values whose sigma it scales:
//   imu_rotation          -> imu_noise gyro ARW         (the IMU factor's attitude rows)
//   imu_velocity_position -> imu_noise accelerometer VRW
//   gyro_bias_process     -> imu_noise gyro bias std    (steady state of the Gauss-Markov)
//   accel_bias_process    -> imu_noise accelerometer bias std
//   gnss_position_h/_v    -> gnss.pos_sigma_scale_h/_v  (multipliers of the fixes' sigmas)
//   gnss_velocity_h/_v    -> gnss.vel_sigma_scale_h/_v
//   mag                   -> mag.noise_uT
//   baro                  -> baro.std_m
//   odometer              -> odometer.std_mps
// Groups that were not adapted (too little redundancy, pseudo-measurements, priors) keep
// their configured values.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/solution.h"

namespace navtwin::gnss_ins {

struct AdaptedNoise {
  GnssInsConfig config;            ///< the input configuration with the adapted values
  std::vector<std::string> lines;  ///< "gyro ARW 0.912 -> 2.93 deg/sqrt(h) (x3.21)", one per change
  bool changed = false;            ///< any group adapted
};

/// The configuration with the adapted groups of `residuals` (a batch solution's) applied.
AdaptedNoise AdaptNoise(const GnssInsConfig& config, const std::map<std::string, ResidualStats>& residuals);

}  // namespace navtwin::gnss_ins
