// The master stream's derivatives by finite differences of the records (master.h;
// docs/transfer-alignment.md, "Derivatives of the master stream").
//
// Attitude: the rate of the matrix R_n_b over an interval is the rotation vector of the
// relative rotation, R_j = R_i Exp(omega dt) for a constant body rate omega = omega_nb^b
// (the rate of R_n_b itself, transport rate included: exactly the quantity the delay
// compensation R_n_b(t) = R_n_b(t - tau) Exp(theta) of problems/transfer_alignment/delay_model.h carries forward).
//   kCausal   omega_k     = Log(R_{k-1}^T R_k) / (t_k - t_{k-1})          (value at the
//                            interval midpoint: lag (t_k - t_{k-1}) / 2)
//             omega_dot_k = (omega_k - omega_{k-1}) / ((t_k - t_{k-2}) / 2) (the two
//                            midpoints are (t_k - t_{k-2}) / 2 apart; lag one interval)
//   kCentral  omega_k     = Log(R_{k-1}^T R_{k+1}) / (t_{k+1} - t_{k-1})
//             omega_dot_k = (omega_{k+1} - omega_{k-1}) / (t_{k+1} - t_{k-1})
// Velocity likewise with v_j - v_i in place of Log(R_i^T R_j): a = dv_n/dt, a_dot = da/dt.
// Ends: where a stencil would leave the records, the nearest value that exists is used
// (kCausal records 0, 1 take the first rate / rate-of-rate available, i.e. look at most
// two records ahead; kCentral's first and last records use the one-sided interval).
#include "problems/transfer_alignment/master.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include <Eigen/Cholesky>

#include "core/io/input_error.h"
#include "core/rotation.h"

namespace navtwin::transfer {
namespace {

[[noreturn]] void Reject(const std::string& path, std::size_t k, const std::string& field,
                         const std::string& reason) {
  throw InputError(path, 0, "record " + std::to_string(k + 1) + ": " + field, reason);
}

void Validate(const std::vector<NavState>& records, const std::string& path) {
  if (records.size() < 3) {
    throw InputError(path, 0, "records",
                     "the master stream needs at least 3 records to estimate rates and their rates (it has " +
                         std::to_string(records.size()) + ")");
  }
  for (std::size_t k = 0; k < records.size(); ++k) {
    const NavState& r = records[k];
    if (!std::isfinite(r.t_s)) Reject(path, k, "t_s", "time tag is not finite");
    if (!std::isfinite(r.lat_rad) || !std::isfinite(r.lon_rad) || !std::isfinite(r.h_m)) {
      Reject(path, k, "position", "not finite");
    }
    if (!r.v_n_mps.allFinite()) Reject(path, k, "v_n_mps", "velocity is not finite");
    const double qn = r.q_n_b.coeffs().norm();
    if (!r.q_n_b.coeffs().allFinite() || !(qn > 0.5 && qn < 2.0)) {
      Reject(path, k, "attitude", "quaternion is not finite or not near unit length");
    }
    if (k > 0 && !(r.t_s > records[k - 1].t_s)) {
      Reject(path, k, "t_s",
             "time tags must increase strictly (" + std::to_string(r.t_s) + " s after " +
                 std::to_string(records[k - 1].t_s) + " s)");
    }
  }
}

// Rotation vector from R_i to R_j in body axes of i: R_j = R_i Exp(result).
Eigen::Vector3d RelativeRotation(const NavState& i, const NavState& j) {
  const Eigen::Matrix3d R_i = i.q_n_b.normalized().toRotationMatrix();
  const Eigen::Matrix3d R_j = j.q_n_b.normalized().toRotationMatrix();
  return LogSO3<double>(Eigen::Matrix3d(R_i.transpose() * R_j));
}

}  // namespace

// Least-squares weights of the quadratic x(s) = c0 + c1 s + c2 s^2 / 2 over the times
// s_j = t_j - t_k (j = 0 the newest): rows of (A^T A)^-1 A^T for c1 and c2, so that
// c1 = sum_j w1_j x_j and c2 = sum_j w2_j x_j.
static void QuadraticFitWeights(const std::vector<double>& s, std::vector<double>* w1, std::vector<double>* w2) {
  const int n = static_cast<int>(s.size());
  Eigen::MatrixXd A(n, 3);
  for (int j = 0; j < n; ++j) A.row(j) << 1.0, s[j], 0.5 * s[j] * s[j];
  const Eigen::MatrixXd W = (A.transpose() * A).ldlt().solve(A.transpose());  // 3 x n
  w1->resize(n);
  w2->resize(n);
  for (int j = 0; j < n; ++j) {
    (*w1)[j] = W(1, j);
    (*w2)[j] = W(2, j);
  }
}

MasterStream::MasterStream(std::vector<NavState> records, DerivativeMode mode, const std::string& path,
                           int fit_records)
    : records_(std::move(records)), fit_records_(fit_records) {
  Validate(records_, path);
  const std::size_t n = records_.size();
  kinematics_.resize(n);
  std::vector<Eigen::Vector3d> omega(n), a(n);
  auto t = [this](std::size_t k) { return records_[k].t_s; };

  if (mode == DerivativeMode::kCausal) {
    // First differences, valid from record 1; record 0 takes record 1's.
    for (std::size_t k = 1; k < n; ++k) {
      const double dt = t(k) - t(k - 1);
      omega[k] = RelativeRotation(records_[k - 1], records_[k]) / dt;
      a[k] = (records_[k].v_n_mps - records_[k - 1].v_n_mps) / dt;
    }
    omega[0] = omega[1];
    a[0] = a[1];
    // Second differences from the midpoint values, valid from record 2.
    for (std::size_t k = 2; k < n; ++k) {
      const double dm = 0.5 * (t(k) - t(k - 2));
      kinematics_[k].omega_dot_nb_b_radps2 = (omega[k] - omega[k - 1]) / dm;
      kinematics_[k].a_dot_n_mps3 = (a[k] - a[k - 1]) / dm;
    }
    for (std::size_t k = 0; k < 2; ++k) {
      kinematics_[k].omega_dot_nb_b_radps2 = kinematics_[2].omega_dot_nb_b_radps2;
      kinematics_[k].a_dot_n_mps3 = kinematics_[2].a_dot_n_mps3;
    }
  } else {
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t lo = k == 0 ? 0 : k - 1;
      const std::size_t hi = k + 1 == n ? k : k + 1;
      const double dt = t(hi) - t(lo);
      omega[k] = RelativeRotation(records_[lo], records_[hi]) / dt;
      a[k] = (records_[hi].v_n_mps - records_[lo].v_n_mps) / dt;
    }
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t lo = k == 0 ? 0 : k - 1;
      const std::size_t hi = k + 1 == n ? k : k + 1;
      const double dt = t(hi) - t(lo);
      kinematics_[k].omega_dot_nb_b_radps2 = (omega[hi] - omega[lo]) / dt;
      kinematics_[k].a_dot_n_mps3 = (a[hi] - a[lo]) / dt;
    }
  }
  if (mode == DerivativeMode::kCausal && fit_records_ >= 3) {
    // Causal quadratic fits over the last fit_records records (master.h).
    const std::size_t w = static_cast<std::size_t>(fit_records_);
    std::vector<double> s(w), w1, w2;
    for (std::size_t k = w - 1; k < n; ++k) {
      for (std::size_t j = 0; j < w; ++j) s[j] = t(k - j) - t(k);
      QuadraticFitWeights(s, &w1, &w2);
      Eigen::Vector3d om = Eigen::Vector3d::Zero(), om_dot = Eigen::Vector3d::Zero();
      Eigen::Vector3d acc = Eigen::Vector3d::Zero(), acc_dot = Eigen::Vector3d::Zero();
      for (std::size_t j = 0; j < w; ++j) {
        const Eigen::Vector3d x = j == 0 ? Eigen::Vector3d::Zero() : RelativeRotation(records_[k], records_[k - j]);
        om += w1[j] * x;
        om_dot += w2[j] * x;
        acc += w1[j] * records_[k - j].v_n_mps;
        acc_dot += w2[j] * records_[k - j].v_n_mps;
      }
      omega[k] = om;
      a[k] = acc;
      kinematics_[k].omega_dot_nb_b_radps2 = om_dot;
      kinematics_[k].a_dot_n_mps3 = acc_dot;
    }
  }
  {
    std::vector<double> dts;
    for (std::size_t k = 1; k < n; ++k) dts.push_back(t(k) - t(k - 1));
    std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
    median_dt_s_ = dts[dts.size() / 2];
  }
  for (std::size_t k = 0; k < n; ++k) {
    MasterKinematics& m = kinematics_[k];
    m.tag_s = records_[k].t_s;
    m.q_n_b = records_[k].q_n_b.normalized();
    m.v_n_mps = records_[k].v_n_mps;
    m.omega_nb_b_radps = omega[k];
    m.a_n_mps2 = a[k];
  }
}

double MasterStream::VelocityNoiseGain(double tau_s, DelayOrder order) const {
  if (order == DelayOrder::kFirst) return 1.0;  // v_k alone
  // Weights of v_k, v_{k-1}, ... in v_k + tau a_k + tau^2/2 a_dot_k.
  std::vector<double> weights;
  if (fit_records_ >= 3) {
    std::vector<double> s(static_cast<std::size_t>(fit_records_)), w1, w2;
    for (std::size_t j = 0; j < s.size(); ++j) s[j] = -static_cast<double>(j) * median_dt_s_;
    QuadraticFitWeights(s, &w1, &w2);
    for (std::size_t j = 0; j < s.size(); ++j) weights.push_back(tau_s * w1[j] + 0.5 * tau_s * tau_s * w2[j]);
  } else {
    // Backward differences: v_k + tau (v_k - v_{k-1})/dt + tau^2/2 (v_k - 2 v_{k-1} + v_{k-2})/dt^2
    // (the causal a_dot's midpoint spacing is dt).
    const double r = tau_s / median_dt_s_;
    weights = {r + 0.5 * r * r, -(r + r * r), 0.5 * r * r};
  }
  weights[0] += 1.0;
  double sum = 0.0;
  for (const double w : weights) sum += w * w;
  return std::sqrt(sum);
}

std::size_t MasterStream::LastAtOrBefore(double t_s) const {
  // First record with tag > t_s, then one back.
  const auto it = std::upper_bound(records_.begin(), records_.end(), t_s,
                                   [](double t, const NavState& r) { return t < r.t_s; });
  if (it == records_.begin()) return npos;
  return static_cast<std::size_t>(it - records_.begin()) - 1;
}

}  // namespace navtwin::transfer
