// The delayed-state transfer-alignment filter (problems/transfer_alignment/history_filter.h):
// its measurement Jacobian against central differences, and the filter on the preset.
#include "problems/transfer_alignment/history_filter.h"

#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "core/sim/scenario.h"
#include "problems/transfer_alignment/run.h"

namespace navtwin::transfer {
namespace history_filter_test {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using Jacobian = Eigen::Matrix<double, 6, kHistoryColumns>;

struct Point {
  HistoryBracket b;
  Eigen::Quaterniond M = Eigen::Quaterniond::Identity();
  MasterKinematics m;
  double tau_s = 0.3;
  Vector3d lever_b_m = Vector3d(1.5, -0.4, 0.2);
};

Vector6 ResidualAt(const Point& p) {
  Vector6 r;
  Jacobian H;
  HistoryMatchResidualAndJacobian(p.b, p.M.toRotationMatrix(), p.m, p.tau_s, p.lever_b_m, &r, &H);
  return r;
}

/// p moved by d in column c of the Jacobian's layout (e0, e1, mu, dtau).
Point Moved(Point p, int c, double d) {
  if (c < 6) {
    p.b.e0[c] += d;
  } else if (c < 12) {
    p.b.e1[c - 6] += d;
  } else if (c < 15) {
    p.M = ApplyAttitudeError<double>(Vector3d(d * Vector3d::Unit(c - 12)), p.M);
  } else {
    p.tau_s += d;
  }
  return p;
}

/// A bracket around s = tag - tau: nominal epochs 5 ms apart, error nodes 20 ms apart.
/// scale 0: identity attitudes, zero rates and errors; small: a tiny perturbation; 1: a
/// random point with manoeuvre-sized rates.
Point MakePoint(std::mt19937& rng, double scale) {
  std::normal_distribution<double> n(0.0, 1.0);
  const auto v3 = [&](double sd) -> Vector3d { return Vector3d(n(rng), n(rng), n(rng)) * (sd * scale); };
  Point p;
  p.m.tag_s = 100.0;
  const double s = p.m.tag_s - p.tau_s;
  const Vector3d omega = v3(0.8), accel = v3(20.0);
  p.b.n0.t_s = s - 0.002;
  p.b.n1.t_s = s + 0.003;
  p.b.n0.q_n_s = Eigen::Quaterniond(ExpSO3<double>(v3(1.0)));
  p.b.n1.q_n_s = Eigen::Quaterniond(p.b.n0.q_n_s.toRotationMatrix() * ExpSO3<double>(Vector3d(omega * 0.005)));
  p.b.n0.v_n_mps = Vector3d(200.0, -10.0, 3.0) * scale;
  p.b.n1.v_n_mps = p.b.n0.v_n_mps + accel * 0.005;
  p.b.c0_s = s - 0.012;
  p.b.c1_s = s + 0.008;
  p.b.e0 << v3(0.05), v3(0.01);
  p.b.e1 << v3(0.05), v3(0.01);
  p.M = Eigen::Quaterniond(ExpSO3<double>(v3(0.02)));
  // The master at the data time near the slave: attitude R_n_s(s) M^T plus a small error.
  p.m.q_n_b = Eigen::Quaterniond(p.b.n0.q_n_s.toRotationMatrix() * p.M.toRotationMatrix().transpose() *
                                 ExpSO3<double>(v3(0.003)));
  p.m.v_n_mps = p.b.n0.v_n_mps + v3(0.1);
  p.m.omega_nb_b_radps = omega;
  return p;
}

void ExpectJacobianMatchesCentralDifferences(const Point& p, const char* where) {
  Vector6 r;
  Jacobian H;
  HistoryMatchResidualAndJacobian(p.b, p.M.toRotationMatrix(), p.m, p.tau_s, p.lever_b_m, &r, &H);
  // Steps: 1e-6 in m/s and rad; 1e-7 s in tau, inside the nominal and error segments.
  for (int c = 0; c < kHistoryColumns; ++c) {
    const double h = c == 15 ? 1e-7 : 1e-6;
    const Vector6 numeric = (ResidualAt(Moved(p, c, h)) - ResidualAt(Moved(p, c, -h))) / (2.0 * h);
    // Central differences err by O(h^2 r''') ~ 1e-12 plus rounding 1e-16 / h ~ 1e-9
    // (tau: 1e-16 * 300 / 1e-7 ~ 3e-7 in the velocity rows' units).
    const double tol = c == 15 ? 1e-6 * std::max(1.0, numeric.norm()) : 1e-8;
    EXPECT_LT((H.col(c) - numeric).cwiseAbs().maxCoeff(), tol)
        << where << " column " << c << "\nanalytic " << H.col(c).transpose() << "\nnumeric  " << numeric.transpose();
  }
}

TEST(HistoryMatch, JacobianAtIdentityTinyPerturbationAndRandomPoint) {
  std::mt19937 rng(23);
  ExpectJacobianMatchesCentralDifferences(MakePoint(rng, 0.0), "identity");
  ExpectJacobianMatchesCentralDifferences(MakePoint(rng, 1e-6), "tiny perturbation");
  for (int i = 0; i < 5; ++i) ExpectJacobianMatchesCentralDifferences(MakePoint(rng, 1.0), "random point");
}

// At the truth (nominal = the slave's true motion, no errors, the master at the data time
// equal to the slave with the true mounting) the residual is zero.
TEST(HistoryMatch, ZeroAtTheTruth) {
  std::mt19937 rng(5);
  Point p = MakePoint(rng, 1.0);
  p.b.e0.setZero();
  p.b.e1.setZero();
  p.lever_b_m.setZero();
  const double s = p.m.tag_s - p.tau_s;
  const double a = (s - p.b.n0.t_s) / (p.b.n1.t_s - p.b.n0.t_s);
  const Eigen::Quaterniond q_s = p.b.n0.q_n_s.slerp(a, p.b.n1.q_n_s);
  p.m.q_n_b = q_s * p.M.conjugate();
  p.m.v_n_mps = p.b.n0.v_n_mps + a * (p.b.n1.v_n_mps - p.b.n0.v_n_mps);
  EXPECT_LT(ResidualAt(p).cwiseAbs().maxCoeff(), 1e-12);
}

}  // namespace history_filter_test
}  // namespace navtwin::transfer
