#include "core/earth.h"

#include <random>

#include <gtest/gtest.h>

#include "core/rotation.h"

namespace navtwin::wgs84 {
namespace core_earth_test {

TEST(Earth, DerivedConstantsMatchTr8350) {
  // NIMA TR8350.2 Table 3.3: b = 6356752.3142 m, e^2 = 6.69437999014e-3 (values printed
  // to 0.1 mm and 1e-14).
  EXPECT_NEAR(kB_m, 6356752.3142, 1e-4);
  EXPECT_NEAR(kE2, 6.69437999014e-3, 1e-14);
}

TEST(Earth, RadiiAtEquatorAndPole) {
  // Closed forms: R_N(0) = a, R_M(0) = a (1 - e^2), R_N(90) = R_M(90) = a^2 / b.
  EXPECT_NEAR(PrimeVerticalRadius(0.0), kA_m, 1e-6);
  EXPECT_NEAR(MeridianRadius(0.0), 6335439.3272, 1e-3);  // a(1-e^2), printed to 1 mm
  EXPECT_NEAR(PrimeVerticalRadius(M_PI / 2), 6399593.6258, 1e-3);
  EXPECT_NEAR(MeridianRadius(M_PI / 2), 6399593.6258, 1e-3);
}

TEST(Earth, NormalGravityMatchesPublishedValues) {
  // TR8350.2 Table 3.4: gamma_e = 9.7803253359, gamma_p = 9.8321849378 m/s^2 (printed
  // to 1e-10).
  EXPECT_NEAR(NormalGravity(0.0, 0.0), 9.7803253359, 1e-10);
  EXPECT_NEAR(NormalGravity(M_PI / 2, 0.0), 9.8321849378, 1e-9);
  // At 45 deg, the GRS80 international gravity formula (Moritz 1980, series form) gives
  // 9.806199203; the series and the closed form of WGS84 differ by ~1.5e-6 m/s^2.
  EXPECT_NEAR(NormalGravity(M_PI / 4, 0.0), 9.806199203, 2e-6);
  // Free-air gradient near the surface: -3.0877e-6 s^-2 at 45 deg (first-order term of
  // eq. 4-3: 2 gamma / a (1 + f + m - f)); 0.1 % covers the second-order term at 1 km.
  const double gradient = (NormalGravity(M_PI / 4, 1000.0) - NormalGravity(M_PI / 4, 0.0)) / 1000.0;
  EXPECT_NEAR(gradient, -3.0877e-6, 3.1e-9);
}

TEST(Earth, RatesInNed) {
  const double lat = 45.0 * kDegToRad;
  const Eigen::Vector3d w = EarthRateNed(lat);
  EXPECT_NEAR(w.norm(), kOmegaIe_radps, 1e-18);
  EXPECT_NEAR(w.x(), kOmegaIe_radps * std::sqrt(0.5), 1e-18);
  EXPECT_NEAR(w.z(), -kOmegaIe_radps * std::sqrt(0.5), 1e-18);
  // Flying east at 100 m/s on the equator: the frame turns about north at v / R_N.
  const Eigen::Vector3d r = TransportRateNed(0.0, 0.0, Eigen::Vector3d(0, 100, 0));
  EXPECT_NEAR(r.x(), 100.0 / kA_m, 1e-18);
  EXPECT_NEAR(r.y(), 0.0, 1e-18);
  // Flying north: the frame turns about -east at v / (R_M + h).
  const Eigen::Vector3d s = TransportRateNed(0.0, 1000.0, Eigen::Vector3d(100, 0, 0));
  EXPECT_NEAR(s.y(), -100.0 / (MeridianRadius(0.0) + 1000.0), 1e-18);
}

TEST(Earth, EcefKnownPointsAndRoundTrip) {
  EXPECT_LT((GeodeticToEcef(0.0, 0.0, 0.0) - Eigen::Vector3d(kA_m, 0, 0)).norm(), 1e-9);
  EXPECT_LT((GeodeticToEcef(M_PI / 2, 0.3, 0.0) - Eigen::Vector3d(0, 0, kB_m)).norm(), 1e-6);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> lat(-M_PI / 2, M_PI / 2), lon(-M_PI, M_PI), h(-500.0, 4.0e5);
  for (int i = 0; i < 500; ++i) {
    const double la = lat(rng), lo = lon(rng), hh = h(rng);
    const Geodetic g = EcefToGeodetic(GeodeticToEcef(la, lo, hh));
    // 1e-11 rad is 0.06 mm on the ground; heights to 0.1 mm.
    EXPECT_NEAR(g.lat_rad, la, 1e-11);
    EXPECT_NEAR(WrapPi(g.lon_rad - lo), 0.0, 1e-11);
    EXPECT_NEAR(g.h_m, hh, 1e-4);
  }
}

TEST(Earth, LocalNedRoundTripAndDirections) {
  const Geodetic o{37.5 * kDegToRad, 127.0 * kDegToRad, 50.0};
  // 1 km north along the meridian is about 1000 / R_M rad of latitude.
  const Geodetic north = NedToGeodetic(Eigen::Vector3d(1000, 0, 0), o);
  EXPECT_NEAR((north.lat_rad - o.lat_rad) * MeridianRadius(o.lat_rad), 1000.0, 0.01);
  const Eigen::Vector3d back = GeodeticToNed(NedToGeodetic(Eigen::Vector3d(1234.5, -987.6, 12.3), o), o);
  EXPECT_LT((back - Eigen::Vector3d(1234.5, -987.6, 12.3)).norm(), 1e-6);
  // The NED axes from RotationEcefFromNed are orthonormal and down points to the centre side.
  const Eigen::Matrix3d R = RotationEcefFromNed(o.lat_rad, o.lon_rad);
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  EXPECT_LT(R.col(2).dot(GeodeticToEcef(o.lat_rad, o.lon_rad, o.h_m)), 0.0);
}

}  // namespace core_earth_test
}  // namespace navtwin::wgs84
