// The IMU error model of the calibration work (seed 001 section 3.1, spec gnss-ins-mag.md
// section 2), shared by the batch residuals, the recursive estimators and the compensation
// applied to data (core/calibration_file.h). It is the simulator's model
// (core/sim/inertial_errors.h) without the random processes:
//
//   gyro:  omega_m = (I + diag(s_g) + M_g) omega + G f + b_g     (rad/s)
//   accel: f_m     = (I + diag(s_a) + M_a) f          + b_a     (m/s^2)
//
// s = scale-factor errors (the seed's lambda = 1 + s), M = misalignment / non-orthogonality
// (off-diagonal only; the seed's alpha_xy = M(0,1), ...), G = gyro g-sensitivity (the seed's
// m, all nine entries), b = bias. omega = omega_ib_b, f = f_b, both true, in the IMU axes.
//
// Parameter blocks (the order every residual and every file uses):
//   triad (12): s_x s_y s_z, M_xy M_xz M_yx M_yz M_zx M_zy, b_x b_y b_z
//   g-sensitivity (9): G row-major
// Templated on the scalar so that Ceres' Jets flow through; small. The parameter names of
// reports and files are in imu_error_model.cc.
#pragma once

#include <string>

#include <Eigen/Core>
#include <Eigen/LU>

namespace navtwin {

constexpr int kTriadParameters = 12;
constexpr int kGSensitivityParameters = 9;

/// Index of the misalignment entry (row, col), row != col, within a triad block.
constexpr int MisalignmentIndex(int row, int col) { return 3 + 2 * row + (col > row ? col - 1 : col); }

/// d(M x)/d(m) for the six misalignment entries of a triad block (m in their block order,
/// entry (row, col) at MisalignmentIndex(row, col) - 3): the entry (r, c) moves row r by x_c.
/// The estimators that linearise M at zero use it (factors/imu_preintegration.h, the
/// transfer-alignment history filter).
inline Eigen::Matrix<double, 3, 6> MisalignmentColumns(const Eigen::Vector3d& x) {
  Eigen::Matrix<double, 3, 6> K = Eigen::Matrix<double, 3, 6>::Zero();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      if (c != r) K(r, MisalignmentIndex(r, c) - 3) = x(c);
    }
  }
  return K;
}

/// K = I + diag(s) + M from a triad block.
template <typename T>
Eigen::Matrix<T, 3, 3> TriadMatrix(const T* triad) {
  Eigen::Matrix<T, 3, 3> K;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      K(r, c) = r == c ? T(1.0) + triad[r] : triad[MisalignmentIndex(r, c)];
    }
  }
  return K;
}

template <typename T>
Eigen::Matrix<T, 3, 1> TriadBias(const T* triad) {
  return Eigen::Matrix<T, 3, 1>(triad[9], triad[10], triad[11]);
}

template <typename T>
Eigen::Matrix<T, 3, 3> GSensitivityMatrix(const T* g9) {
  Eigen::Matrix<T, 3, 3> G;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) G(r, c) = g9[3 * r + c];
  return G;
}

/// Forward model of the accelerometer: f_m from the true f.
template <typename T>
Eigen::Matrix<T, 3, 1> MeasuredSpecificForce(const T* accel, const Eigen::Matrix<T, 3, 1>& f) {
  return TriadMatrix(accel) * f + TriadBias(accel);
}

/// Forward model of the gyro: omega_m from the true omega and f (g9 may be null: G = 0).
template <typename T>
Eigen::Matrix<T, 3, 1> MeasuredRate(const T* gyro, const T* g9, const Eigen::Matrix<T, 3, 1>& omega,
                                    const Eigen::Matrix<T, 3, 1>& f) {
  Eigen::Matrix<T, 3, 1> m = TriadMatrix(gyro) * omega + TriadBias(gyro);
  if (g9 != nullptr) m += GSensitivityMatrix(g9) * f;
  return m;
}

/// Inverse model: the true f from f_m, K^-1 (f_m - b).
template <typename T>
Eigen::Matrix<T, 3, 1> CorrectedSpecificForce(const T* accel, const Eigen::Matrix<T, 3, 1>& f_m) {
  return TriadMatrix(accel).inverse() * (f_m - TriadBias(accel));
}

/// Inverse model: the true omega from omega_m and the (corrected) f, K^-1 (omega_m - G f - b).
template <typename T>
Eigen::Matrix<T, 3, 1> CorrectedRate(const T* gyro, const T* g9, const Eigen::Matrix<T, 3, 1>& omega_m,
                                     const Eigen::Matrix<T, 3, 1>& f) {
  Eigen::Matrix<T, 3, 1> u = omega_m - TriadBias(gyro);
  if (g9 != nullptr) u -= GSensitivityMatrix(g9) * f;
  return TriadMatrix(gyro).inverse() * u;
}

/// "x", "y", "z" for axis 0, 1, 2.
inline const char* AxisLetter(int axis) {
  static const char* const kLetters[3] = {"x", "y", "z"};
  return kLetters[axis];
}

/// Names of the parameters, in block order: "accel.scale_factor.x", "accel.misalignment.xy",
/// "accel.bias.z" (triad = "accel" or "gyro"), "g_sensitivity.xy" (row x, col y). Throw
/// std::out_of_range for an index outside the block.
std::string TriadParameterName(const std::string& triad, int index);
std::string GSensitivityParameterName(int index);

}  // namespace navtwin
