// Rotations on SO(3): skew, exponential and logarithm maps, and conversions between
// direction-cosine matrices, Hamilton quaternions, rotation vectors and ZYX Euler angles.
//
// Everything is templated on the scalar so that ceres::Jet works (the Ceres residuals
// in factors/ call these same functions). Scalar functions are called unqualified
// (sqrt, sin, atan2, ...) so that argument-dependent lookup finds the Jet overloads.
//
// Conventions (DESIGN.md):
//  - R_a_b maps vectors from frame b into frame a: v_a = R_a_b * v_b. R_n_b is the
//    seeds' C_b^n (body FRD to navigation NED).
//  - Quaternions are Hamilton, Eigen::Quaternion (w, x, y, z), q_a_b ~ R_a_b.
//  - Rotation vector phi: Exp(phi) rotates by |phi| rad about phi/|phi| (right hand).
//  - Euler ZYX: R_n_b = Rz(yaw) * Ry(pitch) * Rx(roll); roll in (-pi, pi],
//    pitch in [-pi/2, pi/2], yaw in (-pi, pi].
//
// ATTITUDE ERROR (the one convention used by filters, Ceres manifolds and plots):
//    R_n_b_true = Exp(phi_n) * R_n_b_est,
// i.e. phi_n is a small rotation expressed in the navigation frame (a left
// perturbation; the seeds' phi-angle). AttitudeError() and ApplyAttitudeError() below
// are the only places that encode it.
#pragma once

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/units.h"

namespace navtwin {

template <typename T>
using Vector3 = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Matrix3 = Eigen::Matrix<T, 3, 3>;
template <typename T>
using Quaternion = Eigen::Quaternion<T>;

/// [v]x such that Skew(a) * b = a.cross(b).
template <typename T>
Matrix3<T> Skew(const Vector3<T>& v) {
  Matrix3<T> m;
  m << T(0), -v.z(), v.y(),
       v.z(), T(0), -v.x(),
       -v.y(), v.x(), T(0);
  return m;
}

/// Inverse of Skew for a skew-symmetric matrix (takes the antisymmetric part).
template <typename T>
Vector3<T> Vee(const Matrix3<T>& m) {
  return Vector3<T>(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1)) * T(0.5);
}

/// Unit quaternion for rotation vector phi. Uses a Taylor series below |phi|^2 = 1e-10
/// so that it is exact to double precision near 0 and differentiable (no sqrt(0)).
template <typename T>
Quaternion<T> QuatFromRotVec(const Vector3<T>& phi) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T theta_sq = phi.squaredNorm();
  T w, k;  // q = [w, k * phi]
  if (theta_sq < T(1e-10)) {
    w = T(1) - theta_sq / T(8);
    k = T(0.5) - theta_sq / T(48);
  } else {
    const T theta = sqrt(theta_sq);
    w = cos(theta / T(2));
    k = sin(theta / T(2)) / theta;
  }
  return Quaternion<T>(w, k * phi.x(), k * phi.y(), k * phi.z());
}

/// Rotation vector of a unit quaternion, |phi| in [0, pi]; q and -q give the same result.
/// Accurate near 0 (series) and near pi (atan2 of the vector part against w).
template <typename T>
Vector3<T> RotVecFromQuat(const Quaternion<T>& q_in) {
  using std::atan2;
  using std::sqrt;
  const Quaternion<T> q = q_in.w() < T(0) ? Quaternion<T>(-q_in.coeffs()) : q_in;
  const Vector3<T> u = q.vec();
  const T s_sq = u.squaredNorm();
  if (s_sq < T(1e-12)) {
    // 2 atan(s/w)/s = (2/w) (1 - s^2/(3 w^2) + ...)
    const T w = q.w();
    return u * (T(2) / w * (T(1) - s_sq / (T(3) * w * w)));
  }
  const T s = sqrt(s_sq);
  return u * (T(2) * atan2(s, q.w()) / s);
}

/// Quaternion of a rotation matrix (Shepperd's method: branch on the largest of the
/// trace and the diagonal, so it is well conditioned for every rotation). w >= 0.
template <typename T>
Quaternion<T> QuatFromDcm(const Matrix3<T>& R) {
  using std::sqrt;
  const T tr = R.trace();
  T w, x, y, z;
  if (tr >= R(0, 0) && tr >= R(1, 1) && tr >= R(2, 2)) {
    const T s = sqrt(T(1) + tr) * T(2);  // 4w
    w = T(0.25) * s;
    x = (R(2, 1) - R(1, 2)) / s;
    y = (R(0, 2) - R(2, 0)) / s;
    z = (R(1, 0) - R(0, 1)) / s;
  } else if (R(0, 0) >= R(1, 1) && R(0, 0) >= R(2, 2)) {
    const T s = sqrt(T(1) + R(0, 0) - R(1, 1) - R(2, 2)) * T(2);  // 4x
    w = (R(2, 1) - R(1, 2)) / s;
    x = T(0.25) * s;
    y = (R(0, 1) + R(1, 0)) / s;
    z = (R(0, 2) + R(2, 0)) / s;
  } else if (R(1, 1) >= R(2, 2)) {
    const T s = sqrt(T(1) + R(1, 1) - R(0, 0) - R(2, 2)) * T(2);  // 4y
    w = (R(0, 2) - R(2, 0)) / s;
    x = (R(0, 1) + R(1, 0)) / s;
    y = T(0.25) * s;
    z = (R(1, 2) + R(2, 1)) / s;
  } else {
    const T s = sqrt(T(1) + R(2, 2) - R(0, 0) - R(1, 1)) * T(2);  // 4z
    w = (R(1, 0) - R(0, 1)) / s;
    x = (R(0, 2) + R(2, 0)) / s;
    y = (R(1, 2) + R(2, 1)) / s;
    z = T(0.25) * s;
  }
  Quaternion<T> q(w, x, y, z);
  if (q.w() < T(0)) q.coeffs() = -q.coeffs();
  q.coeffs() /= q.coeffs().norm();
  return q;
}

/// Rotation matrix of a (not necessarily normalised) quaternion.
template <typename T>
Matrix3<T> DcmFromQuat(const Quaternion<T>& q) {
  return q.normalized().toRotationMatrix();
}

/// Exp: so(3) -> SO(3), R = I + sin(t)/t [phi]x + (1 - cos t)/t^2 [phi]x^2.
template <typename T>
Matrix3<T> ExpSO3(const Vector3<T>& phi) {
  return DcmFromQuat(QuatFromRotVec(phi));
}

/// Log: SO(3) -> so(3), |phi| in [0, pi]; accurate near 0 and near pi (goes through
/// Shepperd's quaternion instead of acos of the trace).
template <typename T>
Vector3<T> LogSO3(const Matrix3<T>& R) {
  return RotVecFromQuat(QuatFromDcm(R));
}

/// R_n_b = Rz(yaw) Ry(pitch) Rx(roll).
template <typename T>
Matrix3<T> DcmFromEuler(const T& roll, const T& pitch, const T& yaw) {
  using std::cos;
  using std::sin;
  const T cr = cos(roll), sr = sin(roll);
  const T cp = cos(pitch), sp = sin(pitch);
  const T cy = cos(yaw), sy = sin(yaw);
  Matrix3<T> R;
  R << cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
       sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
       -sp, cp * sr, cp * cr;
  return R;
}

/// (roll, pitch, yaw) of R_n_b. At gimbal lock (|pitch| = 90 deg to within 1e-9 rad of
/// cos(pitch)) roll and yaw are not separable: roll is set to 0 and the whole rotation
/// about the vertical goes into yaw, so that DcmFromEuler(EulerFromDcm(R)) == R.
template <typename T>
Vector3<T> EulerFromDcm(const Matrix3<T>& R) {
  using std::atan2;
  using std::sqrt;
  const T cos_pitch = sqrt(R(2, 1) * R(2, 1) + R(2, 2) * R(2, 2));
  const T pitch = atan2(-R(2, 0), cos_pitch);
  if (cos_pitch < T(1e-9)) {
    return Vector3<T>(T(0), pitch, atan2(-R(0, 1), R(1, 1)));
  }
  return Vector3<T>(atan2(R(2, 1), R(2, 2)), pitch, atan2(R(1, 0), R(0, 0)));
}

template <typename T>
Quaternion<T> QuatFromEuler(const T& roll, const T& pitch, const T& yaw) {
  return QuatFromDcm(DcmFromEuler(roll, pitch, yaw));
}

template <typename T>
Vector3<T> EulerFromQuat(const Quaternion<T>& q) {
  return EulerFromDcm(DcmFromQuat(q));
}

/// phi_n with R_n_b_true = Exp(phi_n) * R_n_b_est (see the header comment).
template <typename T>
Vector3<T> AttitudeError(const Quaternion<T>& q_n_b_true, const Quaternion<T>& q_n_b_est) {
  return RotVecFromQuat(Quaternion<T>(q_n_b_true * q_n_b_est.conjugate()));
}

/// R_n_b_true estimate from an estimate and an attitude error phi_n: Exp(phi_n) * q_est.
template <typename T>
Quaternion<T> ApplyAttitudeError(const Vector3<T>& phi_n, const Quaternion<T>& q_n_b_est) {
  Quaternion<T> q = QuatFromRotVec(phi_n) * q_n_b_est;
  q.normalize();
  return q;
}

/// SO(3) right Jacobian: Exp(phi + d) = Exp(phi) Exp(Jr(phi) d) + O(|d|^2),
///   Jr(phi) = I - (1 - cos t)/t^2 [phi]x + (t - sin t)/t^3 [phi]x^2,   t = |phi|,
/// with the series 1/2 - t^2/24 + t^4/720 and 1/6 - t^2/120 + t^4/5040 below t^2 = 1e-8
/// (truncation < 1e-25). The left Jacobian is Jl(phi) = Jr(-phi).
template <typename T>
Matrix3<T> RightJacobianSO3(const Vector3<T>& phi) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T t2 = phi.squaredNorm();
  T c1, c2;
  if (t2 < T(1e-8)) {
    c1 = T(0.5) - t2 / T(24) + t2 * t2 / T(720);
    c2 = T(1.0 / 6.0) - t2 / T(120) + t2 * t2 / T(5040);
  } else {
    const T t = sqrt(t2);
    c1 = (T(1) - cos(t)) / t2;
    c2 = (t - sin(t)) / (t2 * t);
  }
  const Matrix3<T> K = Skew(phi);
  return Matrix3<T>::Identity() - c1 * K + c2 * K * K;
}

/// Inverse of the right Jacobian: Log(Exp(phi) Exp(d)) = phi + Jr^-1(phi) d + O(|d|^2),
///   Jr^-1(phi) = I + [phi]x / 2 + (1/t^2 - (1 + cos t) / (2 t sin t)) [phi]x^2,
/// with the series 1/12 + t^2/720 + t^4/30240 below t^2 = 1e-8 (cancellation). Also the
/// rate of a rotation vector: d(phi)/dt = Jr^-1(phi) omega_b for R = R0 Exp(phi).
/// Valid for |phi| < 2 pi (sin t = 0 at t = 2 pi).
template <typename T>
Matrix3<T> RightJacobianInverseSO3(const Vector3<T>& phi) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T t2 = phi.squaredNorm();
  T c;
  if (t2 < T(1e-8)) {
    c = T(1.0 / 12.0) + t2 / T(720) + t2 * t2 / T(30240);
  } else {
    const T t = sqrt(t2);
    c = T(1) / t2 - (T(1) + cos(t)) / (T(2) * t * sin(t));
  }
  const Matrix3<T> K = Skew(phi);
  return Matrix3<T>::Identity() + T(0.5) * K + c * K * K;
}

/// Wraps an angle to (-pi, pi]: a - 2 pi floor((a + pi) / 2 pi), then -pi moved to pi.
/// Templated: for a ceres::Jet the floor has derivative 0, so d wrap(a) / da = 1.
template <typename T>
T WrapPi(const T& a_rad) {
  using std::floor;
  const T two_pi(kTwoPi);
  T r = a_rad - two_pi * floor((a_rad + T(kPi)) / two_pi);
  if (r <= T(-kPi)) r += two_pi;
  if (r > T(kPi)) r -= two_pi;
  return r;
}

}  // namespace navtwin
