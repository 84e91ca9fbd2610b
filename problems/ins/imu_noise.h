// The IMU noise model of the aided INS: white noise on the increments and first-order
// Gauss-Markov IMU errors. SI inside (a configuration in people units is converted when
// it is read).
#pragma once

namespace navtwin::ins {

/// IMU noise and error-process parameters. Biases and scale factors are first-order
/// Gauss-Markov processes with steady-state standard deviation *_std and correlation time
/// correlation_time_s (infinite: random constants driven by no noise).
struct ImuNoise {
  double gyro_arw_rad_per_sqrt_s = 0.0;
  double accel_vrw_mps_per_sqrt_s = 0.0;
  double gyro_bias_std_radps = 0.0;
  double accel_bias_std_mps2 = 0.0;
  double gyro_scale_std = 0.0;   ///< dimensionless (ppm * 1e-6)
  double accel_scale_std = 0.0;
  double correlation_time_s = 3600.0;
};

}  // namespace navtwin::ins
