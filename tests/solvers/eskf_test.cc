#include "solvers/eskf.h"
#include "core/units.h"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <Eigen/Dense>
#include <gtest/gtest.h>

namespace navtwin {
namespace solvers_eskf_test {

// Closed-form chi-square CDFs (Abramowitz & Stegun 26.4.4 for odd, 26.4.5 for even
// degrees of freedom), independent of the incomplete-gamma code under test. Returned as
// the upper tail Q = 1 - P so that p = 0.9999 keeps its relative accuracy.
double ChiSquareUpperTail(double x, int dof) {
  switch (dof) {
    case 1:
      return std::erfc(std::sqrt(0.5 * x));
    case 2:
      return std::exp(-0.5 * x);
    case 3:
      return std::erfc(std::sqrt(0.5 * x)) + std::sqrt(2.0 * x / kPi) * std::exp(-0.5 * x);
    case 6:
      return std::exp(-0.5 * x) * (1.0 + 0.5 * x + x * x / 8.0);
  }
  ADD_FAILURE() << "no closed form for dof " << dof;
  return 0.0;
}

TEST(ChiSquareQuantile, MatchesTabulatedCriticalValues) {
  // NIST/SEMATECH e-Handbook of Statistical Methods, sec. 1.3.6.7.4 "Critical Values of
  // the Chi-Square Distribution" (upper-tail probabilities 0.05 and 0.01, printed to
  // 3 decimals, hence the tolerance 5e-4).
  struct Row { int dof; double p95, p99; };
  const Row table[] = {{1, 3.841, 6.635}, {2, 5.991, 9.210}, {3, 7.815, 11.345}, {6, 12.592, 16.812}};
  for (const Row& r : table) {
    EXPECT_NEAR(ChiSquareQuantile(0.95, r.dof), r.p95, 5e-4) << r.dof;
    EXPECT_NEAR(ChiSquareQuantile(0.99, r.dof), r.p99, 5e-4) << r.dof;
  }
  // p = 0.9999: quantiles for dof 1 (= z_{0.99995}^2 with z = 3.890592, A&S Table 26.1 /
  // any normal table) and 2 (exactly -2 ln 1e-4), to the digits given.
  EXPECT_NEAR(ChiSquareQuantile(0.9999, 1), 3.890592 * 3.890592, 1e-5);
  EXPECT_NEAR(ChiSquareQuantile(0.9999, 2), -2.0 * std::log(1e-4), 1e-10);
}

TEST(ChiSquareQuantile, InvertsClosedFormDistributions) {
  for (int dof : {1, 2, 3, 6}) {
    for (double p : {0.01, 0.5, 0.95, 0.99, 0.9999, 1.0 - 1e-9}) {
      const double x = ChiSquareQuantile(p, dof);
      // Relative accuracy of the upper tail: the Newton iteration stops at 1e-14 in x;
      // the tail's relative sensitivity (x/2 at most ~25) and the closed forms' own
      // rounding keep it below 1e-10.
      EXPECT_NEAR(ChiSquareUpperTail(x, dof) / (1.0 - p), 1.0, 1e-10) << dof << " " << p;
    }
  }
  EXPECT_THROW(ChiSquareQuantile(1.0, 3), std::invalid_argument);
  EXPECT_THROW(ChiSquareQuantile(0.0, 3), std::invalid_argument);
  EXPECT_THROW(ChiSquareQuantile(0.5, 0), std::invalid_argument);
}

TEST(ChiSquareQuantile, LargeDegreesOfFreedom) {
  // Mean dof, median ~ dof (1 - 2/(9 dof))^3 (Wilson-Hilferty, relative error ~1e-4 at
  // dof 100); also monotone in p.
  const double median = ChiSquareQuantile(0.5, 100);
  EXPECT_NEAR(median, 100.0 * std::pow(1.0 - 2.0 / 900.0, 3), 0.01);
  EXPECT_LT(ChiSquareQuantile(0.9, 100), ChiSquareQuantile(0.99, 100));
}

Eigen::MatrixXd RandomSpd(int n, std::mt19937* rng) {
  std::normal_distribution<double> N01;
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = N01(*rng);
  return A * A.transpose() + 0.5 * Eigen::MatrixXd::Identity(n, n);
}

// Linear Gaussian toy problem z = H x + v, v ~ N(0, R) with a full R: the whitened
// Joseph-form update (y = L^-1 (z - H x), H_w = L^-1 H, R = LL^T) equals the textbook
// update K = P H^T (H P H^T + R)^-1, x+ = x + K (z - H x), P+ = (I - K H) P.
TEST(ErrorStateKalmanFilter, JosephUpdateEqualsTextbookUpdate) {
  std::mt19937 rng(42);
  std::normal_distribution<double> N01;
  const int n = 5, m = 3;
  const Eigen::MatrixXd P = RandomSpd(n, &rng);
  const Eigen::MatrixXd R = RandomSpd(m, &rng);
  Eigen::MatrixXd H(m, n);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < n; ++j) H(i, j) = N01(rng);
  Eigen::VectorXd innovation(m);  // z - H x_est
  for (int i = 0; i < m; ++i) innovation(i) = N01(rng);

  const Eigen::MatrixXd K_ref = P * H.transpose() * (H * P * H.transpose() + R).inverse();
  const Eigen::VectorXd dx_ref = K_ref * innovation;
  const Eigen::MatrixXd P_ref = (Eigen::MatrixXd::Identity(n, n) - K_ref * H) * P;

  const Eigen::MatrixXd L = R.llt().matrixL();
  ErrorStateKalmanFilter kf(P);
  const auto u = kf.Correct(L.triangularView<Eigen::Lower>().solve(innovation),
                            L.triangularView<Eigen::Lower>().solve(H), 1.0);
  ASSERT_TRUE(u.accepted);
  EXPECT_TRUE(std::isinf(u.gate));
  // Entries are O(1..10); both paths round at ~1e-15 relative with condition numbers ~1e2.
  EXPECT_LT((u.dx - dx_ref).cwiseAbs().maxCoeff(), 1e-12);
  // The gain of the whitened measurement: P H^T L^-T (L^-1 (H P H^T + R) L^-T)^-1 = K_ref L.
  ASSERT_EQ(u.K.rows(), n);
  ASSERT_EQ(u.K.cols(), m);
  EXPECT_LT((u.K - K_ref * L).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((kf.P() - P_ref).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ((kf.P() - kf.P().transpose()).cwiseAbs().maxCoeff(), 0.0);
  // NIS = innovation^T (H P H^T + R)^-1 innovation.
  EXPECT_NEAR(u.nis, innovation.dot((H * P * H.transpose() + R).inverse() * innovation), 1e-12);
  // Whitened S = L^-1 (H P H^T + R) L^-T: log det S = log det(H P H^T + R) - log det R.
  EXPECT_NEAR(u.log_det_s,
              std::log((H * P * H.transpose() + R).determinant()) - std::log(R.determinant()), 1e-10);
  EXPECT_EQ(kf.accepted_count(), 1);
}

TEST(ErrorStateKalmanFilter, GateRejectsTenSigmaOutlierAndCountsIt) {
  ErrorStateKalmanFilter kf(Eigen::MatrixXd::Identity(3, 3));
  const Eigen::MatrixXd H = Eigen::MatrixXd::Identity(3, 3);
  // S = H P H^T + I = 2 I: a 10-sigma innovation along x has NIS = 100 > 21.1 (chi2 3 dof, 0.9999).
  Eigen::VectorXd y = Eigen::Vector3d(10.0 * std::sqrt(2.0), 0.0, 0.0);
  const auto bad = kf.Correct(y, H, 0.9999);
  EXPECT_FALSE(bad.accepted);
  EXPECT_NEAR(bad.nis, 100.0, 1e-12);
  EXPECT_NEAR(bad.log_det_s, 3.0 * std::log(2.0), 1e-12);  // S = 2 I
  EXPECT_NEAR(bad.gate, ChiSquareQuantile(0.9999, 3), 1e-12);
  EXPECT_EQ(bad.dx.size(), 3);
  EXPECT_EQ(bad.dx.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(bad.K.size(), 0);  // no gain: nothing was applied
  EXPECT_EQ(kf.P(), Eigen::MatrixXd::Identity(3, 3));  // untouched
  EXPECT_EQ(kf.rejected_count(), 1);
  // A 1-sigma innovation passes; the same outlier without a gate is accepted.
  const auto good = kf.Correct(Eigen::Vector3d(1.0, -1.0, 0.5), H, 0.9999);
  EXPECT_TRUE(good.accepted);
  EXPECT_EQ(kf.rejected_count(), 1);
  EXPECT_TRUE(kf.Correct(y, H, 1.0).accepted);
  EXPECT_EQ(kf.accepted_count(), 2);
}

// Random constant x observed by z_k = x + v_k (R = r): closed form P_k = 1 / (1/P0 + k/r)
// and x_k = P_k (x0/P0 + sum z / r) (the weighted mean). Run as an error-state filter
// with feedback: nominal += dx after every update.
TEST(ErrorStateKalmanFilter, RandomConstantClosedForm) {
  std::mt19937 rng(7);
  std::normal_distribution<double> N01;
  const double P0 = 4.0, r = 0.25, x_true = 1.7, x0 = 0.0;
  ErrorStateKalmanFilter kf(Eigen::MatrixXd::Constant(1, 1, P0));
  double x_est = x0, sum_z = 0.0;
  const Eigen::MatrixXd H = Eigen::MatrixXd::Constant(1, 1, 1.0 / std::sqrt(r));
  for (int k = 1; k <= 50; ++k) {
    kf.Predict(Eigen::MatrixXd::Identity(1, 1), Eigen::MatrixXd::Zero(1, 1));
    const double z = x_true + std::sqrt(r) * N01(rng);
    sum_z += z;
    const auto u = kf.Correct(Eigen::VectorXd::Constant(1, (z - x_est) / std::sqrt(r)), H, 1.0);
    x_est += u.dx(0);
    const double Pk = 1.0 / (1.0 / P0 + k / r);
    EXPECT_NEAR(kf.P()(0, 0), Pk, 1e-14);
    EXPECT_NEAR(x_est, Pk * (x0 / P0 + sum_z / r), 1e-13);
  }
}

// Scalar random walk x_{k+1} = x_k + w (Q = q), z = x + v (R = r): the prior variance
// converges to the algebraic Riccati solution P- = (q + sqrt(q^2 + 4 q r)) / 2 and the
// posterior to P- r / (P- + r).
TEST(ErrorStateKalmanFilter, RandomWalkSteadyState) {
  const double q = 0.01, r = 0.5;
  ErrorStateKalmanFilter kf(Eigen::MatrixXd::Constant(1, 1, 10.0));
  const Eigen::MatrixXd H = Eigen::MatrixXd::Constant(1, 1, 1.0 / std::sqrt(r));
  double P_prior = 0.0;
  for (int k = 0; k < 2000; ++k) {  // convergence factor (1 - K)^2 ~ 0.98 per step
    kf.Predict(Eigen::MatrixXd::Identity(1, 1), Eigen::MatrixXd::Constant(1, 1, q));
    P_prior = kf.P()(0, 0);
    kf.Correct(Eigen::VectorXd::Zero(1), H, 1.0);
  }
  const double P_ss = 0.5 * (q + std::sqrt(q * q + 4.0 * q * r));
  EXPECT_NEAR(P_prior, P_ss, 1e-14);
  EXPECT_NEAR(kf.P()(0, 0), P_ss * r / (P_ss + r), 1e-14);
}

TEST(ErrorStateKalmanFilter, RejectsBadInput) {
  EXPECT_THROW(ErrorStateKalmanFilter(Eigen::MatrixXd::Zero(2, 3)), std::invalid_argument);
  Eigen::MatrixXd asym = Eigen::MatrixXd::Identity(2, 2);
  asym(0, 1) = 0.5;
  EXPECT_THROW(ErrorStateKalmanFilter{asym}, std::invalid_argument);
  ErrorStateKalmanFilter kf(Eigen::MatrixXd::Identity(2, 2));
  EXPECT_THROW(kf.Predict(Eigen::MatrixXd::Identity(3, 3), Eigen::MatrixXd::Zero(3, 3)),
               std::invalid_argument);
  EXPECT_THROW(kf.Correct(Eigen::VectorXd::Zero(1), Eigen::MatrixXd::Zero(1, 3), 1.0),
               std::invalid_argument);
  Eigen::VectorXd nan_y = Eigen::VectorXd::Constant(1, std::numeric_limits<double>::quiet_NaN());
  EXPECT_THROW(kf.Correct(nan_y, Eigen::MatrixXd::Zero(1, 2), 1.0), std::invalid_argument);
  EXPECT_EQ(kf.size(), 2);
}

}  // namespace solvers_eskf_test
}  // namespace navtwin
