// The magnetometer as an aiding source: the field vector (factors/mag_vector.h), the
// tilt-compensated heading or the 2-axis heading (factors/mag_heading.h), each sample at
// the first IMU epoch at or after its time (filter) or carried to its nearest batch state
// with the gyro increments between the two times (batch).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/mag_iron_model.h"
#include "core/types.h"
#include "core/units.h"
#include "problems/ins/aiding.h"

namespace navtwin::ins {

/// Magnetometer use. The iron (hard iron h, soft iron S) is core/mag_iron_model.h's:
/// m_b = (I + S) R_b_n m_n + h; measurements are corrected as (I + S)^-1 (m - h).
struct MagConfig {
  enum class Mode {
    kOff,
    kVector,        ///< full field vector in the body axes (needs field_ned_uT)
    kHeading,       ///< 3-axis tilt-compensated heading
    kHeading2Axis,  ///< seed 001: heading from x, y only, used while |roll|, |pitch| < max_tilt_rad
  };
  Mode mode = Mode::kOff;
  Eigen::Vector3d field_ned_uT = Eigen::Vector3d::Zero();  ///< for kVector
  double declination_rad = 0.0;                            ///< east of true north
  MagIronModel iron;
  double noise_uT = 0.5;            ///< per axis, kVector
  double heading_std_rad = 0.035;   ///< kHeading, kHeading2Axis
  double max_tilt_rad = 2.0 * kDegToRad;
  double min_interval_s = 0.0;      ///< use at most one sample per this interval (0: all)
};

/// A magnetometer sample with the hard- and soft-iron calibration removed:
/// (I + S)^-1 (m - h) (MagConfig).
Eigen::Vector3d CalibrateMag(const Eigen::Vector3d& m_raw_uT, const MagConfig& mag);

/// Count key "mag" (rejected: a vertical mean field in heading mode, a tilt beyond
/// max_tilt_rad in 2-axis mode, a sample that cannot be carried to its state). Throws
/// std::invalid_argument for kVector without a field.
std::unique_ptr<AidingSource> MakeMagSource(const std::vector<MagSample>& samples, const MagConfig& config);

}  // namespace navtwin::ins
