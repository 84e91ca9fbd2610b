// PositionManifold: Ceres' manifold invariants (ceres/manifold_test_utils.h) at the
// equator, 60 deg N, high altitude and next to the date line; analytic Jacobians against
// central differences; Plus is the local NED displacement to first order; the templated
// PositionPlus / PositionMinus work with Jets.
#include "factors/position_manifold.h"

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <ceres/jet.h>
#include <ceres/manifold_test_utils.h>
#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/units.h"

namespace navtwin {
namespace factors_position_manifold_test {

using Mat3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

struct Case {
  std::string name;
  Eigen::Vector3d x;      // {lat_rad, lon_rad, h_m}
  Eigen::Vector3d delta;  // dp_ned_m
  Eigen::Vector3d y;      // a second point
};

std::vector<Case> Cases() {
  std::mt19937 rng(4242);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const auto ned = [&](double scale_m) -> Eigen::Vector3d {
    return Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)) * scale_m;
  };
  const auto plus = [](const Eigen::Vector3d& x, const Eigen::Vector3d& d) {
    Eigen::Vector3d out;
    PositionPlus(x.data(), d.data(), out.data());
    return out;
  };
  std::vector<Case> cases;
  const Eigen::Vector3d equator(0.0, 0.3, 50.0);
  cases.push_back({"equator", equator, ned(100.0), plus(equator, ned(5000.0))});
  const Eigen::Vector3d north60(60.0 * kDegToRad, -2.0, 200.0);
  cases.push_back({"60N", north60, ned(100.0), plus(north60, ned(5000.0))});
  const Eigen::Vector3d high(-35.0 * kDegToRad, 2.5, 20000.0);
  cases.push_back({"high_altitude", high, ned(100.0), plus(high, ned(5000.0))});
  // y on the other side of the date line: Minus must take the short way round.
  const Eigen::Vector3d dateline(10.0 * kDegToRad, M_PI - 1e-6, 10.0);
  cases.push_back({"date_line", dateline, ned(100.0), Eigen::Vector3d(10.0 * kDegToRad, -M_PI + 1e-6, 30.0)});
  return cases;
}

Eigen::Vector3d Plus(const PositionManifold& m, const Eigen::Vector3d& x, const Eigen::Vector3d& d) {
  Eigen::Vector3d out;
  EXPECT_TRUE(m.Plus(x.data(), d.data(), out.data()));
  return out;
}

Eigen::Vector3d Minus(const PositionManifold& m, const Eigen::Vector3d& y, const Eigen::Vector3d& x) {
  Eigen::Vector3d out;
  EXPECT_TRUE(m.Minus(y.data(), x.data(), out.data()));
  return out;
}

TEST(PositionManifold, CeresManifoldInvariantsHold) {
  using namespace ceres;  // the macro names Ceres' matchers and ceres::Vector unqualified
  const PositionManifold m;
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    const Vector x = c.x, delta = c.delta, y = c.y;
    // The checks are relative. Round trips through (lat, lon) lose ~eps |lat| (M + h) ~
    // 1e-9 m on deltas of ~100 m (1e-11 relative); Ridders' differences are good to ~1e-10
    // relative. 1e-9 leaves margin and would catch any wrong radius (relative ~1e-3).
    EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD(m, x, delta, y, 1e-9);
  }
}

TEST(PositionManifold, MinusTakesTheShortWayAcrossTheDateLine) {
  const PositionManifold m;
  const Case c = Cases().back();
  const Eigen::Vector3d d = Minus(m, c.y, c.x);
  // 2e-6 rad of longitude east at 10 deg N: 2e-6 (N + h) cos(lat) ~ 12.56 m.
  const double expected_e = 2e-6 * (wgs84::PrimeVerticalRadius(c.x[0]) + c.x[2]) * std::cos(c.x[0]);
  EXPECT_NEAR(d.x(), 0.0, 1e-12);
  EXPECT_NEAR(d.y(), expected_e, 1e-6);  // lon difference formed from ~pi values: ~1e-9 m rounding
  EXPECT_NEAR(d.z(), -20.0, 1e-12);
}

TEST(PositionManifold, JacobiansAreDiagonalAndMatchCentralDifferences) {
  const PositionManifold m;
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    Mat3 plus_jacobian, minus_jacobian;
    ASSERT_TRUE(m.PlusJacobian(c.x.data(), plus_jacobian.data()));
    ASSERT_TRUE(m.MinusJacobian(c.x.data(), minus_jacobian.data()));
    // Plus is linear in delta and Minus linear in y (radii at x), so central differences
    // have no truncation error; steps 1 m and 1e-7 rad / 1 m keep rounding ~1e-16 relative
    // to the O(1) coordinates below 1e-8 relative to each entry.
    Mat3 numeric_plus, numeric_minus;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d h = Eigen::Vector3d::Unit(i);
      numeric_plus.col(i) = (Plus(m, c.x, h) - Plus(m, c.x, -h)) / 2.0;
      const double step = i < 2 ? 1e-7 : 1.0;
      const Eigen::Vector3d hy = step * Eigen::Vector3d::Unit(i);
      numeric_minus.col(i) = (Minus(m, c.x + hy, c.x) - Minus(m, c.x - hy, c.x)) / (2.0 * step);
    }
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        if (i != j) {
          EXPECT_EQ(plus_jacobian(i, j), 0.0);
          EXPECT_EQ(minus_jacobian(i, j), 0.0);
        }
      }
      EXPECT_NEAR(plus_jacobian(i, i), numeric_plus(i, i), 1e-8 * std::abs(plus_jacobian(i, i)));
      EXPECT_NEAR(minus_jacobian(i, i), numeric_minus(i, i), 1e-8 * std::abs(minus_jacobian(i, i)));
    }
    EXPECT_LT((numeric_plus - Mat3(numeric_plus.diagonal().asDiagonal())).norm(), 1e-12);
    // MinusJacobian * PlusJacobian = I: products of reciprocals, rounding only.
    EXPECT_LT((minus_jacobian * plus_jacobian - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  }
}

TEST(PositionManifold, PlusIsTheLocalNedDisplacement) {
  // Through ECEF (wgs84::GeodeticToNed, exact): Plus(x, d) lies at NED offset d from x up
  // to the chart's second-order error ~|d|^2 / R ~ (1 km)^2 / 6.4e6 m = 0.16 m (the NED
  // plane vs the curved ellipsoid coordinates); at 10 m it is ~1.6e-5 m.
  const PositionManifold m;
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    for (const double scale : {10.0, 1000.0}) {
      const Eigen::Vector3d d = c.delta.normalized() * scale;
      const Eigen::Vector3d y = Plus(m, c.x, d);
      const Eigen::Vector3d ned = wgs84::GeodeticToNed({y[0], y[1], y[2]}, {c.x[0], c.x[1], c.x[2]});
      const double tol = 2.0 * scale * scale / 6.3e6;  // 2 |d|^2 / R_min
      EXPECT_LT((ned - d).norm(), tol) << "scale " << scale << " ned " << ned.transpose();
    }
  }
}

TEST(PositionManifold, TemplatedFunctionsWorkWithJets) {
  // PositionPlus on Jets: the derivative w.r.t. delta at 0 equals PlusJacobian.
  using Jet = ceres::Jet<double, 3>;
  const PositionManifold m;
  const Case c = Cases()[1];
  const Jet x[3] = {Jet(c.x[0]), Jet(c.x[1]), Jet(c.x[2])};
  const Jet delta[3] = {Jet(0.0, 0), Jet(0.0, 1), Jet(0.0, 2)};
  Jet out[3];
  PositionPlus(x, delta, out);
  Mat3 plus_jacobian;
  ASSERT_TRUE(m.PlusJacobian(c.x.data(), plus_jacobian.data()));
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(out[i].a, c.x[i]);
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(out[i].v[j], plus_jacobian(i, j), 1e-15 * (1 + std::abs(plus_jacobian(i, j))));
  }
  // PositionMinus on Jets w.r.t. y at y = x equals MinusJacobian.
  const Jet y[3] = {Jet(c.x[0], 0), Jet(c.x[1], 1), Jet(c.x[2], 2)};
  PositionMinus(y, x, out);
  Mat3 minus_jacobian;
  ASSERT_TRUE(m.MinusJacobian(c.x.data(), minus_jacobian.data()));
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(out[i].a, 0.0);
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(out[i].v[j], minus_jacobian(i, j), 1e-15 * (1 + std::abs(minus_jacobian(i, j))));
  }
}

}  // namespace factors_position_manifold_test
}  // namespace navtwin
