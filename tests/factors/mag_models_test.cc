// MagVector, MagHeading and MagHeading2Axis: meaning (zero for the true attitude; a heading
// estimate too large by d gives +d / sigma, also tilted; wrapping across +-pi; the 2-axis
// form equals the 3-axis form when level), tangent-space Jacobians (through Linearize)
// against central differences at identity, a tiny perturbation and a random attitude, and
// the constructors' checks; MagHeading's behaviour under sample noise (no bias about
// magnetic east, no information about the field axis after RemoveDipNoise).
#include "factors/mag_heading.h"
#include "factors/mag_vector.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "core/units.h"
#include "factors/attitude_manifold.h"
#include "solvers/linearize.h"
#include "tests/factors/tangent_jacobian_check.h"

namespace navtwin {
namespace factors_mag_models_test {

using namespace tangent_check;  // Block, States, ExpectTangentJacobiansMatch, Std

const AttitudeManifold kAttitudeManifold;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Central differences with step 1e-6 rad: truncation ~h^2 |r'''| / 6 and rounding
// ~eps |r| / h; with |r| <= ~100 (50 uT / 0.5 uT) both are <= 1e-8, so 1e-7 relative to
// max(1, |J|) is safe and far below any real error.
constexpr double kAttStep = 1e-6;
constexpr double kJacobianTol = 1e-7;

/// A local field in NED: horizontal part H (uT) towards azimuth D (east of true north),
/// vertical part Z (uT, down positive). Defaults: ~49 uT, inclination ~66 deg (mid-latitude).
Eigen::Vector3d Field(double declination_rad, double horizontal_uT = 20.0, double down_uT = 45.0) {
  return Eigen::Vector3d(horizontal_uT * std::cos(declination_rad), horizontal_uT * std::sin(declination_rad), down_uT);
}

double Eval1(const ceres::CostFunction& f, const Eigen::Quaterniond& q) {
  return Residual(f, {{Std(q), nullptr, 0.0}})[0];
}

TEST(MagVector, ZeroForTheTrueAttitudeAndFirstOrderInTheError) {
  const Eigen::Quaterniond q = QuatFromEuler(0.2, -0.3, 2.2);
  const Eigen::Vector3d m_n = Field(0.05);
  const double sigma = 0.5;
  const Eigen::Vector3d m_b = DcmFromQuat(q).transpose() * m_n;
  const std::unique_ptr<ceres::CostFunction> f(MagVector::Create(m_b, m_n, sigma));
  EXPECT_LT(Residual(*f, {{Std(q), nullptr, 0.0}}).norm(), 1e-13);  // rounding of 50 uT / 0.5
  // Estimate with attitude error: R_est = Exp(-phi) R_true (phi = true minus estimate),
  // R_est^T m_n = R_true^T Exp(phi) m_n ~ m_b + R_true^T (phi x m_n).
  const Eigen::Vector3d phi(0.001, -0.002, 0.003);
  const Eigen::Quaterniond q_est = ApplyAttitudeError<double>(-phi, q);
  const Eigen::Vector3d expected = DcmFromQuat(q).transpose() * phi.cross(m_n) / sigma;
  // Second-order term |phi|^2 |m| / 2 / sigma ~ 1.4e-5 * 50 / 2 / 0.5 ~ 7e-4.
  EXPECT_LT((Residual(*f, {{Std(q_est), nullptr, 0.0}}) - expected).norm(), 1e-3);
}

TEST(MagVector, TangentJacobianMatchesCentralDifferences) {
  for (const State& s : States()) {
    SCOPED_TRACE(s.name);
    const Eigen::Vector3d m_n = Field(0.1);
    const Eigen::Vector3d m_b = DcmFromQuat(s.q_n_b).transpose() * m_n + Eigen::Vector3d(0.3, -0.2, 0.5);
    const std::unique_ptr<ceres::CostFunction> f(MagVector::Create(m_b, m_n, 0.5));
    const std::vector<Block> blocks = {{Std(s.q_n_b), &kAttitudeManifold, kAttStep}};
    ExpectTangentJacobiansMatch(*f, blocks, kJacobianTol);
    // d(Exp(phi) R)^T m_n / d phi = R^T [m_n]x.
    const Linearization lin = LinearizeAt(*f, blocks);
    EXPECT_LT((lin.jacobians[0] - DcmFromQuat(s.q_n_b).transpose() * Skew<double>(m_n) / 0.5).norm(), 1e-12);
  }
}

TEST(MagVector, RejectsBadSigma) {
  const Eigen::Vector3d m = Field(0.0);
  for (const double bad : {0.0, -1.0, kNaN, kInf}) EXPECT_THROW(MagVector(m, m, bad), std::invalid_argument) << bad;
  EXPECT_THROW(MagVector(Eigen::Vector3d(kNaN, 0, 0), m, 1.0), std::invalid_argument);
}

TEST(MagHeading, ZeroForTrueAttitudeAndPlusDForHeadingTooLarge) {
  const double declination = 3.0 * kDegToRad, sigma = 0.02;
  const Eigen::Vector3d m_n = Field(declination);
  for (const Eigen::Vector3d& euler : {Eigen::Vector3d(0.0, 0.0, 0.7), Eigen::Vector3d(0.3, -0.25, -2.0),
                                       Eigen::Vector3d(-0.1, 0.4, 3.1)}) {
    SCOPED_TRACE(euler.transpose());
    const Eigen::Quaterniond q = QuatFromEuler(euler.x(), euler.y(), euler.z());
    const Eigen::Vector3d m_b = DcmFromQuat(q).transpose() * m_n;
    const std::unique_ptr<ceres::CostFunction> f(MagHeading::Create(m_b, declination, sigma, 20.0));  // H0 = Field's horizontal
    EXPECT_NEAR(Eval1(*f, q), 0.0, 1e-12);  // atan2 rounding ~1e-16 rad / 0.02
    // Same roll and pitch, yaw larger by d: R_est = Rz(d) R_true.
    for (const double d : {0.01, -0.2, 1.5}) {
      const Eigen::Quaterniond q_est = QuatFromEuler(euler.x(), euler.y(), euler.z() + d);
      EXPECT_NEAR(Eval1(*f, q_est) * sigma, d, 1e-12) << d;
    }
  }
}

TEST(MagHeading, WrapsAcrossPlusMinusPi) {
  // Magnetic north at D = 170 deg; estimated heading 20 deg too large: the raw difference
  // of the azimuths is 190 - 360 - 170 = -340 deg, wrapped +20 deg.
  const double declination = 170.0 * kDegToRad, sigma = 0.1;
  const Eigen::Vector3d m_n = Field(declination);
  const Eigen::Quaterniond q = QuatFromEuler(0.0, 0.0, 0.5);
  const std::unique_ptr<ceres::CostFunction> f(
      MagHeading::Create(DcmFromQuat(q).transpose() * m_n, declination, sigma, 20.0));
  const Eigen::Quaterniond q_est = QuatFromEuler(0.0, 0.0, 0.5 + 20.0 * kDegToRad);
  EXPECT_NEAR(Eval1(*f, q_est) * sigma, 20.0 * kDegToRad, 1e-12);
  const Eigen::Quaterniond q_est2 = QuatFromEuler(0.0, 0.0, 0.5 - 20.0 * kDegToRad);
  EXPECT_NEAR(Eval1(*f, q_est2) * sigma, -20.0 * kDegToRad, 1e-12);
}

TEST(MagHeading, TangentJacobianMatchesCentralDifferences) {
  for (const State& s : States()) {
    SCOPED_TRACE(s.name);
    const Eigen::Vector3d m_b = DcmFromQuat(s.q_n_b).transpose() * Field(0.2) + Eigen::Vector3d(0.5, -1.0, 0.3);
    const std::unique_ptr<ceres::CostFunction> f(MagHeading::Create(m_b, 0.1, 0.05, 25.0));
    ExpectTangentJacobiansMatch(*f, {{Std(s.q_n_b), &kAttitudeManifold, kAttStep}}, kJacobianTol);
  }
}

// Errors in variables: the noisy sample is in the residual and in its Jacobian. Over many
// noisy samples at the true attitude, the whitened J^T r must average to zero (a nonzero
// mean is a systematic pull of every update). Field: D = 0, H = 20, Z = 45 uT (I = 66 deg),
// per-axis noise 0.5 uT, sigma = noise / H; tangent column 1 is the rotation about
// (magnetic) east, which tilts the field towards the horizontal.
TEST(MagHeading, UnbiasedAboutMagneticEastUnderSampleNoise) {
  const double noise_uT = 0.5, h_uT = 20.0, sigma = noise_uT / h_uT;
  const Eigen::Vector3d m_n = Field(0.0, h_uT);
  const Eigen::Quaterniond q = QuatFromEuler(0.1, -0.2, 0.8);
  std::mt19937 rng(11);
  std::normal_distribution<double> normal(0.0, noise_uT);
  const int n = 20000;
  double sum_jr = 0.0, sum_bare = 0.0;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d m_b = DcmFromQuat(q).transpose() * m_n + Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    const std::unique_ptr<ceres::CostFunction> f(MagHeading::Create(m_b, 0.0, sigma, h_uT));
    const Linearization lin = LinearizeAt(*f, {{Std(q), &kAttitudeManifold, 0.0}});
    sum_jr += lin.jacobians[0](0, 1) * lin.residual[0];
    // The bare angle a / sigma (the former model) from the same sample, by hand: J_east =
    // -m_D m_E / (h^2 sigma) (a rotation phi about east moves m_N by phi m_D).
    const Eigen::Vector3d mn = DcmFromQuat(q) * m_b;
    const double h2 = mn.head<2>().squaredNorm();
    sum_bare += (-mn.z() * mn.y() / (h2 * sigma)) * (std::atan2(mn.y(), mn.x()) / sigma);
  }
  // Bare angle: E[J r] = -Z E[m_E^2] / (H^3 sigma^2) = -(Z / H) (noise / (H sigma))^2 =
  // -2.25 per sample (per rad). Each term has std ~ (Z / H) = 2.25, so the mean of 20000
  // has std ~0.016: the new model's mean is within 0.1 of zero, the bare angle's within
  // 0.1 of -2.25.
  EXPECT_NEAR(sum_jr / n, 0.0, 0.1);
  EXPECT_NEAR(sum_bare / n, -45.0 / 20.0, 0.1);
}

// The second effect: the null space of a function of R m_b is the rotation about the
// measured direction, so the noise along the dip direction gives each sample a Jacobian
// component about the true field axis (~ noise / (H sigma) = 1 whitened, per rad).
// RemoveDipNoise with the true attitude and field takes it out: what is left is second
// order (~ noise^2).
TEST(MagHeading, RemoveDipNoiseLeavesNoInformationAboutTheFieldAxis) {
  const double noise_uT = 0.5, h_uT = 20.0, sigma = noise_uT / h_uT, declination = 0.3;
  const Eigen::Vector3d m_n = Field(declination, h_uT);
  const Eigen::Vector3d axis = m_n.normalized();
  const Eigen::Quaterniond q = QuatFromEuler(-0.15, 0.1, 2.0);
  std::mt19937 rng(12);
  std::normal_distribution<double> normal(0.0, noise_uT);
  double sum_sq_raw = 0.0, sum_sq_clean = 0.0;
  const int n = 2000;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d m_b = DcmFromQuat(q).transpose() * m_n + Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    const Eigen::Vector3d clean = MagHeading::RemoveDipNoise(m_b, q, m_n);
    // The removed part is along R^T d, d in the field's vertical plane, perpendicular to it.
    const Eigen::Vector3d removed_n = DcmFromQuat(q) * (m_b - clean);
    EXPECT_LT(std::abs(removed_n.dot(axis)), 1e-12);
    EXPECT_LT(std::abs(removed_n.dot(Eigen::Vector3d(-std::sin(declination), std::cos(declination), 0.0))), 1e-12);
    for (const auto& [m, sum] : {std::make_pair(m_b, &sum_sq_raw), std::make_pair(clean, &sum_sq_clean)}) {
      const std::unique_ptr<ceres::CostFunction> f(MagHeading::Create(m, declination, sigma, h_uT));
      const double j_axis = LinearizeAt(*f, {{Std(q), &kAttitudeManifold, 0.0}}).jacobians[0].row(0).dot(axis);
      *sum += j_axis * j_axis;
    }
  }
  // Raw: E[j^2] = (noise / (H sigma))^2 = 1 (rad^-2 per sample, whitened). Clean: the
  // second-order rest, (noise / H)^2 (Z / H)^2 / sigma^2 ~ 3e-3 at most; 0.05 separates.
  EXPECT_NEAR(sum_sq_raw / n, 1.0, 0.15);
  EXPECT_LT(sum_sq_clean / n, 0.05);
  // Degenerate references leave the sample unchanged.
  const Eigen::Vector3d m_b(10.0, -3.0, 40.0);
  EXPECT_EQ(MagHeading::RemoveDipNoise(m_b, q, Eigen::Vector3d::Zero()), m_b);
  EXPECT_EQ(MagHeading::RemoveDipNoise(m_b, q, Eigen::Vector3d(0.0, 0.0, 50.0)), m_b);
}

TEST(MagHeading2Axis, MatchesMagHeadingWhenLevel) {
  const double declination = -7.0 * kDegToRad, sigma = 0.03;
  const Eigen::Vector3d m_n = Field(declination);
  for (const double yaw_true : {0.0, 1.2, -2.9, M_PI}) {
    const Eigen::Vector3d m_b = DcmFromQuat(QuatFromEuler(0.0, 0.0, yaw_true)).transpose() * m_n;
    const std::unique_ptr<ceres::CostFunction> f3(MagHeading::Create(m_b, declination, sigma, 20.0));
    const std::unique_ptr<ceres::CostFunction> f2(MagHeading2Axis::Create(m_b.x(), m_b.y(), declination, sigma));
    for (const double d : {0.0, 0.05, -0.6, 2.5}) {
      SCOPED_TRACE("yaw " + std::to_string(yaw_true) + " d " + std::to_string(d));
      const Eigen::Quaterniond q_est = QuatFromEuler(0.0, 0.0, yaw_true + d);
      // Both are wrap(yaw_est - yaw_true) / sigma; atan2 rounding ~1e-16 / 0.03.
      EXPECT_NEAR(Eval1(*f2, q_est), Eval1(*f3, q_est), 1e-12);
      EXPECT_NEAR(Eval1(*f2, q_est) * sigma, d, 1e-12);
      // In the tangent, a rotation about down moves the heading one for one:
      // d r / d phi_d = 1 / sigma for both (the tilt columns differ: the 3-axis form sees
      // the vertical field tilt into the horizontal plane).
      const std::vector<Block> blocks = {{Std(q_est), &kAttitudeManifold, 0.0}};
      EXPECT_NEAR(LinearizeAt(*f2, blocks).jacobians[0](0, 2), 1.0 / sigma, 1e-10);
      EXPECT_NEAR(LinearizeAt(*f3, blocks).jacobians[0](0, 2), 1.0 / sigma, 1e-10);
    }
  }
}

TEST(MagHeading2Axis, MeasuredHeadingAndTangentJacobian) {
  // A level compass heading 90 deg (east) sees magnetic north (D = 0) on its left: my < 0.
  const MagHeading2Axis east(0.0, -20.0, 0.0, 0.1);
  EXPECT_NEAR(east.heading_meas_rad(), M_PI / 2, 1e-15);
  for (const State& s : States()) {
    SCOPED_TRACE(s.name);
    const std::unique_ptr<ceres::CostFunction> f(MagHeading2Axis::Create(15.0, -7.0, 0.05, 0.05));
    ExpectTangentJacobiansMatch(*f, {{Std(s.q_n_b), &kAttitudeManifold, kAttStep}}, kJacobianTol);
  }
}

TEST(MagHeading, RejectsBadSigma) {
  for (const double bad : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_THROW(MagHeading(Field(0.0), 0.0, bad, 20.0), std::invalid_argument) << bad;
    EXPECT_THROW(MagHeading(Field(0.0), 0.0, 0.1, bad), std::invalid_argument) << bad;
    EXPECT_THROW(MagHeading2Axis(20.0, 1.0, 0.0, bad), std::invalid_argument) << bad;
  }
  EXPECT_THROW(MagHeading(Field(0.0), kNaN, 0.1, 20.0), std::invalid_argument);
  EXPECT_THROW(MagHeading2Axis(kInf, 1.0, 0.0, 0.1), std::invalid_argument);
}

}  // namespace factors_mag_models_test
}  // namespace navtwin
