// Error-state (indirect) Kalman filter engine, problem-agnostic: covariance propagation
// with a given transition and process noise, whitened measurement updates in Joseph form
// with chi-square innovation gating. The nominal state and the feedback of the estimated
// error are the caller's (e.g. problems/gnss_ins/filter.h); after each accepted update the
// caller adds dx into its nominal state, so the error-state mean is zero between updates
// and only the covariance is kept here.
//
// Measurement convention (common to filter and batch, DESIGN.md "one model, two
// estimators"): a whitened residual r = (h(x) - z) / sigma of the nominal state has the
// tangent-space Jacobian H = dr/d(dx); for x_true = x_est (+) dx, 0 ~ r + H dx + v with
// v ~ N(0, I), so the innovation is y = -r = H dx + v and R = I.
#pragma once

#include <Eigen/Core>

namespace navtwin {

/// Chi-square quantile: the x with P(X <= x) = p for dof degrees of freedom (p in (0,1)),
/// accurate to ~1e-10 relative. Throws std::invalid_argument for p outside (0, 1) or
/// dof < 1.
double ChiSquareQuantile(double p, int dof);

class ErrorStateKalmanFilter {
 public:
  /// P0: n x n, symmetric positive semi-definite (checked: square, finite, symmetric to
  /// 1e-9 relative, non-negative diagonal; throws std::invalid_argument otherwise).
  explicit ErrorStateKalmanFilter(Eigen::MatrixXd P0);

  int size() const { return static_cast<int>(P_.rows()); }

  /// P = Phi P Phi^T + Qd (symmetrised). Throws std::invalid_argument on a size mismatch.
  void Predict(const Eigen::MatrixXd& Phi, const Eigen::MatrixXd& Qd);

  struct Update {
    bool accepted = false;
    double nis = 0.0;   ///< normalised innovation squared y^T S^-1 y, S = H P H^T + I
    double log_det_s = 0.0;  ///< log det S (with nis: -2 log N(y; 0, S) = nis + log det S + m log 2 pi)
    double gate = 0.0;  ///< the chi-square threshold used (inf when not gating)
    Eigen::VectorXd dx; ///< the error-state estimate K y (zero when rejected)
    Eigen::MatrixXd K;  ///< the gain P H^T S^-1, state size x dim y (empty when rejected)
  };

  /// Whitened measurement y = H dx + v, v ~ N(0, I) (y = -r of a whitened residual r).
  /// Gate: rejected (P unchanged) when NIS > ChiSquareQuantile(gate_probability, dim y);
  /// no gate when gate_probability >= 1. Otherwise K = P H^T S^-1, dx = K y and the
  /// Joseph-form update P = (I - K H) P (I - K H)^T + K K^T, symmetrised. The caller feeds
  /// dx back into its nominal state (the error state is then zero again).
  /// Throws std::invalid_argument on size mismatch or non-finite y / H, std::runtime_error
  /// when S is not positive definite.
  Update Correct(const Eigen::VectorXd& y, const Eigen::MatrixXd& H, double gate_probability);

  const Eigen::MatrixXd& P() const { return P_; }
  /// Replaces the covariance (same size; symmetrised).
  void SetP(const Eigen::MatrixXd& P);

  /// Number of updates rejected by the gate so far.
  int rejected_count() const { return rejected_; }
  /// Number of updates accepted so far.
  int accepted_count() const { return accepted_; }

 private:
  Eigen::MatrixXd P_;
  int rejected_ = 0;
  int accepted_ = 0;
};

}  // namespace navtwin
