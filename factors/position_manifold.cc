#include "factors/position_manifold.h"

#include <cmath>

namespace navtwin {

bool PositionManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  double out[3];  // x_plus_delta may alias x (Ceres allows it): compute into a temporary
  PositionPlus(x, delta, out);
  x_plus_delta[0] = out[0];
  x_plus_delta[1] = out[1];
  x_plus_delta[2] = out[2];
  return true;
}

bool PositionManifold::PlusJacobian(const double* x, double* jacobian) const {
  const double rm_h = wgs84::MeridianRadius(x[0]) + x[2];
  const double rn_h = wgs84::PrimeVerticalRadius(x[0]) + x[2];
  for (int i = 0; i < 9; ++i) jacobian[i] = 0.0;
  jacobian[0] = 1.0 / rm_h;
  jacobian[4] = 1.0 / (rn_h * std::cos(x[0]));
  jacobian[8] = -1.0;
  return true;
}

bool PositionManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  double out[3];
  PositionMinus(y, x, out);
  y_minus_x[0] = out[0];
  y_minus_x[1] = out[1];
  y_minus_x[2] = out[2];
  return true;
}

bool PositionManifold::MinusJacobian(const double* x, double* jacobian) const {
  const double rm_h = wgs84::MeridianRadius(x[0]) + x[2];
  const double rn_h = wgs84::PrimeVerticalRadius(x[0]) + x[2];
  for (int i = 0; i < 9; ++i) jacobian[i] = 0.0;
  jacobian[0] = rm_h;
  jacobian[4] = rn_h * std::cos(x[0]);
  jacobian[8] = -1.0;
  return true;
}

}  // namespace navtwin
