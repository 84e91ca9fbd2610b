#include "solvers/rts.h"

#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

namespace navtwin {

RtsResult RunRts(const std::vector<RtsKnot>& knots) {
  RtsResult result;
  const int N = static_cast<int>(knots.size());
  if (N == 0) return result;
  const int n = static_cast<int>(knots[0].P_post.rows());
  for (int k = 0; k < N; ++k) {
    const RtsKnot& kn = knots[k];
    const bool ok = kn.P_post.rows() == n && kn.P_post.cols() == n && kn.P_prior.rows() == n &&
                    kn.P_prior.cols() == n &&
                    (kn.dx_fed_back.size() == 0 || kn.dx_fed_back.size() == n) &&
                    (k == 0 || (kn.Phi.rows() == n && kn.Phi.cols() == n));
    if (!ok) {
      throw std::invalid_argument("RunRts: knot " + std::to_string(k) +
                                  " has inconsistent sizes (state size " + std::to_string(n) + ")");
    }
  }
  result.dx.assign(N, Eigen::VectorXd::Zero(n));
  result.P.resize(N);
  result.P[N - 1] = knots[N - 1].P_post;
  for (int k = N - 2; k >= 0; --k) {
    const RtsKnot& next = knots[k + 1];
    // A = P_post_k Phi^T P_prior_{k+1}^-1 = (P_prior_{k+1}^-1 Phi P_post_k)^T
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(next.P_prior);
    if (ldlt.info() != Eigen::Success) {
      throw std::runtime_error("RunRts: prior covariance at knot " + std::to_string(k + 1) +
                               " cannot be factorised");
    }
    const Eigen::MatrixXd A = ldlt.solve(next.Phi * knots[k].P_post).transpose();
    Eigen::VectorXd target = result.dx[k + 1];
    if (next.dx_fed_back.size() == n) target += next.dx_fed_back;
    result.dx[k] = A * target;
    Eigen::MatrixXd P = knots[k].P_post + A * (result.P[k + 1] - next.P_prior) * A.transpose();
    result.P[k] = 0.5 * (P + P.transpose());
  }
  return result;
}

}  // namespace navtwin
