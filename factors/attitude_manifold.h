// Ceres manifold for an attitude q_n_b stored as an Eigen quaternion, whose tangent
// space is the project's attitude error (core/rotation.h, docs/attitude-error.md):
//
//   R_n_b_true = Exp(phi_n) * R_n_b_est,
//
// a LEFT perturbation expressed in the navigation frame, phi_n a rotation vector in rad
// (full angle, not Ceres' half-angle QuaternionManifold convention). Hence
//
//   Plus(x, delta) = Exp(delta) (x) x           (normalised)
//   Minus(y, x)    = Log(y (x) x^-1),           |Minus| <= pi
//
// Storage: 4 doubles in Eigen's order (x, y, z, w), i.e. the coeffs() of
// Eigen::Quaterniond and what Eigen::Map<Eigen::Quaterniond> expects.
// Jacobians (derived in docs/attitude-error.md), with Xi(q) = [w I - [v]x ; -v^T] (4x3),
// q = (v, w) a unit quaternion:
//   PlusJacobian(x)  = 1/2 Xi(x)     (d Plus(x, delta) / d delta at delta = 0)
//   MinusJacobian(x) = 2 Xi(x)^T     (d Minus(y, x) / d y at y = x)
// and MinusJacobian(x) * PlusJacobian(x) = Xi^T Xi = I3.
#pragma once

#include <ceres/manifold.h>

namespace navtwin {

class AttitudeManifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 4; }
  int TangentSize() const override { return 3; }

  /// x_plus_delta = Exp(delta) (x) x, normalised; delta in rad, navigation frame.
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  /// Row-major 4x3: 1/2 Xi(x).
  bool PlusJacobian(const double* x, double* jacobian) const override;
  /// y_minus_x = Log(y (x) x^-1) in rad; the sign of y or x does not matter.
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  /// Row-major 3x4: 2 Xi(x)^T.
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

}  // namespace navtwin
