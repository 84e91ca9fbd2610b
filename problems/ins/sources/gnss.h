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
};

/// Counts: "gnss_position", "gnss_velocity", and "gnss_reset" (filter: after
/// reset_rejections positions in a row rejected by the gate, position and velocity are
/// reset to the fix with its covariance; 0: never). A fix farther than
/// config.max_distance_m from the prediction is an InputError naming `path`.
std::unique_ptr<AidingSource> MakeGnssSource(const std::vector<GnssSample>& fixes, const GnssConfig& config,
                                             const Eigen::Vector3d& antenna_lever_arm_b_m,
                                             int reset_rejections, const std::string& path);

}  // namespace navtwin::ins
