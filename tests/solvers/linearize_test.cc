// Linearize: the tangent Jacobian is the ambient Jacobian times each manifold's
// PlusJacobian (the ambient one for nullptr); it predicts the residual at x (+) dx to first
// order, which gives the filter relation 0 ~ r(x_est) + J dx for x_true = x_est (+) dx;
// the reusing overload gives the same result; bad arguments are rejected.
#include "solvers/linearize.h"

#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/units.h"
#include "factors/attitude_manifold.h"
#include "factors/baro_height.h"
#include "factors/gnss_position.h"
#include "factors/position_manifold.h"
#include "factors/zero_velocity.h"

namespace navtwin {
namespace solvers_linearize_test {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

const PositionManifold kPositionManifold;
const AttitudeManifold kAttitudeManifold;

struct Point {
  Eigen::Vector3d pos{47.0 * kDegToRad, 8.5 * kDegToRad, 430.0};
  Eigen::Vector4d q = QuatFromEuler(0.1, -0.05, 2.0).coeffs();
};

std::unique_ptr<ceres::CostFunction> MakeGnss(const Point& p) {
  const wgs84::Geodetic meas = wgs84::NedToGeodetic(Eigen::Vector3d(2.0, -1.0, 0.5), {p.pos[0], p.pos[1], p.pos[2]});
  return std::unique_ptr<ceres::CostFunction>(GnssPosition::Create(
      Eigen::Vector3d(meas.lat_rad, meas.lon_rad, meas.h_m), Eigen::Vector3d(0.6, -0.4, -1.3), Eigen::Vector3d(0.5, 0.7, 1.5)));
}

TEST(Linearize, IsTheAmbientJacobianTimesThePlusJacobian) {
  const Point p;
  const std::unique_ptr<ceres::CostFunction> f = MakeGnss(p);
  // Ambient Jacobians straight from Ceres (row-major).
  RowMajor a0(3, 3), a1(3, 4);
  Eigen::Vector3d r;
  const double* params[] = {p.pos.data(), p.q.data()};
  double* jac[] = {a0.data(), a1.data()};
  ASSERT_TRUE(f->Evaluate(params, r.data(), jac));

  // nullptr manifolds: the ambient Jacobians, bit for bit.
  const Linearization ambient = Linearize(*f, {p.pos.data(), p.q.data()}, {nullptr, nullptr});
  ASSERT_EQ(ambient.jacobians.size(), 2u);
  EXPECT_EQ(ambient.residual, Eigen::VectorXd(r));
  EXPECT_EQ(ambient.jacobians[0], Eigen::MatrixXd(a0));
  EXPECT_EQ(ambient.jacobians[1], Eigen::MatrixXd(a1));

  // With manifolds: A_k P_k, P_k from each manifold's PlusJacobian (row-major).
  RowMajor p0(3, 3), p1(4, 3);
  ASSERT_TRUE(kPositionManifold.PlusJacobian(p.pos.data(), p0.data()));
  ASSERT_TRUE(kAttitudeManifold.PlusJacobian(p.q.data(), p1.data()));
  const Linearization tangent = Linearize(*f, {p.pos.data(), p.q.data()}, {&kPositionManifold, &kAttitudeManifold});
  ASSERT_EQ(tangent.jacobians.size(), 2u);
  EXPECT_EQ(tangent.jacobians[0].rows(), 3);
  EXPECT_EQ(tangent.jacobians[0].cols(), 3);
  EXPECT_EQ(tangent.jacobians[1].rows(), 3);
  EXPECT_EQ(tangent.jacobians[1].cols(), 3);
  // Same products in possibly different summation order: rounding ~1e-16 of O(1) entries.
  EXPECT_LT((tangent.jacobians[0] - a0 * p0).norm(), 1e-14);
  EXPECT_LT((tangent.jacobians[1] - a1 * p1).norm(), 1e-14);

  // Mixed: only the attitude through its manifold.
  const Linearization mixed = Linearize(*f, {p.pos.data(), p.q.data()}, {nullptr, &kAttitudeManifold});
  EXPECT_EQ(mixed.jacobians[0], Eigen::MatrixXd(a0));
  EXPECT_LT((mixed.jacobians[1] - tangent.jacobians[1]).norm(), 1e-15);
}

TEST(Linearize, PredictsTheResidualToFirstOrderAsAFilterUsesIt) {
  // Truth x_true = x_est (+) dx and a measurement made from the truth (r(x_true) = 0):
  // then r(x_est) + J dx = O(|dx|^2). With dx ~ (3 m, 0.02 rad) the remainder is the
  // attitude's second-order term |l| |phi|^2 / 2 / sigma ~ 1.6 * 4e-4 / 2 / 0.5 ~ 7e-4
  // (the position part is linear), against a first-order change |J dx| of several units.
  Point truth;
  const Eigen::Vector3d lever(0.6, -0.4, -1.3), sigma(0.5, 0.7, 1.5);
  const Eigen::Vector3d q_rot = DcmFromQuat(Eigen::Quaterniond(truth.q)) * lever;
  const wgs84::Geodetic ant = wgs84::NedToGeodetic(q_rot, {truth.pos[0], truth.pos[1], truth.pos[2]});
  const std::unique_ptr<ceres::CostFunction> f(
      GnssPosition::Create(Eigen::Vector3d(ant.lat_rad, ant.lon_rad, ant.h_m), lever, sigma));

  const Eigen::Vector3d dp(2.0, -3.0, 1.0), dphi(0.01, -0.015, 0.02);
  // x_est = x_true (+) (-dx) to first order; build the estimate and then the exact dx
  // with Minus so that x_true = x_est (+) dx holds exactly on the manifold.
  Point est;
  ASSERT_TRUE(kPositionManifold.Plus(truth.pos.data(), Eigen::Vector3d(-dp).data(), est.pos.data()));
  ASSERT_TRUE(kAttitudeManifold.Plus(truth.q.data(), Eigen::Vector3d(-dphi).data(), est.q.data()));
  Eigen::Vector3d dx_p, dx_phi;
  ASSERT_TRUE(kPositionManifold.Minus(truth.pos.data(), est.pos.data(), dx_p.data()));
  ASSERT_TRUE(kAttitudeManifold.Minus(truth.q.data(), est.q.data(), dx_phi.data()));

  const Linearization lin = Linearize(*f, {est.pos.data(), est.q.data()}, {&kPositionManifold, &kAttitudeManifold});
  const Eigen::Vector3d predicted = lin.residual + lin.jacobians[0] * dx_p + lin.jacobians[1] * dx_phi;
  EXPECT_GT(lin.residual.norm(), 3.0);  // the estimate is clearly off
  // Chart error over |l| (~3e-7 m) plus the attitude remainder above.
  EXPECT_LT(predicted.norm(), 2e-3) << predicted.transpose();
  // Halving dx quarters the remainder (second order): the Jacobian is right, not just close.
  Point est_half;
  ASSERT_TRUE(kPositionManifold.Plus(truth.pos.data(), Eigen::Vector3d(-dp / 2).data(), est_half.pos.data()));
  ASSERT_TRUE(kAttitudeManifold.Plus(truth.q.data(), Eigen::Vector3d(-dphi / 2).data(), est_half.q.data()));
  ASSERT_TRUE(kPositionManifold.Minus(truth.pos.data(), est_half.pos.data(), dx_p.data()));
  ASSERT_TRUE(kAttitudeManifold.Minus(truth.q.data(), est_half.q.data(), dx_phi.data()));
  const Linearization lin_half =
      Linearize(*f, {est_half.pos.data(), est_half.q.data()}, {&kPositionManifold, &kAttitudeManifold});
  const Eigen::Vector3d predicted_half =
      lin_half.residual + lin_half.jacobians[0] * dx_p + lin_half.jacobians[1] * dx_phi;
  // Ratio 4 up to the O(|dx|^3) terms and the ~1e-6 chart error: 3..5 is a clear margin.
  const double ratio = predicted.norm() / predicted_half.norm();
  EXPECT_GT(ratio, 3.0);
  EXPECT_LT(ratio, 5.0);
}

TEST(Linearize, ReusingOverloadMatchesAcrossModelsOfDifferentSizes) {
  const Point p;
  const std::unique_ptr<ceres::CostFunction> gnss = MakeGnss(p);
  const std::unique_ptr<ceres::CostFunction> baro(BaroHeight::Create(400.0, 3.0));
  const std::unique_ptr<ceres::CostFunction> zupt(ZeroVelocity::Create(0.05));
  const Eigen::Vector3d v(0.1, -0.2, 0.03);
  Linearization out;
  for (int pass = 0; pass < 2; ++pass) {  // the second pass runs on grown scratch buffers
    Linearize(*gnss, {p.pos.data(), p.q.data()}, {&kPositionManifold, &kAttitudeManifold}, &out);
    const Linearization fresh_gnss =
        Linearize(*gnss, {p.pos.data(), p.q.data()}, {&kPositionManifold, &kAttitudeManifold});
    EXPECT_EQ(out.residual, fresh_gnss.residual);
    ASSERT_EQ(out.jacobians.size(), 2u);
    EXPECT_EQ(out.jacobians[0], fresh_gnss.jacobians[0]);
    EXPECT_EQ(out.jacobians[1], fresh_gnss.jacobians[1]);

    Linearize(*baro, {p.pos.data()}, {&kPositionManifold}, &out);
    ASSERT_EQ(out.jacobians.size(), 1u);
    ASSERT_EQ(out.residual.size(), 1);
    EXPECT_DOUBLE_EQ(out.residual[0], 10.0);  // (430 - 400) / 3
    EXPECT_EQ(out.jacobians[0], Eigen::MatrixXd(Eigen::RowVector3d(0.0, 0.0, -1.0 / 3.0)));

    Linearize(*zupt, {v.data()}, {nullptr}, &out);
    ASSERT_EQ(out.jacobians.size(), 1u);
    EXPECT_LT((out.residual - v / 0.05).norm(), 1e-15);
    EXPECT_EQ(out.jacobians[0], Eigen::MatrixXd(Eigen::Matrix3d::Identity() / 0.05));
  }
}

/// A cost function that always fails to evaluate.
class Failing final : public ceres::CostFunction {
 public:
  Failing() {
    set_num_residuals(1);
    mutable_parameter_block_sizes()->push_back(3);
  }
  bool Evaluate(double const* const*, double*, double**) const override { return false; }
};

TEST(Linearize, RejectsBadArguments) {
  const Point p;
  const std::unique_ptr<ceres::CostFunction> gnss = MakeGnss(p);
  // Block and manifold counts must match the cost function.
  EXPECT_THROW(Linearize(*gnss, {p.pos.data()}, {&kPositionManifold}), std::invalid_argument);
  EXPECT_THROW(Linearize(*gnss, {p.pos.data(), p.q.data()}, {&kPositionManifold}), std::invalid_argument);
  // A manifold's ambient size must match its block (attitude manifold on the position).
  EXPECT_THROW(Linearize(*gnss, {p.pos.data(), p.q.data()}, {&kAttitudeManifold, &kAttitudeManifold}),
               std::invalid_argument);
  // A failing evaluation is an error, not garbage.
  const Failing failing;
  EXPECT_THROW(Linearize(failing, {p.pos.data()}, {nullptr}), std::runtime_error);
}

}  // namespace solvers_linearize_test
}  // namespace navtwin
