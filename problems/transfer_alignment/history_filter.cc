// Delayed-state fusion for transfer alignment (history_filter.h).
#include "problems/transfer_alignment/history_filter.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "core/earth.h"
#include "core/rotation.h"
#include "core/imu_error_model.h"
#include "core/strapdown.h"
#include "problems/transfer_alignment/filter_model.h"
#include "problems/transfer_alignment/master.h"

namespace navtwin::transfer {
namespace {

using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using tstate::kAtt;
using tstate::kMis;
using tstate::kTau;
using tstate::kVel;

constexpr int kCloneSize = 6;  // [dv, phi] of the slave at the clone's time
constexpr int kClonePhi = 3;   // offset of phi within a clone
constexpr int kInstr = kTransferStates;                        // offset of the instrument errors
constexpr int kPresent = kTransferStates + kInstrumentStates;  // the present's block
using InstrumentVector = InstrumentPrior;  // same shape: the estimates
constexpr int kHistoryIterations = 3;
constexpr double kSettledDelay_s = 1e-6;
constexpr double kSettledAngle_rad = 1e-6;
constexpr double kSettledVelocity_mps = 1e-6;
// Spacing of the clones (s): the error between two clones is interpolated linearly, and the
// error state changes little over it (f x phi dt: 50 m/s^2 x 0.1 mrad x 0.1 s = 0.5 mm/s,
// against the master's 10-50 mm/s). 0.1 s gave the same errors over 50 seeds at 1.15 times
// the cost (docs/transfer-alignment.md, "Cost").
constexpr double kCloneSpacing_s = 0.2;
// History kept beyond |tau| + 4 sigma_tau: room for the delay to grow before the next trim.
constexpr double kHistoryMargin_s = 0.1;
// A delay estimate below zero puts the data time after the present: the measurement is then
// the slave's newest IMU interval extrapolated (the linearisation of the model about the
// present), up to this lead; further, the record is not used.
constexpr double kMaxLead_s = 0.5;

/// The nominal slave's acceleration over a bracket, NED, m/s^2: (v_n1 - v_n0) / h.
Vector3d BracketAcceleration(const HistoryBracket& b) { return (b.n1.v_n_mps - b.n0.v_n_mps) / (b.n1.t_s - b.n0.t_s); }

/// Velocity-match variance per NED axis that the linearisation in the delay leaves out: the
/// delay column carries the nominal slave's acceleration a_s = (v_n1 - v_n0) / h, which
/// differs from the true one by -[f x] phi (f = a_s - g_n, the specific force, and phi the
/// attitude error); the neglected product [f x] phi dtau, of two independent zero-mean
/// errors, has variance sigma_tau^2 diag([f x] P_phi [f x]^T). It matters while both are
/// large (an acquisition with a precise master: the nominal's own drift would otherwise be
/// read as motion that fixes the delay) and vanishes as they converge.
/// (m/s)^2 per axis; P_phi_rad2: the attitude error's covariance at the node before s.
Vector3d DelayLinearisationVariance(const HistoryBracket& b, const Vector3d& g_n_mps2, const Matrix3d& P_phi_rad2,
                                    double var_tau_s2) {
  const Matrix3d F = Skew<double>(Vector3d(BracketAcceleration(b) - g_n_mps2));
  return (F * P_phi_rad2 * F.transpose()).diagonal() * std::max(var_tau_s2, 0.0);
}

/// Position of s in a sorted sequence of times: the segment [i0, i0 + 1] that holds s, or
/// the first / last segment when s is outside (the caller extrapolates).
template <typename Times>
std::size_t Segment(const Times& times, double s) {
  const auto it = std::upper_bound(times.begin(), times.end(), s);
  const std::size_t j = static_cast<std::size_t>(it - times.begin());
  return std::min(std::max<std::size_t>(j, 1), times.size() - 1) - 1;
}

class HistoryFilter {
 public:
  HistoryFilter(const TransferInputs& in, const TransferConfig& cfg)
      : cfg_(cfg),
        master_(in.master, DerivativeMode::kCausal, in.master_path,
                MasterFitRecords(in.master, cfg.master_fit_window_s)),
        ins_(in.slave_initial),
        q_(TransferProcessNoise(cfg, SlaveBiases::kAsStates)),
        slave_imu_(in.slave_imu) {
    CheckTransferFilterConfig(cfg, "RunHistoryFilter");
    misalignment_ = in.misalignment_guess.normalized();
    tau_s_ = cfg.delay_initial_s;
    Eigen::Matrix<double, kPresent, 1> sd;
    sd << TransferInitialSigma(cfg), InstrumentPriorSigma(cfg);
    P_ = MatrixXd(sd.cwiseAbs2().asDiagonal());
    acc_xx_.setIdentity();
    acc_xi_.setZero();
    acc_q_.setZero();
    PushNode();
    AddClone();
  }

  const MatrixXd& P() const { return P_; }

  void Run(TransferFilterRun* out) {
    WalkSlaveImu(
        slave_imu_, master_, ins_.state().t_s, [this](const ImuSample& s) { Propagate(s); },
        [this, out](std::size_t k) { Update(k, out); });
  }

 private:
  std::size_t clones() const { return clone_t_.size(); }
  static int CloneOffset(std::size_t j) { return kPresent + kCloneSize * static_cast<int>(j); }

  /// The raw sample corrected for the estimated instrument errors: K^-1 (x - b dt) with
  /// K = I + diag(s) + M (core/imu_error_model.h), K^-1 kept from the last update.
  ImuSample CorrectInstrument(const ImuSample& raw) const {
    ImuSample c = raw;
    c.dtheta_b_rad = gyro_correction_ * (raw.dtheta_b_rad - TriadBias(instrument_.data() + istate::kSg) * raw.dt_s);
    c.dv_b_mps = accel_correction_ * (raw.dv_b_mps - TriadBias(instrument_.data() + istate::kSa) * raw.dt_s);
    return c;
  }

  void PushNode() {
    const NavState& s = ins_.state();
    node_t_.push_back(s.t_s);
    nodes_.push_back({s.t_s, s.q_n_b, s.v_n_mps});
  }

  // The present [x (10), instrument errors (24)] moves with [[Phi_xx, Phi_xi], [0, I]]
  // (filter_model.h TransferTransition). P is not touched per sample: the
  // product of the transitions since the last update, [[A, B], [0, I]], and the process
  // noise carried through them, Q_acc, are accumulated, and applied once at the next
  // update (FlushPropagation) -- the same result as sample by sample, at a fraction of the
  // cost with 34 states and the clones.
  void Propagate(const ImuSample& raw) {
    const ImuSample s = CorrectInstrument(raw);
    const double dt = s.dt_s;
    InstrumentColumns phi_xi;
    const TransferMatrix phi_xx = TransferTransition(ins_.state(), s, &phi_xi);
    // Coefficient-based products: fixed 10 x 10 and 10 x 24 blocks, where the blocked
    // GEMM's packing costs more than the arithmetic (per IMU sample).
    acc_xi_ = phi_xx.lazyProduct(acc_xi_) + phi_xi;
    acc_xx_ = phi_xx.lazyProduct(acc_xx_);
    const TransferMatrix phi_q = phi_xx.lazyProduct(acc_q_);
    acc_q_ = phi_q.lazyProduct(phi_xx.transpose());
    acc_q_.diagonal() += q_ * dt;
    ins_.Update(s);
    PushNode();
  }

  /// Applies the transition accumulated since the last update to P:
  ///   P_xx <- A P_xx A^T + A P_xi B^T + B P_ix A^T + B P_ii B^T + Q_acc,
  ///   P_xi <- A P_xi + B P_ii,  P_xc <- A P_xc + B P_ic   (clones c),
  /// the instrument errors' and the clones' own blocks unchanged.
  void FlushPropagation() {
    const int n = kCloneSize * static_cast<int>(clones());
    auto Pxx = P_.topLeftCorner<kTransferStates, kTransferStates>();
    auto Pxi = P_.block<kTransferStates, kInstrumentStates>(0, kInstr);
    const auto Pii = P_.block<kInstrumentStates, kInstrumentStates>(kInstr, kInstr);
    const InstrumentColumns Pxi0 = Pxi;
    const Eigen::Matrix<double, kInstrumentStates, kInstrumentStates> Pii0 = Pii;
    const InstrumentColumns A_Pxi = acc_xx_.lazyProduct(Pxi0);
    const InstrumentColumns B_Pii = acc_xi_.lazyProduct(Pii0);
    const TransferMatrix Pxx0 = Pxx;
    const TransferMatrix cross = A_Pxi.lazyProduct(acc_xi_.transpose());
    Pxx = acc_xx_.lazyProduct(Pxx0).lazyProduct(acc_xx_.transpose()) + cross + cross.transpose() +
          B_Pii.lazyProduct(acc_xi_.transpose()) + acc_q_;
    Pxi = A_Pxi + B_Pii;
    P_.block<kInstrumentStates, kTransferStates>(kInstr, 0) = Pxi.transpose();
    if (n > 0) {
      // Coefficient-wise (lazy) products: the blocks are a few tens wide, where the blocked
      // GEMM's packing costs more than the arithmetic.
      const MatrixXd Pxc = P_.block(0, kPresent, kTransferStates, n);
      P_.block(0, kPresent, kTransferStates, n) =
          acc_xx_.lazyProduct(Pxc) + acc_xi_.lazyProduct(P_.block(kInstr, kPresent, kInstrumentStates, n));
      P_.block(kPresent, 0, n, kTransferStates) = P_.block(0, kPresent, kTransferStates, n).transpose();
    }
    acc_xx_.setIdentity();
    acc_xi_.setZero();
    acc_q_.setZero();
  }

  /// Clones the present's [dv, phi] at its time (unless the newest clone is at that time).
  void AddClone() {
    if (!clone_t_.empty() && clone_t_.back() > ins_.state().t_s - kCloneSpacing_s + 1e-9) return;
    const int N = static_cast<int>(P_.rows());
    MatrixXd P(N + kCloneSize, N + kCloneSize);
    P.topLeftCorner(N, N) = P_;
    P.bottomLeftCorner(kCloneSize, N) = P_.topRows(kCloneSize);
    P.topRightCorner(N, kCloneSize) = P_.leftCols(kCloneSize);
    P.bottomRightCorner<kCloneSize, kCloneSize>() = P_.topLeftCorner<kCloneSize, kCloneSize>();
    P_.swap(P);
    clone_t_.push_back(ins_.state().t_s);
  }

  /// Drops the clones (and nominal epochs) older than the history the delay needs, keeping
  /// the newest one at or before that horizon.
  void Trim(double t_now_s) {
    const double sigma_tau = std::sqrt(std::max(P_(kTau, kTau), 0.0));
    const double span = std::min(cfg_.history_window_s, std::max(tau_s_, 0.0) + 4.0 * sigma_tau + kHistoryMargin_s);
    const double horizon = t_now_s - span;
    std::size_t drop = 0;
    while (drop + 1 < clones() && clone_t_[drop + 1] <= horizon) ++drop;
    if (drop > 0) {
      const int n_old = kCloneSize * static_cast<int>(drop);
      const int keep = static_cast<int>(P_.rows()) - kPresent - n_old;
      MatrixXd P(kPresent + keep, kPresent + keep);
      P.topLeftCorner<kPresent, kPresent>() = P_.topLeftCorner<kPresent, kPresent>();
      P.topRightCorner(kPresent, keep) = P_.topRightCorner(kPresent, keep);
      P.bottomLeftCorner(keep, kPresent) = P_.bottomLeftCorner(keep, kPresent);
      P.bottomRightCorner(keep, keep) = P_.bottomRightCorner(keep, keep);
      P_.swap(P);
      clone_t_.erase(clone_t_.begin(), clone_t_.begin() + static_cast<std::ptrdiff_t>(drop));
    }
    const double oldest = clone_t_.front();
    while (node_t_.size() > 2 && node_t_[1] <= oldest) {
      node_t_.pop_front();
      nodes_.pop_front();
    }
  }

  /// The bracket at data time s under the augmented correction dx (errors of the nodes),
  /// with the augmented offsets of its two error nodes; false when s is outside the history.
  bool Bracket(double s, const VectorXd& dx, HistoryBracket* b, int* o0, int* o1) const {
    const double t_now = ins_.state().t_s;
    if (s < clone_t_.front() || s > t_now + kMaxLead_s || nodes_.size() < 2) return false;
    const std::size_t i = Segment(node_t_, s);
    b->n0 = nodes_[i];
    b->n1 = nodes_[i + 1];
    // Error nodes: the clones, then the present.
    const std::size_t j = static_cast<std::size_t>(std::upper_bound(clone_t_.begin(), clone_t_.end(), s) - clone_t_.begin());
    if (j >= clones()) {  // after the newest clone
      b->c0_s = clone_t_.back();
      b->c1_s = t_now;
      *o0 = CloneOffset(clones() - 1);
      *o1 = 0;
    } else {
      b->c0_s = clone_t_[j - 1];
      b->c1_s = clone_t_[j];
      *o0 = CloneOffset(j - 1);
      *o1 = CloneOffset(j);
    }
    if (!(b->c1_s > b->c0_s)) {
      // The present still at the newest clone's time (no IMU sample since): the two are the
      // same state, so any split of the weight between them gives the same error; 1 s apart
      // puts it on the present.
      b->c0_s = b->c1_s - 1.0;
    }
    b->e0 = dx.segment<kCloneSize>(*o0);
    b->e1 = dx.segment<kCloneSize>(*o1);
    return true;
  }

  void Update(std::size_t k, TransferFilterRun* out) {
    FlushPropagation();
    const MasterKinematics& kin = master_.kinematics(k);
    Trim(kin.tag_s);
    NavState s = ins_.state();
    ResetSlavePosition(master_.record(k), tau_s_, &s);
    ins_.SetState(s);
    Eigen::Matrix<double, 6, 1> r0;
    double nis0 = std::nan("");
    const bool used = Correct(kin, &r0, &nis0);
    if (!used) ++out->records_outside_history;
    AddClone();
    TransferEpoch e;
    e.t_s = kin.tag_s;
    e.slave = ins_.state();
    e.slave.t_s = kin.tag_s;
    e.misalignment = misalignment_;
    e.delay_s = tau_s_;
    e.sigma = P_.diagonal().head<kTransferStates>().cwiseMax(0.0).cwiseSqrt();
    e.innovation = used ? Eigen::Matrix<double, 6, 1>(-r0) : Eigen::Matrix<double, 6, 1>::Constant(std::nan(""));
    e.nis = nis0;
    out->epochs.push_back(e);
  }

  /// The iterated update with record kin (history_filter.h); r0, nis0: the residual and the
  /// normalised innovation squared at the prior estimate. False (nothing changed) when the
  /// data time lies outside the history.
  bool Correct(const MasterKinematics& kin, Eigen::Matrix<double, 6, 1>* r0, double* nis0) {
    const int N = static_cast<int>(P_.rows());
    const NavState& now = ins_.state();
    const Vector3d g_n_mps2 = wgs84::GravityNed(now.lat_rad, now.h_m);
    Vector6 inv_sigma;
    VectorXd dx = VectorXd::Zero(N);
    MatrixXd PHt(N, 6);
    Eigen::LLT<Eigen::Matrix<double, 6, 6>> S;  // of H P H^T + I (whitened)
    Vector6 y;
    for (int it = 0; it < kHistoryIterations; ++it) {
      const double tau_i = tau_s_ + dx(kTau);
      HistoryBracket b;
      int o0 = 0, o1 = 0;
      if (!Bracket(kin.tag_s - tau_i, dx, &b, &o0, &o1)) {
        if (it == 0) return false;
        break;  // the iterate left the history: keep the previous linearisation
      }
      const Matrix3d M_i = ApplyAttitudeError<double>(Vector3d(dx.segment<3>(kMis)), misalignment_).toRotationMatrix();
      Vector6 r;
      Eigen::Matrix<double, 6, kHistoryColumns> H;
      HistoryMatchResidualAndJacobian(b, M_i, kin, tau_i, cfg_.lever_arm_b_m, &r, &H);
      if (it == 0) {
        *r0 = r;
        const Vector3d var_v = Vector3d::Constant(cfg_.master_velocity_mps * cfg_.master_velocity_mps) +
                               DelayLinearisationVariance(b, g_n_mps2, P_.block<3, 3>(o0 + kClonePhi, o0 + kClonePhi), P_(kTau, kTau));
        inv_sigma << var_v.cwiseSqrt().cwiseInverse(), Vector3d::Constant(1.0 / cfg_.master_attitude_rad);
      }
      H = inv_sigma.asDiagonal() * H;
      const int idx[4] = {o0, o1, kMis, kTau};
      const int len[4] = {kCloneSize, kCloneSize, 3, 1};
      PHt.setZero();
      y = -r.cwiseProduct(inv_sigma);
      for (int g = 0, col = 0; g < 4; col += len[g], ++g) {
        PHt.noalias() += P_.middleCols(idx[g], len[g]).lazyProduct(H.middleCols(col, len[g]).transpose());
        y += H.middleCols(col, len[g]) * dx.segment(idx[g], len[g]);
      }
      Eigen::Matrix<double, 6, 6> HPHt = Eigen::Matrix<double, 6, 6>::Identity();
      for (int g = 0, col = 0; g < 4; col += len[g], ++g) {
        HPHt.noalias() += H.middleCols(col, len[g]).lazyProduct(PHt.middleRows(idx[g], len[g]));
      }
      S.compute(HPHt);
      const Vector6 S_inv_y = S.solve(y);
      if (it == 0) *nis0 = y.dot(S_inv_y);
      const VectorXd dx_next = PHt * S_inv_y;
      if (!dx_next.allFinite()) Fail(kin.tag_s, "the iterated correction");
      // The linearisation point moved by less than the model's nonlinearity can feel (the
      // delay by 1 us, attitudes by 1 urad): a further iteration would give the same.
      const VectorXd step = dx_next - dx;
      const bool settled = it > 0 && std::abs(step(kTau)) < kSettledDelay_s &&
                           step.segment<3>(kVel).cwiseAbs().maxCoeff() < kSettledVelocity_mps &&
                           step.segment<6>(kAtt).cwiseAbs().maxCoeff() < kSettledAngle_rad;  // phi and mu
      dx = dx_next;
      if (settled) break;
    }
    // P <- P - K S K^T with K = P H^T S^-1 (the last linearisation): K S K^T = W W^T with
    // W = P H^T L^-T, S = L L^T.
    // W by a coefficient-based product with L^-T (6 x 6): at N x 6 the blocked triangular
    // solve spends more on packing than on arithmetic.
    const Eigen::Matrix<double, 6, 6> L_inv_T =
        S.matrixL().solve(Eigen::Matrix<double, 6, 6>::Identity()).transpose();
    const MatrixXd W = PHt.lazyProduct(L_inv_T);
    P_.selfadjointView<Eigen::Lower>().rankUpdate(W, -1.0);  // the lower triangle: half the work
    P_.triangularView<Eigen::StrictlyUpper>() = P_.transpose();  // exactly symmetric
    Feedback(dx, kin.tag_s);
    return true;
  }

  /// The correction into the present, the misalignment, the delay and the stored history
  /// (each nominal epoch by its error interpolated between the error nodes around it).
  void Feedback(const VectorXd& dx, double t_s) {
    NavState s = ins_.state();
    s.v_n_mps += dx.segment<3>(kVel);
    s.q_n_b = ApplyAttitudeError<double>(Vector3d(dx.segment<3>(kAtt)), s.q_n_b);
    misalignment_ = ApplyAttitudeError<double>(Vector3d(dx.segment<3>(kMis)), misalignment_);
    tau_s_ += dx(kTau);
    instrument_ += dx.segment<kInstrumentStates>(kInstr);
    gyro_correction_ = TriadMatrix(instrument_.data() + istate::kSg).inverse();
    accel_correction_ = TriadMatrix(instrument_.data() + istate::kSa).inverse();
    if (!s.v_n_mps.allFinite() || !s.q_n_b.coeffs().allFinite() || !std::isfinite(tau_s_)) Fail(t_s, "the slave state");
    ins_.SetState(s);
    const auto node_error = [&](std::size_t j) -> Vector6 {
      return j < clones() ? Vector6(dx.segment<kCloneSize>(CloneOffset(j))) : Vector6(dx.head<kCloneSize>());
    };
    std::size_t j = 0;  // error node at or after the epoch (clones(): the present)
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      SlaveNode& n = nodes_[i];
      while (j < clones() && clone_t_[j] < n.t_s) ++j;
      Vector6 e;
      if (j == 0) {
        e = node_error(0);
      } else {
        const double c0 = clone_t_[j - 1], c1 = j < clones() ? clone_t_[j] : s.t_s;
        const double a = c1 > c0 ? (n.t_s - c0) / (c1 - c0) : 1.0;
        e = (1.0 - a) * node_error(j - 1) + a * node_error(j);
      }
      n.v_n_mps += e.head<3>();
      n.q_n_s = ApplyAttitudeError<double>(Vector3d(e.tail<3>()), n.q_n_s);
    }
    nodes_.back() = {s.t_s, s.q_n_b, s.v_n_mps};
  }

  [[noreturn]] static void Fail(double t_s, const char* what) { ThrowNonFinite("RunHistoryFilter", t_s, what); }

  const TransferConfig& cfg_;
  MasterStream master_;
  Strapdown ins_;
  Eigen::Quaterniond misalignment_;
  double tau_s_ = 0.0;
  TransferVector q_;  // continuous process-noise PSD per state
  const std::vector<ImuSample>& slave_imu_;
  MatrixXd P_;  // [present: x (10), instrument errors (24); clone 0 (6), clone 1 (6), ...]
  // Transition since the last update, not yet in the present-clone cross blocks:
  // [[acc_xx_, acc_xi_], [0, I]].
  TransferMatrix acc_xx_;
  InstrumentColumns acc_xi_;
  TransferMatrix acc_q_;
  InstrumentVector instrument_ = InstrumentVector::Zero();  // estimated, istate layout
  Matrix3d gyro_correction_ = Matrix3d::Identity();         // TriadMatrix(gyro)^-1
  Matrix3d accel_correction_ = Matrix3d::Identity();        // TriadMatrix(accel)^-1
  std::deque<double> clone_t_;
  std::deque<double> node_t_;  // times of nodes_, for the searches
  std::deque<SlaveNode> nodes_;
};

}  // namespace

void HistoryMatchResidualAndJacobian(const HistoryBracket& b, const Matrix3d& R_b_s, const MasterKinematics& m,
                                     double tau_s, const Vector3d& lever_arm_b_m, Eigen::Matrix<double, 6, 1>* r,
                                     Eigen::Matrix<double, 6, kHistoryColumns>* H) {
  const double s = m.tag_s - tau_s;
  const double h = b.n1.t_s - b.n0.t_s;
  const double hc = b.c1_s - b.c0_s;
  if (!(h > 0.0) || !(hc > 0.0)) throw std::invalid_argument("HistoryMatchResidualAndJacobian: empty bracket");
  // Nominal at s: linear velocity, geodesic attitude R0 Exp(a omega h).
  const double a = (s - b.n0.t_s) / h;
  const Matrix3d R0 = b.n0.q_n_s.toRotationMatrix();
  const Vector3d omega_s = LogSO3<double>(Matrix3d(R0.transpose() * b.n1.q_n_s.toRotationMatrix())) / h;
  const Vector3d a_n_mps2 = BracketAcceleration(b);
  // Error at s, linear between the error nodes.
  const double ac = (s - b.c0_s) / hc;
  const Vector6 e = b.e0 + ac * (b.e1 - b.e0);
  const Matrix3d R_s = ExpSO3<double>(Vector3d(e.tail<3>())) * R0 * ExpSO3<double>(Vector3d(omega_s * (a * h)));
  const Vector3d v_s = b.n0.v_n_mps + a * h * a_n_mps2 + e.head<3>();
  // The shared model with no carry: the master at its data time.
  Eigen::Matrix<double, 6, kTransferStates> H10;
  MatchResidualAndJacobian(R_s, v_s, R_b_s, m, 0.0, DelayOrder::kFirst, lever_arm_b_m, r, &H10);
  // [dv, phi] at s; phi enters as Exp(phi) R, so d/d phi of Exp(phi + d) = Exp(Jl(phi) d) Exp(phi).
  Eigen::Matrix<double, 6, 6> H_e = H10.leftCols<6>();
  H_e.rightCols<3>() = H_e.rightCols<3>() * RightJacobianSO3<double>(Vector3d(-e.tail<3>()));
  H->setZero();
  H->leftCols<6>() = (1.0 - ac) * H_e;
  H->middleCols<6>(6) = ac * H_e;
  H->middleCols<3>(12) = H10.middleCols<3>(kMis);
  // d/dtau (ds/dtau = -1): the error interpolation, the nominal velocity, and the nominal
  // attitude R(s - d) = R(s) Exp(-omega d), which makes E = R_s M^T C^T into E Exp(-C M omega d).
  const Vector6 de_dtau = -(b.e1 - b.e0) / hc;
  Vector6 h_tau = H_e * de_dtau;
  h_tau.head<3>() -= a_n_mps2;
  const Matrix3d C = m.q_n_b.toRotationMatrix();
  h_tau.tail<3>() -= RightJacobianInverseSO3<double>(Vector3d(r->tail<3>())) * (C * R_b_s * omega_s);
  H->col(15) = h_tau;
}

TransferFilterRun RunHistoryFilter(const TransferInputs& inputs, const TransferConfig& config) {
  const auto start = std::chrono::steady_clock::now();
  ValidateInputs(inputs);
  TransferFilterRun run;
  HistoryFilter filter(inputs, config);
  filter.Run(&run);
  run.misalignment_delay_covariance = filter.P().block<4, 4>(kMis, kMis);
  run.run_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

}  // namespace navtwin::transfer
