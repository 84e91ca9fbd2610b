#include "factors/attitude_manifold.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"

namespace navtwin {
namespace {

using ConstQuatMap = Eigen::Map<const Eigen::Quaterniond>;  // (x, y, z, w) storage

/// Xi(q) = [w I - [v]x ; -v^T] (4x3, rows in storage order x, y, z, w): the map from a
/// left rotation-vector perturbation eps to d(q), d(Exp(eps) (x) q) = 1/2 Xi(q) eps.
Eigen::Matrix<double, 4, 3> Xi(const Eigen::Quaterniond& q) {
  Eigen::Matrix<double, 4, 3> xi;
  xi.topRows<3>() = q.w() * Eigen::Matrix3d::Identity() - Skew<double>(q.vec());
  xi.bottomRows<1>() = -q.vec().transpose();
  return xi;
}

}  // namespace

bool AttitudeManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Eigen::Map<const Eigen::Vector3d> phi_n_rad(delta);
  Eigen::Map<Eigen::Quaterniond> out(x_plus_delta);
  out = ApplyAttitudeError<double>(phi_n_rad, ConstQuatMap(x));
  return true;
}

bool AttitudeManifold::PlusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 4, 3, Eigen::RowMajor>> out(jacobian);
  out = 0.5 * Xi(ConstQuatMap(x));
  return true;
}

bool AttitudeManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  Eigen::Map<Eigen::Vector3d> out(y_minus_x);
  out = AttitudeError<double>(ConstQuatMap(y), ConstQuatMap(x));
  return true;
}

bool AttitudeManifold::MinusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> out(jacobian);
  out = 2.0 * Xi(ConstQuatMap(x)).transpose();
  return true;
}

}  // namespace navtwin
