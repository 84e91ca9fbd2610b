// The batch twin of the distance method (issue 7): one Ceres problem over the whole
// flight (or any prefix of it) whose unknowns are the heading error, the level attitude,
// the accelerometer and gyro biases, the initial position and velocity errors of the free
// INS and the steps of the level random walk, and whose residuals are the distance-based
// heading residual at every raw GPS fix under a robust loss plus the sensor-specification
// priors.
//
// Residual of one fix (problems/inflight_alignment/distance_heading_residual.h), whitened by the GPS sigma:
//     r = ( err - (Rz(dH) - I) D - s(t) - w(t) ) / sigma_gps,       2 x 1 (north, east)
// with D the gained displacement and err the distance error of the fix (free_ins.h),
// Rz(dH) the rotation of (N, E) by dH clockwise seen from above (the exact form of
// equation 8: atan2 of the cross-track over the along-track part of err - s is dH) and
// s(t) the Schuler part (distance_heading.h) of the physical unknowns:
//     s_E = dp0_E + dv0_E b1 + (df_E - g eps_N) b2 - g dw_N b3
//     s_N = dp0_N + dv0_N b1 + (df_N + g eps_E) b2 + g dw_E b3
// (eps level attitude error at the start, df / dw accelerometer / gyro bias projected on
// north and east, b_k = SchulerBasis), and w(t) the level random walk that the gyro angle
// random walk drives (sensors.gyro_arw_deg_sqrt_h, ARW in rad/sqrt(s)), cut into steps
// d_eps_k at tau_k = k T (T = batch.tilt_segment_s, k >= 1, tau_k before the last fix),
// each the tilt term shifted in time, summed over the steps with tau_k < t:
//     w_E = -g sum_k d_eps_N,k b2(t - tau_k),   w_N = g sum_k d_eps_E,k b2(t - tau_k).
// Without w the walk's position effect (g times its double integral, 22 m 1 sigma after
// 545 s at 0.005 deg/sqrt(h)) is a correlated error that the constant terms, the heading
// among them, partly absorb, and the reported sigma is too small (batch.cc has the
// approximation's error). A constant run of steps is a level ramp, i.e. a gyro bias: the
// data see their sum, the priors split it, like level and accelerometer bias.
// The loss (Huber or Cauchy, scale in GPS sigmas) acts on |r|^2 of each fix, so an outlier
// fix is down-weighted as a whole.
// Priors (zero mean, 1 sigma from InflightConfig): level, accelerometer bias, gyro bias
// (widened by the Earth-rate coupling of the initial heading sigma, Omega cos L
// sigma_psi0, which has the gyro term's shape), initial position and velocity, and each
// level step ARW sqrt(T) (no steps when T or ARW is 0). The heading has no prior. Level
// and accelerometer bias enter only as df - g eps: the data fix the combination, the
// priors split it (reported as is).
#pragma once

#include <string>
#include <vector>

#include "problems/inflight_alignment/config.h"
#include "problems/inflight_alignment/free_ins.h"

namespace navtwin::inflight {

/// Estimated unknowns with 1 sigma (from ceres::Covariance), SI units, north/east axes.
struct BatchHeadingSolution {
  double dh_rad = 0.0;        ///< free INS heading error, yaw_ins - yaw_true
  double dh_sigma_rad = 0.0;
  Eigen::Vector2d level_rad = Eigen::Vector2d::Zero();       ///< eps_N, eps_E at the start
  Eigen::Vector2d level_sigma_rad = Eigen::Vector2d::Zero();
  Eigen::Vector2d accel_bias_ne_mps2 = Eigen::Vector2d::Zero();
  Eigen::Vector2d accel_bias_sigma_mps2 = Eigen::Vector2d::Zero();
  Eigen::Vector2d gyro_bias_ne_radps = Eigen::Vector2d::Zero();
  Eigen::Vector2d gyro_bias_sigma_radps = Eigen::Vector2d::Zero();
  Eigen::Vector2d position0_ne_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity0_ne_mps = Eigen::Vector2d::Zero();
  double gps_sigma_m = 0.0;   ///< the sigma used (given or estimated)
  int fixes = 0;              ///< GPS fixes in the problem
  int tilt_steps = 0;         ///< level random-walk steps in the problem (batch.tilt_segment_s)
  int downweighted = 0;       ///< fixes whose robust weight is below 0.5
  double residual_rms_m = 0.0;  ///< RMS of |err - model| over fixes with weight >= 0.5
  int iterations = 0;
  std::string loss;           ///< "none", "huber", "cauchy"
};

/// Solves the problem over epochs (from RunFreeIns; at least 10, with a gained
/// displacement above 100 m somewhere). gps_sigma_m > 0 whitens the residuals; pass
/// EstimateGpsSigma of the raw fixes otherwise. schuler_rate_radps from SchulerRate at
/// the start; lat_rad for the Earth-rate term of the gyro prior. Throws
/// std::invalid_argument for too few epochs, non-finite input or a configuration value out
/// of range (naming the key; also segments giving more than 1000 steps), std::runtime_error
/// if Ceres fails or the covariance is rank-deficient (message says which block).
BatchHeadingSolution SolveHeadingBatch(const std::vector<FreeInsEpoch>& epochs, double gps_sigma_m,
                                       double lat_rad, double schuler_rate_radps,
                                       const InflightConfig& config);

/// The robust weight rho'(s) of the loss at a squared whitened residual s (1 for none).
double RobustWeight(RobustLoss loss, double scale_sigma, double squared_residual);

}  // namespace navtwin::inflight
