// The leveling measurement model shared by every leveling method (equation 1 of seed 000):
// the plain mean and period average (problems/leveling/leveling.cc), the online filter
// (problems/leveling/filter.cc) and the Ceres residual of the batch
// (problems/leveling/leveling_vibration.*). In core because equation 1 is also the level of
// other problems (the accelerometer level of problems/calibration/mag_heading).
// At rest the accelerometers sense f_b = R_b_n (0, 0, -g)^T in body FRD axes, NED frame:
//   f_b = ( g sin(pitch), -g sin(roll) cos(pitch), -g cos(roll) cos(pitch) )
// and inversely (the signed atan2 form of equation 1)
//   pitch = atan2(f_x, sqrt(f_y^2 + f_z^2)),   roll = atan2(-f_y, -f_z).
#pragma once

#include <cmath>

#include <Eigen/Core>

namespace navtwin::leveling {

/// Specific force at rest for roll and pitch (rad) and gravity magnitude g (m/s^2).
template <typename T>
Eigen::Matrix<T, 3, 1> SpecificForceAtRest(const T& roll_rad, const T& pitch_rad, const T& g_mps2) {
  using std::cos;
  using std::sin;
  const T cp = cos(pitch_rad);
  return Eigen::Matrix<T, 3, 1>(g_mps2 * sin(pitch_rad), -g_mps2 * sin(roll_rad) * cp,
                                -g_mps2 * cos(roll_rad) * cp);
}

/// d SpecificForceAtRest / d(roll, pitch) (3 x 2, columns roll, pitch): the filter's
/// measurement Jacobian and the attitude block of the batch residual.
inline Eigen::Matrix<double, 3, 2> SpecificForceAtRestJacobian(double roll_rad, double pitch_rad, double g_mps2) {
  const double sr = std::sin(roll_rad), cr = std::cos(roll_rad);
  const double sp = std::sin(pitch_rad), cp = std::cos(pitch_rad);
  Eigen::Matrix<double, 3, 2> j;
  j << 0.0, g_mps2 * cp,  //
      -g_mps2 * cr * cp, g_mps2 * sr * sp,  //
      g_mps2 * sr * cp, g_mps2 * cr * sp;
  return j;
}

/// Roll and pitch (rad) from a mean specific force (equation 1, atan2 form).
struct RollPitch {
  double roll_rad = 0.0;
  double pitch_rad = 0.0;
};
inline RollPitch LevelFromSpecificForce(const Eigen::Vector3d& f_b_mps2) {
  return {std::atan2(-f_b_mps2.y(), -f_b_mps2.z()),
          std::atan2(f_b_mps2.x(), std::hypot(f_b_mps2.y(), f_b_mps2.z()))};
}

/// d(roll, pitch)/d f_b of LevelFromSpecificForce, for propagating the covariance of a
/// mean specific force to the angles: rows roll, pitch; columns f_x, f_y, f_z.
inline Eigen::Matrix<double, 2, 3> LevelJacobian(const Eigen::Vector3d& f_b_mps2) {
  const double fx = f_b_mps2.x(), fy = f_b_mps2.y(), fz = f_b_mps2.z();
  const double ryz2 = fy * fy + fz * fz;
  const double ryz = std::sqrt(ryz2);
  const double n2 = ryz2 + fx * fx;
  Eigen::Matrix<double, 2, 3> j;
  j << 0.0, fz / ryz2, -fy / ryz2,  // roll = atan2(-fy, -fz)
      ryz / n2, -fx * fy / (ryz * n2), -fx * fz / (ryz * n2);
  return j;
}

}  // namespace navtwin::leveling
