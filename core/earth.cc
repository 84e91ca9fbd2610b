#include "core/earth.h"

namespace navtwin::wgs84 {

Geodetic EcefToGeodetic(const Eigen::Vector3d& r_e_m) {
  const double x = r_e_m.x(), y = r_e_m.y(), z = r_e_m.z();
  const double p = std::hypot(x, y);
  Geodetic g;
  g.lon_rad = std::atan2(y, x);
  // Bowring's parametric-latitude start, then Newton-like fixed-point refinement of
  // tan(lat) = (z + e^2 R_N sin(lat)) / p, which converges quadratically from this start.
  const double ep2 = kE2 / (1.0 - kE2);
  const double beta = std::atan2(z * kA_m, p * kB_m);
  double lat = std::atan2(z + ep2 * kB_m * std::pow(std::sin(beta), 3),
                          p - kE2 * kA_m * std::pow(std::cos(beta), 3));
  for (int i = 0; i < 5; ++i) {
    const double rn = PrimeVerticalRadius(lat);
    const double next = std::atan2(z + kE2 * rn * std::sin(lat), p);
    const bool done = std::abs(next - lat) < 1e-15;
    lat = next;
    if (done) break;
  }
  g.lat_rad = lat;
  const double rn = PrimeVerticalRadius(lat);
  // Height from the component along the normal: well conditioned at every latitude.
  g.h_m = p * std::cos(lat) + z * std::sin(lat) - rn * (1.0 - kE2 * std::sin(lat) * std::sin(lat));
  return g;
}

Eigen::Vector3d GeodeticToNed(const Geodetic& p, const Geodetic& origin) {
  const Eigen::Vector3d d_e = GeodeticToEcef(p.lat_rad, p.lon_rad, p.h_m) -
                              GeodeticToEcef(origin.lat_rad, origin.lon_rad, origin.h_m);
  return RotationEcefFromNed(origin.lat_rad, origin.lon_rad).transpose() * d_e;
}

Geodetic NedToGeodetic(const Eigen::Vector3d& p_n_m, const Geodetic& origin) {
  const Eigen::Vector3d r_e = GeodeticToEcef(origin.lat_rad, origin.lon_rad, origin.h_m) +
                              RotationEcefFromNed(origin.lat_rad, origin.lon_rad) * p_n_m;
  return EcefToGeodetic(r_e);
}

}  // namespace navtwin::wgs84
