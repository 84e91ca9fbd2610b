#include "solvers/rts.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "solvers/eskf.h"

namespace navtwin {
namespace solvers_rts_test {

// 2-D constant-velocity model, state (pE, pN, vE, vN), white-acceleration PSD q:
//   Phi = [I dt I; 0 I],  Q = q [dt^3/3 I, dt^2/2 I; dt^2/2 I, dt I].
Eigen::MatrixXd CvPhi(double dt) {
  Eigen::MatrixXd Phi = Eigen::MatrixXd::Identity(4, 4);
  Phi.block(0, 2, 2, 2) = dt * Eigen::MatrixXd::Identity(2, 2);
  return Phi;
}

Eigen::MatrixXd CvQ(double dt, double q) {
  Eigen::MatrixXd Q(4, 4);
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(2, 2);
  Q << q * dt * dt * dt / 3 * I, q * dt * dt / 2 * I, q * dt * dt / 2 * I, q * dt * I;
  return Q;
}

struct Measurement {
  Eigen::MatrixXd H;  // rows of the linear measurement
  Eigen::VectorXd z;
  double sigma;
};

struct Problem {
  Eigen::VectorXd m0;
  Eigen::MatrixXd P0;
  std::vector<Eigen::MatrixXd> Phi, Q;           // [k] from knot k-1 to k (k >= 1)
  std::vector<std::vector<Measurement>> meas;    // per knot, possibly none or several
};

// Simulated with a fixed seed: irregular knot spacing; knots with no measurement, with one
// position fix, with two fixes (summed feedback), and with a velocity-only measurement.
Problem MakeProblem() {
  std::mt19937 rng(2024);
  std::normal_distribution<double> N01;
  std::uniform_real_distribution<double> U(0.2, 1.5);
  Problem pr;
  const int N = 40;
  const double q = 0.3;
  pr.m0 = Eigen::Vector4d(10.0, -5.0, 2.0, 1.0);
  pr.P0 = Eigen::Vector4d(25.0, 25.0, 4.0, 4.0).asDiagonal();
  Eigen::VectorXd x = pr.m0;
  for (int i = 0; i < 4; ++i) x(i) += std::sqrt(pr.P0(i, i)) * N01(rng);
  Eigen::MatrixXd Hpos = Eigen::MatrixXd::Zero(2, 4), Hvel = Eigen::MatrixXd::Zero(1, 4);
  Hpos(0, 0) = Hpos(1, 1) = 1.0;
  Hvel(0, 2) = 0.6;
  Hvel(0, 3) = 0.8;
  pr.Phi.resize(N);
  pr.Q.resize(N);
  pr.meas.resize(N);
  for (int k = 0; k < N; ++k) {
    if (k > 0) {
      const double dt = U(rng);
      pr.Phi[k] = CvPhi(dt);
      pr.Q[k] = CvQ(dt, q);
      const Eigen::MatrixXd Lq = pr.Q[k].llt().matrixL();
      Eigen::Vector4d w(N01(rng), N01(rng), N01(rng), N01(rng));
      x = pr.Phi[k] * x + Lq * w;
    }
    auto add = [&](const Eigen::MatrixXd& H, double sigma) {
      Eigen::VectorXd z = H * x;
      for (int i = 0; i < z.size(); ++i) z(i) += sigma * N01(rng);
      pr.meas[k].push_back({H, z, sigma});
    };
    if (k % 4 == 1 || k % 4 == 3) add(Hpos, 2.0);             // one fix
    if (k % 4 == 3) add(Hpos, 3.0);                            // a second fix
    if (k % 5 == 2) add(Hvel, 0.2);                            // velocity along a direction
    // k % 4 == 0 or 2 (and no velocity): no update at all.
  }
  return pr;
}

// The error-state filter with feedback on the linear problem: the nominal x_hat is
// propagated with Phi, each update's dx is added into it, and a knot is stored per step.
void RunFilter(const Problem& pr, std::vector<RtsKnot>* knots, std::vector<Eigen::VectorXd>* x_post) {
  ErrorStateKalmanFilter kf(pr.P0);
  Eigen::VectorXd x_hat = pr.m0;
  const int N = static_cast<int>(pr.meas.size());
  for (int k = 0; k < N; ++k) {
    RtsKnot knot;
    if (k > 0) {
      knot.Phi = pr.Phi[k];
      x_hat = pr.Phi[k] * x_hat;
      kf.Predict(pr.Phi[k], pr.Q[k]);
    }
    knot.P_prior = kf.P();
    knot.dx_fed_back = Eigen::VectorXd::Zero(4);
    for (const Measurement& m : pr.meas[k]) {
      // Whitened residual r = (H x_hat - z) / sigma; innovation y = -r; H_w = H / sigma.
      const Eigen::VectorXd y = -(m.H * x_hat - m.z) / m.sigma;
      const auto u = kf.Correct(y, m.H / m.sigma, 1.0);
      ASSERT_TRUE(u.accepted);
      x_hat += u.dx;
      knot.dx_fed_back += u.dx;
    }
    if (pr.meas[k].empty() && k % 8 == 0) knot.dx_fed_back.resize(0);  // empty = zero
    knot.P_post = kf.P();
    knots->push_back(knot);
    x_post->push_back(x_hat);
  }
}

// Independent batch solution: minimise the sum of squared whitened residuals (prior on
// x_0, process residuals Lq^-1 (x_k - Phi x_{k-1}), measurements (H x_k - z)/sigma) over
// all states at once by the normal equations; covariance = (J^T J)^-1.
void SolveBatch(const Problem& pr, Eigen::VectorXd* X, Eigen::MatrixXd* C) {
  const int N = static_cast<int>(pr.meas.size());
  const int n = 4 * N;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);  // J^T J
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);     // J^T (whitened targets)
  const Eigen::MatrixXd P0inv = pr.P0.inverse();
  A.block(0, 0, 4, 4) += P0inv;
  b.segment(0, 4) += P0inv * pr.m0;
  for (int k = 1; k < N; ++k) {
    const Eigen::MatrixXd Qinv = pr.Q[k].inverse();
    Eigen::MatrixXd J(4, 8);  // residual x_k - Phi x_{k-1} in (x_{k-1}, x_k)
    J << -pr.Phi[k], Eigen::MatrixXd::Identity(4, 4);
    A.block(4 * (k - 1), 4 * (k - 1), 8, 8) += J.transpose() * Qinv * J;
  }
  for (int k = 0; k < N; ++k) {
    for (const Measurement& m : pr.meas[k]) {
      A.block(4 * k, 4 * k, 4, 4) += m.H.transpose() * m.H / (m.sigma * m.sigma);
      b.segment(4 * k, 4) += m.H.transpose() * m.z / (m.sigma * m.sigma);
    }
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(A);
  ASSERT_EQ(llt.info(), Eigen::Success);
  *X = llt.solve(b);
  *C = llt.solve(Eigen::MatrixXd::Identity(n, n));
}

TEST(RunRts, EqualsBatchLeastSquaresOnLinearGaussianProblem) {
  const Problem pr = MakeProblem();
  std::vector<RtsKnot> knots;
  std::vector<Eigen::VectorXd> x_post;
  RunFilter(pr, &knots, &x_post);
  const RtsResult rts = RunRts(knots);
  Eigen::VectorXd X;
  Eigen::MatrixXd C;
  SolveBatch(pr, &X, &C);
  ASSERT_EQ(rts.dx.size(), knots.size());
  ASSERT_EQ(rts.P.size(), knots.size());
  // Values are O(1..100) m and m/s, variances O(0.01..10); both solutions are exact
  // algebra on a well-conditioned problem (condition number of J^T J ~ 1e5), so they
  // agree to ~1e-12; 1e-9 as required.
  for (size_t k = 0; k < knots.size(); ++k) {
    const Eigen::VectorXd smoothed = x_post[k] + rts.dx[k];
    EXPECT_LT((smoothed - X.segment(4 * k, 4)).cwiseAbs().maxCoeff(), 1e-9) << "knot " << k;
    EXPECT_LT((rts.P[k] - C.block(4 * k, 4 * k, 4, 4)).cwiseAbs().maxCoeff(), 1e-9) << "knot " << k;
  }
  // The last knot: filter = smoother.
  EXPECT_EQ(rts.dx.back().cwiseAbs().maxCoeff(), 0.0);
  // Smoothing reduces every variance (strictly at the knots that are not the last).
  for (size_t k = 0; k + 1 < knots.size(); ++k) {
    EXPECT_TRUE((rts.P[k].diagonal().array() < knots[k].P_post.diagonal().array()).all()) << k;
  }
}

// A state with zero variance throughout (e.g. a bias the configuration fixes) makes
// P_prior singular; the smoother must still give the result of the reduced problem.
TEST(RunRts, SingularPriorOnUnexcitedState) {
  const Problem pr = MakeProblem();
  std::vector<RtsKnot> knots;
  std::vector<Eigen::VectorXd> x_post;
  RunFilter(pr, &knots, &x_post);
  std::vector<RtsKnot> padded = knots;  // append a fifth state, variance 0, Phi = 1
  for (RtsKnot& k : padded) {
    auto pad = [](const Eigen::MatrixXd& A, double corner) {
      Eigen::MatrixXd B = Eigen::MatrixXd::Zero(A.rows() + 1, A.cols() + 1);
      B.topLeftCorner(A.rows(), A.cols()) = A;
      B(A.rows(), A.cols()) = corner;
      return B;
    };
    if (k.Phi.size() > 0) k.Phi = pad(k.Phi, 1.0);
    k.P_prior = pad(k.P_prior, 0.0);
    k.P_post = pad(k.P_post, 0.0);
    if (k.dx_fed_back.size() > 0) {
      k.dx_fed_back.conservativeResize(5);
      k.dx_fed_back(4) = 0.0;
    }
  }
  const RtsResult full = RunRts(padded), reduced = RunRts(knots);
  for (size_t k = 0; k < knots.size(); ++k) {
    ASSERT_TRUE(full.dx[k].allFinite() && full.P[k].allFinite()) << k;
    // Eigen's LDLT treats the zero pivot as a pseudo-inverse: the other states are
    // unaffected up to rounding.
    EXPECT_LT((full.dx[k].head(4) - reduced.dx[k]).cwiseAbs().maxCoeff(), 1e-9) << k;
    EXPECT_LT((full.P[k].topLeftCorner(4, 4) - reduced.P[k]).cwiseAbs().maxCoeff(), 1e-9) << k;
    EXPECT_EQ(full.dx[k](4), 0.0);
    EXPECT_EQ(full.P[k](4, 4), 0.0);
  }
}

TEST(RunRts, EmptyAndInconsistentInput) {
  EXPECT_TRUE(RunRts({}).dx.empty());
  RtsKnot a{Eigen::MatrixXd(), Eigen::MatrixXd::Identity(2, 2), Eigen::MatrixXd::Identity(2, 2),
            Eigen::VectorXd()};
  RtsKnot b{Eigen::MatrixXd::Identity(3, 3), Eigen::MatrixXd::Identity(2, 2),
            Eigen::MatrixXd::Identity(2, 2), Eigen::VectorXd()};
  EXPECT_THROW(RunRts({a, b}), std::invalid_argument);
  const RtsResult single = RunRts({a});
  ASSERT_EQ(single.dx.size(), 1u);
  EXPECT_EQ(single.P[0], a.P_post);
}

}  // namespace solvers_rts_test
}  // namespace navtwin
