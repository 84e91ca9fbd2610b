// GNSS position and velocity as an aiding source: the antenna position and velocity
// functors (factors/gnss_position.h, factors/gnss_velocity.h) at the fixes' times (the
// filter splits the IMU sample there; the batch places a state at each fix).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/types.h"
#include "problems/ins/aiding.h"

namespace navtwin::ins {

struct GnssConfig {
  bool use_velocity = true;        ///< when the file has velocity
  double pos_std_floor_m = 0.0;    ///< sigma used = max(file sigma, floor)
  double vel_std_floor_mps = 0.0;
  double default_pos_std_m = 5.0;  ///< when the file gives none
  double default_vel_std_mps = 0.1;
  double max_distance_m = 10000.0; ///< a fix this far from the INS prediction is an input error
  /// Multipliers of the sigmas used (after floor and default), horizontal (N, E) and
  /// vertical: the noise scales that the batch's variance components estimate
  /// (ResidualStats::sigma_scale of gnss_position_h, ...), so a run can use them.
  double pos_sigma_scale_h = 1.0;
  double pos_sigma_scale_v = 1.0;
  double vel_sigma_scale_h = 1.0;
  double vel_sigma_scale_v = 1.0;
  /// The antenna lever arm as three auxiliary states ("gnss_lever_arm_{x,y,z}_m") with prior
  /// the configured lever arm and std lever_arm_std_m per body axis.
  bool estimate_lever_arm = false;
  Eigen::Vector3d lever_arm_std_m = Eigen::Vector3d::Constant(0.5);
  /// The receiver's time offset tau (latency: the fix stamped t describes the antenna at
  /// t - tau; factors/gnss_installation.h): time_offset_s is its value, or with
  /// estimate_time_offset the prior of the auxiliary state "gnss_time_offset_s".
  bool estimate_time_offset = false;
  double time_offset_s = 0.0;
  double time_offset_std_s = 0.2;
};

/// Counts: "gnss_position", "gnss_velocity", and "gnss_reset" (filter: after
/// reset_rejections positions in a row rejected by the gate, position and velocity are
/// reset to the fix with its covariance; 0: never). A fix farther than
/// config.max_distance_m from the prediction is an InputError naming `path`. With the lever
/// arm or the time offset estimated, or a time offset other than 0, the models are those of
/// factors/gnss_installation.h; otherwise factors/gnss_position.h and gnss_velocity.h.
std::unique_ptr<AidingSource> MakeGnssSource(const std::vector<GnssSample>& fixes, const GnssConfig& config,
                                             const Eigen::Vector3d& antenna_lever_arm_b_m,
                                             int reset_rejections, const std::string& path);

}  // namespace navtwin::ins
