#include "core/rotation.h"

#include <random>

#include <ceres/jet.h>
#include <gtest/gtest.h>

namespace navtwin {
namespace core_rotation_test {

// Round trips through exp/log and the conversions lose a few ulps per operation;
// 1e-12 on unit-scale quantities leaves a margin of ~1000 ulps.
constexpr double kTol = 1e-12;

Eigen::Vector3d RandomRotVec(std::mt19937* rng, double max_angle) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, max_angle);
  Eigen::Vector3d axis(n(*rng), n(*rng), n(*rng));
  return axis.normalized() * u(*rng);
}

TEST(Rotation, SkewIsCrossProductAndVeeInvertsIt) {
  const Eigen::Vector3d a(0.3, -1.2, 2.5), b(-0.7, 0.4, 1.1);
  EXPECT_LT((Skew(a) * b - a.cross(b)).norm(), kTol);
  EXPECT_LT((Vee(Skew(a)) - a).norm(), kTol);
}

TEST(Rotation, ExpMatchesRodriguesAtModerateAngles) {
  std::mt19937 rng(7);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d phi = RandomRotVec(&rng, 3.0);
    const double t = phi.norm();
    const Eigen::Matrix3d K = Skew(phi);
    const Eigen::Matrix3d R = Eigen::Matrix3d::Identity() + std::sin(t) / t * K +
                              (1.0 - std::cos(t)) / (t * t) * K * K;
    EXPECT_LT((ExpSO3(phi) - R).norm(), kTol);
    EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), kTol);
  }
}

TEST(Rotation, ExpLogRoundTripAtRandomTinyAndNearPi) {
  std::mt19937 rng(11);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d phi = RandomRotVec(&rng, M_PI - 1e-6);
    EXPECT_LT((LogSO3(ExpSO3(phi)) - phi).norm(), 1e-10) << phi.transpose();
  }
  // Tiny angles: relative accuracy must hold (no 1 - cos cancellation).
  for (double t : {1e-15, 1e-12, 1e-9, 1e-6, 1e-4}) {
    const Eigen::Vector3d phi = Eigen::Vector3d(0.6, -0.8, 0.0) * t;
    EXPECT_LT((LogSO3(ExpSO3(phi)) - phi).norm(), 1e-12 * t) << t;
    EXPECT_LT((RotVecFromQuat(QuatFromRotVec(phi)) - phi).norm(), 1e-14 * t) << t;
  }
  // Near pi: the axis must survive; at exactly pi either sign of the axis is right.
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, 2.0, -2.0).normalized();
  for (double eps : {1e-3, 1e-6, 1e-9}) {
    const Eigen::Vector3d phi = axis * (M_PI - eps);
    // Conditioning of log near pi: the rotation matrix entries carry ~1e-16 absolute
    // error and the angle is recovered to ~1e-8 where d(cos)/d(angle) ~ eps.
    EXPECT_LT((LogSO3(ExpSO3(phi)) - phi).norm(), 1e-7) << eps;
  }
  const Eigen::Vector3d at_pi = LogSO3(ExpSO3(Eigen::Vector3d(axis * M_PI)));
  EXPECT_NEAR(at_pi.norm(), M_PI, 1e-9);
  EXPECT_NEAR(std::abs(at_pi.normalized().dot(axis)), 1.0, 1e-9);
}

TEST(Rotation, QuaternionDcmRoundTripAndSignConvention) {
  std::mt19937 rng(3);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d phi = RandomRotVec(&rng, M_PI);
    const Eigen::Quaterniond q = QuatFromRotVec(phi);
    const Eigen::Quaterniond q2 = QuatFromDcm(DcmFromQuat(q));
    EXPECT_GE(q2.w(), 0.0);
    EXPECT_NEAR(std::abs(q.coeffs().dot(q2.coeffs())), 1.0, kTol);
  }
  // Hamilton convention: R(q) v == q v q*, and a +90 deg yaw maps body x (forward) to
  // NED y (east).
  const Eigen::Quaterniond q_yaw = QuatFromRotVec(Eigen::Vector3d(0, 0, M_PI / 2));
  EXPECT_LT((DcmFromQuat(q_yaw) * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), kTol);
}

TEST(Rotation, EulerZyxDefinitionAndRoundTrip) {
  // Pure yaw / pitch / roll each rotate about the expected axis with the expected sign:
  // positive pitch raises the nose (body x gets a negative down component).
  const Eigen::Vector3d nose = DcmFromEuler(0.0, 0.1, 0.0) * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(nose.z(), -std::sin(0.1), kTol);
  // Positive roll lowers the right wing (body y gets a positive down component).
  const Eigen::Vector3d wing = DcmFromEuler(0.1, 0.0, 0.0) * Eigen::Vector3d::UnitY();
  EXPECT_NEAR(wing.z(), std::sin(0.1), kTol);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> a(-M_PI + 1e-6, M_PI);
  std::uniform_real_distribution<double> p(-M_PI / 2 + 1e-3, M_PI / 2 - 1e-3);
  for (int i = 0; i < 200; ++i) {
    const double r = a(rng), pi = p(rng), y = a(rng);
    const Eigen::Vector3d e = EulerFromDcm(DcmFromEuler(r, pi, y));
    EXPECT_NEAR(WrapPi(e.x() - r), 0.0, 1e-10);
    EXPECT_NEAR(e.y(), pi, 1e-10);
    EXPECT_NEAR(WrapPi(e.z() - y), 0.0, 1e-10);
    const Eigen::Vector3d eq = EulerFromQuat(QuatFromEuler(r, pi, y));
    EXPECT_LT((DcmFromEuler(eq.x(), eq.y(), eq.z()) - DcmFromEuler(r, pi, y)).norm(), 1e-10);
  }
}

TEST(Rotation, EulerAtGimbalLockPutsEverythingInYaw) {
  for (double pitch : {M_PI / 2, -M_PI / 2}) {
    const Eigen::Matrix3d R = DcmFromEuler(0.3, pitch, 0.5);
    const Eigen::Vector3d e = EulerFromDcm(R);
    EXPECT_EQ(e.x(), 0.0);
    EXPECT_NEAR(e.y(), pitch, 1e-8);
    EXPECT_LT((DcmFromEuler(e.x(), e.y(), e.z()) - R).norm(), 1e-8);
  }
}

TEST(Rotation, AttitudeErrorConventionRoundTrips) {
  std::mt19937 rng(13);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Quaterniond q_est = QuatFromRotVec(RandomRotVec(&rng, M_PI));
    const Eigen::Vector3d phi_n = RandomRotVec(&rng, 0.5);
    const Eigen::Quaterniond q_true = ApplyAttitudeError(phi_n, q_est);
    EXPECT_LT((AttitudeError(q_true, q_est) - phi_n).norm(), kTol);
    // The error is a rotation of the navigation frame: R_true = Exp(phi) R_est.
    EXPECT_LT((DcmFromQuat(q_true) - ExpSO3(phi_n) * DcmFromQuat(q_est)).norm(), kTol);
  }
}

TEST(Rotation, JetDerivativesOfExpAndLogAreConsistent) {
  using J = ceres::Jet<double, 3>;
  // d Log(Exp(phi)) / d phi = I, checked at a moderate angle and at zero where the
  // series branch must carry the derivative.
  for (const Eigen::Vector3d& phi0 : {Eigen::Vector3d(0.3, -0.2, 0.9), Eigen::Vector3d::Zero().eval()}) {
    Vector3<J> phi;
    for (int i = 0; i < 3; ++i) phi[i] = J(phi0[i], i);
    const Vector3<J> back = LogSO3(ExpSO3(phi));
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(back[i].a, phi0[i], kTol);
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(back[i].v[j], i == j ? 1.0 : 0.0, 1e-10);
    }
  }
  // Euler angles with Jets: d roll / d roll = 1 away from gimbal lock.
  const J roll(0.2, 0), pitch(0.1, 1), yaw(-1.0, 2);
  const Vector3<J> e = EulerFromDcm(DcmFromEuler(roll, pitch, yaw));
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(e[i].v[j], i == j ? 1.0 : 0.0, 1e-10);
  }
}

TEST(Rotation, WrapPi) {
  EXPECT_NEAR(WrapPi(3 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapPi(-M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapPi(0.5), 0.5, 1e-15);
  EXPECT_NEAR(WrapPi(-7.0), -7.0 + 2 * M_PI, 1e-12);
}

TEST(Rotation, WrapPiKeepsAJetDerivative) {
  using J = ceres::Jet<double, 1>;
  const J w = WrapPi(J(7.0, 0));
  EXPECT_NEAR(w.a, 7.0 - 2 * M_PI, 1e-12);
  EXPECT_EQ(w.v[0], 1.0);
}

// Central differences of Exp/Log, step h: truncation O(h^2) ~ 1e-10 and rounding
// ~ 1e-16 / h ~ 1e-11 on unit-scale entries, so 1e-8 is a margin of 100.
constexpr double kStep = 1e-5;
constexpr double kJacobianTol = 1e-8;

/// Column i: (Log(Exp(phi)^T Exp(phi + h e_i)) - Log(Exp(phi)^T Exp(phi - h e_i))) / 2h.
Eigen::Matrix3d NumericRightJacobian(const Eigen::Vector3d& phi) {
  const Eigen::Matrix3d Rt = ExpSO3(phi).transpose();
  Eigen::Matrix3d J;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d d = kStep * Eigen::Vector3d::Unit(i);
    const Eigen::Matrix3d Rp = Rt * ExpSO3<double>(phi + d), Rm = Rt * ExpSO3<double>(phi - d);
    J.col(i) = (LogSO3(Rp) - LogSO3(Rm)) / (2.0 * kStep);
  }
  return J;
}

/// Column i: (Log(Exp(phi) Exp(h e_i)) - Log(Exp(phi) Exp(-h e_i))) / 2h.
Eigen::Matrix3d NumericRightJacobianInverse(const Eigen::Vector3d& phi) {
  const Eigen::Matrix3d R = ExpSO3(phi);
  Eigen::Matrix3d J;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d d = kStep * Eigen::Vector3d::Unit(i);
    const Eigen::Matrix3d Rp = R * ExpSO3<double>(d), Rm = R * ExpSO3<double>(-d);
    J.col(i) = (LogSO3(Rp) - LogSO3(Rm)) / (2.0 * kStep);
  }
  return J;
}

TEST(Rotation, RightJacobianAndItsInverseMatchCentralDifferences) {
  std::mt19937 rng(20261127);
  const Eigen::Vector3d random = RandomRotVec(&rng, 2.5);
  const Eigen::Vector3d tiny = 1e-8 * Eigen::Vector3d(0.6, -0.8, 0.0);
  for (const Eigen::Vector3d& phi : {Eigen::Vector3d::Zero().eval(), tiny, random}) {
    SCOPED_TRACE(phi.transpose());
    const Eigen::Matrix3d Jr = RightJacobianSO3(phi), Jr_inv = RightJacobianInverseSO3(phi);
    EXPECT_LT((Jr - NumericRightJacobian(phi)).cwiseAbs().maxCoeff(), kJacobianTol);
    EXPECT_LT((Jr_inv - NumericRightJacobianInverse(phi)).cwiseAbs().maxCoeff(), kJacobianTol);
    EXPECT_LT((Jr * Jr_inv - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), kTol);
  }
  // At zero both are the identity exactly; the two branches agree where they meet.
  EXPECT_EQ(RightJacobianSO3(Eigen::Vector3d::Zero().eval()), Eigen::Matrix3d::Identity());
  EXPECT_EQ(RightJacobianInverseSO3(Eigen::Vector3d::Zero().eval()), Eigen::Matrix3d::Identity());
  const Eigen::Vector3d below(0.99e-4, 0.0, 0.0), above(1.01e-4, 0.0, 0.0);
  EXPECT_LT((RightJacobianSO3(below) - RightJacobianSO3(above)).norm(), 1e-5);
  EXPECT_LT((RightJacobianInverseSO3(below) - RightJacobianInverseSO3(above)).norm(), 1e-5);
}

}  // namespace core_rotation_test
}  // namespace navtwin
