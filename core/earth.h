// WGS84 Earth model: constants, radii of curvature, normal gravity with height, Earth and
// transport rates in NED, and geodetic <-> ECEF <-> local NED conversions.
//
// References:
//  [1] NIMA TR8350.2, "Department of Defense World Geodetic System 1984", 3rd ed., 2000:
//      defining constants (Table 3.1), Somigliana normal gravity on the ellipsoid
//      (eq. 4-1), its height correction to second order (eq. 4-3), derived constants
//      (Table 3.3: gamma_e, k, m).
//  [2] P. D. Groves, "Principles of GNSS, Inertial, and Multisensor Integrated Navigation
//      Systems", 2nd ed., 2013, sec. 2.4 (radii, ECEF), 5.4 (NED rates).
//
// Templated on the scalar so that Ceres residuals can use the same formulas.
// Positions: latitude, longitude in rad, height h above the ellipsoid in m.
#pragma once

#include <cmath>

#include <Eigen/Core>

namespace navtwin::wgs84 {

constexpr double kA_m = 6378137.0;                  ///< semi-major axis [1]
constexpr double kF = 1.0 / 298.257223563;          ///< flattening [1]
constexpr double kB_m = kA_m * (1.0 - kF);          ///< semi-minor axis
constexpr double kE2 = kF * (2.0 - kF);             ///< first eccentricity squared
constexpr double kOmegaIe_radps = 7.292115e-5;      ///< Earth rotation rate [1]
constexpr double kGM_m3_s2 = 3.986004418e14;        ///< geocentric gravitational constant [1]
constexpr double kGammaE_mps2 = 9.7803253359;       ///< normal gravity at the equator [1]
constexpr double kSomiglianaK = 0.00193185265241;   ///< k = (b gamma_p)/(a gamma_e) - 1 [1]
constexpr double kM = 0.00344978650684;             ///< m = omega^2 a^2 b / GM [1]

/// Meridian radius of curvature R_M (north-south), m.
template <typename T>
T MeridianRadius(const T& lat_rad) {
  using std::sin;
  using std::sqrt;
  const T s = sin(lat_rad);
  const T d = T(1) - T(kE2) * s * s;
  return T(kA_m * (1.0 - kE2)) / (d * sqrt(d));
}

/// Prime-vertical (transverse) radius of curvature R_N (east-west), m.
template <typename T>
T PrimeVerticalRadius(const T& lat_rad) {
  using std::sin;
  using std::sqrt;
  const T s = sin(lat_rad);
  return T(kA_m) / sqrt(T(1) - T(kE2) * s * s);
}

/// Normal gravity magnitude (gravitation plus centrifugal), m/s^2, along the ellipsoid
/// normal: Somigliana on the ellipsoid [1, eq. 4-1] with the second-order height
/// correction [1, eq. 4-3]:
///   gamma_h = gamma [1 - 2/a (1 + f + m - 2 f sin^2 lat) h + 3 h^2 / a^2].
template <typename T>
T NormalGravity(const T& lat_rad, const T& h_m) {
  using std::sin;
  using std::sqrt;
  const T s2 = sin(lat_rad) * sin(lat_rad);
  const T gamma = T(kGammaE_mps2) * (T(1) + T(kSomiglianaK) * s2) / sqrt(T(1) - T(kE2) * s2);
  const T corr = T(1) - T(2.0 / kA_m) * (T(1.0 + kF + kM) - T(2.0 * kF) * s2) * h_m +
                 T(3.0 / (kA_m * kA_m)) * h_m * h_m;
  return gamma * corr;
}

/// Gravity vector in NED, m/s^2: (0, 0, gamma_h). The normal gravity's tiny north
/// component off the ellipsoid (< 1e-6 g below 10 km) and the deflection of the vertical
/// are neglected, as in common strapdown practice.
template <typename T>
Eigen::Matrix<T, 3, 1> GravityNed(const T& lat_rad, const T& h_m) {
  return Eigen::Matrix<T, 3, 1>(T(0), T(0), NormalGravity(lat_rad, h_m));
}

/// Earth rotation rate omega_ie_n in NED, rad/s.
template <typename T>
Eigen::Matrix<T, 3, 1> EarthRateNed(const T& lat_rad) {
  using std::cos;
  using std::sin;
  return Eigen::Matrix<T, 3, 1>(T(kOmegaIe_radps) * cos(lat_rad), T(0),
                                -T(kOmegaIe_radps) * sin(lat_rad));
}

/// Transport rate omega_en_n (rotation of NED over the ellipsoid), rad/s:
///   (vE/(R_N+h), -vN/(R_M+h), -vE tan(lat)/(R_N+h)).
template <typename T>
Eigen::Matrix<T, 3, 1> TransportRateNed(const T& lat_rad, const T& h_m,
                                        const Eigen::Matrix<T, 3, 1>& v_n_mps) {
  using std::tan;
  const T rn_h = PrimeVerticalRadius(lat_rad) + h_m;
  const T rm_h = MeridianRadius(lat_rad) + h_m;
  return Eigen::Matrix<T, 3, 1>(v_n_mps.y() / rn_h, -v_n_mps.x() / rm_h,
                                -v_n_mps.y() * tan(lat_rad) / rn_h);
}

/// Geodetic (lat, lon rad; h m) -> ECEF (m).
template <typename T>
Eigen::Matrix<T, 3, 1> GeodeticToEcef(const T& lat_rad, const T& lon_rad, const T& h_m) {
  using std::cos;
  using std::sin;
  const T rn = PrimeVerticalRadius(lat_rad);
  const T cl = cos(lat_rad);
  return Eigen::Matrix<T, 3, 1>((rn + h_m) * cl * cos(lon_rad), (rn + h_m) * cl * sin(lon_rad),
                                (rn * T(1.0 - kE2) + h_m) * sin(lat_rad));
}

/// Rotation R_e_n from NED at (lat, lon) to ECEF.
template <typename T>
Eigen::Matrix<T, 3, 3> RotationEcefFromNed(const T& lat_rad, const T& lon_rad) {
  using std::cos;
  using std::sin;
  const T sl = sin(lat_rad), cl = cos(lat_rad), so = sin(lon_rad), co = cos(lon_rad);
  Eigen::Matrix<T, 3, 3> R;
  R << -sl * co, -so, -cl * co,
       -sl * so, co, -cl * so,
       cl, T(0), -sl;
  return R;
}

/// Geodetic coordinates of a point.
struct Geodetic {
  double lat_rad = 0.0;
  double lon_rad = 0.0;
  double h_m = 0.0;
};

/// ECEF (m) -> geodetic. Newton iteration on latitude from Bowring's start; converges to
/// < 1e-12 rad and < 1e-6 m everywhere outside a 1 km ball around the Earth's centre.
Geodetic EcefToGeodetic(const Eigen::Vector3d& r_e_m);

/// NED offset (m) of point p from origin o, through ECEF (exact, any distance).
Eigen::Vector3d GeodeticToNed(const Geodetic& p, const Geodetic& origin);

/// Geodetic coordinates of the point at NED offset p_n_m from origin (exact, through ECEF).
Geodetic NedToGeodetic(const Eigen::Vector3d& p_n_m, const Geodetic& origin);

}  // namespace navtwin::wgs84
