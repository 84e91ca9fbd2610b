// The non-holonomic constraint of a ground vehicle as an aiding source
// (factors/nhc_velocity.h): no lateral and no vertical velocity of the vehicle reference
// point, in the filter at IMU epochs at most once per interval_s, in the batch at every
// state; off while the vehicle stands (the stillness rule holds and the speed is below
// 0.5 m/s: a still vehicle is a ZUPT's business).
#pragma once

#include <memory>

#include <Eigen/Core>

#include "problems/ins/aiding.h"
#include "problems/ins/measurement_rules.h"

namespace navtwin::ins {

/// How the IMU sits in the vehicle: v_v = R_v_b v_b with R_v_b = DcmFromEuler(mounting_rpy_rad)
/// (roll, pitch, yaw, ZYX: the body axes' attitude in the vehicle frame, FRD both), and the
/// vehicle reference point (the middle of the rear axle, where NHC holds and the odometer
/// measures) at lever_arm_b_m from the IMU, body axes.
struct VehicleConfig {
  Eigen::Vector3d mounting_rpy_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d lever_arm_b_m = Eigen::Vector3d::Zero();
};

struct NhcConfig {
  bool enabled = false;
  double std_mps = 0.1;     ///< lateral and vertical
  /// Filter: at most one update per this interval. The constraint's errors (a mounting
  /// error, the pitch error it couples into the vertical) are correlated over seconds:
  /// applied at 10 Hz as independent measurements they are weighted ten times too much
  /// (measured on mems-car-odometer: vertical drift 1.4 -> 2.3 m; docs/vehicle-constraints.md).
  /// 1 s, the batch's state spacing, keeps filter and batch alike.
  double interval_s = 1.0;
};

/// Count key "nhc". still_rule: the stillness thresholds (the ZUPT configuration's).
std::unique_ptr<AidingSource> MakeNhcSource(const NhcConfig& config, const VehicleConfig& vehicle,
                                            const StillnessConfig& still_rule);

}  // namespace navtwin::ins
