// Ceres manifold for a geodetic position block {lat_rad, lon_rad, h_m} whose tangent space
// is a local NED offset dp_ned_m (the position part of the error state, ins_state.h):
//
//   Plus(x, d)  = (lat + d_n / (M(lat) + h),
//                  wrap(lon + d_e / ((N(lat) + h) cos lat)),
//                  h   - d_d)
//   Minus(y, x) = ((lat_y - lat_x) (M(lat_x) + h_x),
//                  wrap(lon_y - lon_x) (N(lat_x) + h_x) cos lat_x,
//                  -(h_y - h_x))
//
// M, N: WGS84 meridian and prime-vertical radii (core/earth.h), evaluated at x only, so
// Minus(Plus(x, d), x) = d and Plus(x, Minus(y, x)) = y exactly (up to rounding): the
// manifold is a per-point linear chart of (lat, lon, h), first-order equal to the true NED
// displacement. wrap() takes longitudes and their differences to (-pi, pi] (date line), so
// Plus(x, Minus(y, x)) = y also across it; stored longitudes are expected in (-pi, pi].
// Not defined at the poles (cos lat = 0).
//
// Jacobians (diagonal):
//   PlusJacobian(x)  = diag(1 / (M + h), 1 / ((N + h) cos lat), -1)   (3x3, d Plus / d d at 0)
//   MinusJacobian(x) = diag(M + h, (N + h) cos lat, -1)               (3x3, d Minus / d y at x)
#pragma once

#include <cmath>

#include <ceres/manifold.h>

#include "core/earth.h"
#include "core/rotation.h"

namespace navtwin {

/// out = Plus(x, delta): x = {lat_rad, lon_rad, h_m}, delta = dp_ned_m. Templated for Jets.
/// out must not alias x or delta.
template <typename T>
void PositionPlus(const T* x, const T* delta, T* out) {
  using std::cos;
  const T rm_h = wgs84::MeridianRadius(x[0]) + x[2];
  const T rn_h = wgs84::PrimeVerticalRadius(x[0]) + x[2];
  out[0] = x[0] + delta[0] / rm_h;
  out[1] = WrapPi(x[1] + delta[1] / (rn_h * cos(x[0])));
  out[2] = x[2] - delta[2];
}

/// out = Minus(y, x) = dp_ned_m of y relative to x (radii at x). Templated for Jets.
/// out must not alias x or y.
template <typename T>
void PositionMinus(const T* y, const T* x, T* out) {
  using std::cos;
  const T rm_h = wgs84::MeridianRadius(x[0]) + x[2];
  const T rn_h = wgs84::PrimeVerticalRadius(x[0]) + x[2];
  const T dlon = WrapPi(T(y[1] - x[1]));
  out[0] = (y[0] - x[0]) * rm_h;
  out[1] = dlon * rn_h * cos(x[0]);
  out[2] = -(y[2] - x[2]);
}

class PositionManifold final : public ceres::Manifold {
 public:
  static constexpr int kAmbientSize = 3;
  static constexpr int kTangentSize = 3;

  int AmbientSize() const override { return kAmbientSize; }
  int TangentSize() const override { return kTangentSize; }

  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  /// Row-major 3x3, diag(1/(M+h), 1/((N+h) cos lat), -1).
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  /// Row-major 3x3, diag(M+h, (N+h) cos lat, -1).
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

}  // namespace navtwin
