#include "solvers/eskf.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

namespace navtwin {
namespace {

// Regularised incomplete gamma functions of a > 0, x >= 0: P(a, x) = gamma(a, x) / Gamma(a)
// and Q = 1 - P. Series for x < a + 1 and Legendre's continued fraction (evaluated with
// the modified Lentz method) otherwise (Abramowitz & Stegun 6.5.29 and 6.5.31; each
// converges fast in its region, and computing the smaller of P, Q directly keeps the
// relative accuracy of tail probabilities).
struct GammaPQ {
  double p;
  double q;
};

GammaPQ RegularizedGamma(double a, double x) {
  if (x <= 0.0) return {0.0, 1.0};
  const double log_prefactor = a * std::log(x) - x - std::lgamma(a);  // x^a e^-x / Gamma(a)
  if (x < a + 1.0) {
    // P = x^a e^-x / Gamma(a + 1) * sum_n x^n / ((a+1)...(a+n))
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n < 10000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-17) break;
    }
    const double p = sum * std::exp(log_prefactor);
    return {p, 1.0 - p};
  }
  // Q = x^a e^-x / Gamma(a) * 1/(x + 1 - a - 1(1-a)/(x + 3 - a - 2(2-a)/(x + 5 - a - ...)))
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i < 10000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  const double q = std::exp(log_prefactor) * h;
  return {1.0 - q, q};
}

// Standard normal quantile, Abramowitz & Stegun 26.2.23 (|error| < 4.5e-4): only the
// starting point of the Newton iteration below.
double NormalQuantileApprox(double p) {
  const double pp = p < 0.5 ? p : 1.0 - p;
  const double t = std::sqrt(-2.0 * std::log(pp));
  const double z = t - (2.515517 + 0.802853 * t + 0.010328 * t * t) /
                           (1.0 + 1.432788 * t + 0.189269 * t * t + 0.001308 * t * t * t);
  return p < 0.5 ? -z : z;
}

void CheckSymmetricPsd(const Eigen::MatrixXd& P, const char* what) {
  if (P.rows() != P.cols() || P.rows() == 0) {
    throw std::invalid_argument(std::string(what) + ": covariance must be square and non-empty");
  }
  if (!P.allFinite()) throw std::invalid_argument(std::string(what) + ": covariance not finite");
  const double scale = P.cwiseAbs().maxCoeff();
  if ((P - P.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
    throw std::invalid_argument(std::string(what) + ": covariance not symmetric");
  }
  if ((P.diagonal().array() < 0.0).any()) {
    throw std::invalid_argument(std::string(what) + ": covariance has a negative variance");
  }
}

}  // namespace

double ChiSquareQuantile(double p, int dof) {
  if (!(p > 0.0 && p < 1.0)) {
    throw std::invalid_argument("ChiSquareQuantile: probability " + std::to_string(p) +
                                " not in (0, 1)");
  }
  if (dof < 1) {
    throw std::invalid_argument("ChiSquareQuantile: dof " + std::to_string(dof) + " < 1");
  }
  // X ~ chi2(k): P(X <= x) = P(k/2, x/2). Solve for y = x/2 in P(a, y) = p (or, in the
  // upper tail, Q(a, y) = 1 - p, which keeps the relative accuracy there).
  const double a = 0.5 * dof;
  const double k = dof;
  // Wilson-Hilferty: (X/k)^(1/3) ~ N(1 - 2/(9k), 2/(9k)).
  const double z = NormalQuantileApprox(p);
  double x = k * std::pow(std::max(1.0 - 2.0 / (9.0 * k) + z * std::sqrt(2.0 / (9.0 * k)), 0.05), 3);
  double y = 0.5 * x;
  const bool upper = p > 0.5;
  const double target = upper ? 1.0 - p : p;
  // Bracket for the safeguarded Newton iteration: f(y) = P(a, y) - p is increasing.
  double lo = 0.0;
  double hi = std::numeric_limits<double>::infinity();
  const double log_gamma_a = std::lgamma(a);
  for (int it = 0; it < 200; ++it) {
    const GammaPQ g = RegularizedGamma(a, y);
    const double f = upper ? target - g.q : g.p - target;  // both increasing in y
    if (f > 0.0) hi = y; else lo = y;
    // d/dy P(a, y) = y^(a-1) e^-y / Gamma(a)
    const double density = std::exp((a - 1.0) * std::log(y) - y - log_gamma_a);
    double y_new = y - f / density;
    if (!(y_new > lo && y_new < hi) || !std::isfinite(y_new)) {
      y_new = std::isfinite(hi) ? 0.5 * (lo + hi) : 2.0 * y;  // bisection / expansion
    }
    const double step = std::abs(y_new - y);
    y = y_new;
    if (step <= 1e-14 * y) break;
  }
  return 2.0 * y;
}

ErrorStateKalmanFilter::ErrorStateKalmanFilter(Eigen::MatrixXd P0) : P_(std::move(P0)) {
  CheckSymmetricPsd(P_, "ErrorStateKalmanFilter");
  P_ = 0.5 * (P_ + P_.transpose()).eval();
}

void ErrorStateKalmanFilter::Predict(const Eigen::MatrixXd& Phi, const Eigen::MatrixXd& Qd) {
  const int n = size();
  if (Phi.rows() != n || Phi.cols() != n || Qd.rows() != n || Qd.cols() != n) {
    throw std::invalid_argument("ErrorStateKalmanFilter::Predict: Phi and Qd must be " +
                                std::to_string(n) + " x " + std::to_string(n));
  }
  Eigen::MatrixXd P = Phi * P_ * Phi.transpose() + Qd;
  P_ = 0.5 * (P + P.transpose());
}

ErrorStateKalmanFilter::Update ErrorStateKalmanFilter::Correct(const Eigen::VectorXd& y,
                                                               const Eigen::MatrixXd& H,
                                                               double gate_probability) {
  const int n = size();
  const int m = static_cast<int>(y.size());
  if (m == 0 || H.rows() != m || H.cols() != n) {
    throw std::invalid_argument("ErrorStateKalmanFilter::Correct: H must be " + std::to_string(m) +
                                " x " + std::to_string(n) + " (dim y x state size), y non-empty");
  }
  if (!y.allFinite() || !H.allFinite()) {
    throw std::invalid_argument("ErrorStateKalmanFilter::Correct: y or H not finite");
  }
  Update u;
  u.dx = Eigen::VectorXd::Zero(n);
  const Eigen::MatrixXd PHt = P_ * H.transpose();
  Eigen::MatrixXd S = H * PHt;
  S.diagonal().array() += 1.0;  // R = I for a whitened measurement
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) {
    throw std::runtime_error("ErrorStateKalmanFilter::Correct: innovation covariance not positive definite");
  }
  u.nis = y.dot(llt.solve(y));
  // S = L L^T: log det S = 2 sum log L_ii.
  u.log_det_s = 2.0 * llt.matrixLLT().diagonal().array().log().sum();
  u.gate = gate_probability >= 1.0 ? std::numeric_limits<double>::infinity()
                                   : ChiSquareQuantile(gate_probability, m);
  if (!(u.nis <= u.gate)) {
    ++rejected_;
    return u;
  }
  // K = P H^T S^-1 = (S^-1 H P)^T (S and P symmetric).
  u.K = llt.solve(PHt.transpose()).transpose();
  const Eigen::MatrixXd& K = u.K;
  u.dx = K * y;
  Eigen::MatrixXd IKH = -K * H;
  IKH.diagonal().array() += 1.0;
  Eigen::MatrixXd P = IKH * P_ * IKH.transpose() + K * K.transpose();
  P_ = 0.5 * (P + P.transpose());
  u.accepted = true;
  ++accepted_;
  return u;
}

void ErrorStateKalmanFilter::SetP(const Eigen::MatrixXd& P) {
  if (P.rows() != size() || P.cols() != size()) {
    throw std::invalid_argument("ErrorStateKalmanFilter::SetP: wrong size");
  }
  CheckSymmetricPsd(P, "ErrorStateKalmanFilter::SetP");
  P_ = 0.5 * (P + P.transpose());
}

}  // namespace navtwin
