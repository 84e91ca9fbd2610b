// Errors of a navigation solution against a reference (truth) trajectory: position in
// local NED metres, velocity in NED m/s, attitude as roll/pitch/yaw differences in rad
// (estimate minus truth, wrapped), accumulated as RMS, maximum and final values.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/types.h"

namespace navtwin {

/// Error components of one epoch, estimate minus truth.
struct NavError {
  double t_s = 0.0;
  Eigen::Vector3d pos_ned_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d vel_ned_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy_rad = Eigen::Vector3d::Zero();  ///< roll, pitch, yaw differences
};

NavError CompareNav(const NavState& estimate, const NavState& truth);

/// RMS / max / final of each of the nine components, plus horizontal and 3-D position.
class NavErrorStats {
 public:
  void Add(const NavError& e);
  std::size_t count() const { return count_; }
  /// Component index: 0-2 position N, E, D; 3-5 velocity N, E, D; 6-8 roll, pitch, yaw.
  double Rms(int component) const;
  double Max(int component) const;  ///< maximum absolute value
  double Final(int component) const;
  double HorizontalRms_m() const;
  double HorizontalMax_m() const;
  const NavError& final_error() const { return last_; }

 private:
  std::size_t count_ = 0;
  std::array<double, 9> sum_sq_{};
  std::array<double, 9> max_abs_{};
  double sum_sq_horizontal_ = 0.0;
  double max_horizontal_ = 0.0;
  NavError last_;
};

/// Linear interpolation of position and velocity, spherical of attitude, between two
/// states at t in [a.t_s, b.t_s].
NavState InterpolateNav(const NavState& a, const NavState& b, double t_s);

/// The state of a time-sorted record at t (InterpolateNav between the records around t);
/// nullopt outside [front.t_s - tolerance_s, back.t_s + tolerance_s] (the end record within
/// the tolerance).
std::optional<NavState> NavAt(const std::vector<NavState>& nav, double t_s, double tolerance_s = 0.0);

}  // namespace navtwin
