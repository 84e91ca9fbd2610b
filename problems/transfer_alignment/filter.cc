// The seed's 10-state transfer-alignment filter (filter.h; docs/transfer-alignment.md,
// "The filter").
//
// Nominal state: the slave INS (core/strapdown.h on the raw slave IMU, attitude R_n_s),
// the misalignment estimate M = R_b_s and the delay estimate tau. Error state (true minus
// estimate): dx = [dv_n (3), phi_n (3), mu_b (3), dtau (1)] with
//   v_true = v + dv,  R_n_s_true = Exp(phi) R_n_s,  M_true = Exp(mu) M,  tau_true = tau + dtau.
//
// Propagation, per IMU sample (or part of one, when a master tag splits it), and the
// process noise: the shared model of problems/transfer_alignment/filter_model.h.
//
// Update at every master record whose tag lies inside the slave span: the INS is stepped
// to the tag, its position reset from the record carried forward over tau (the record
// holds the master's position at tag - tau), and the matching residuals of problems/transfer_alignment/delay_model.h
//   r = [v_s - v_pred(tau) - R_pred (omega x l);  Log(R_n_s (R_pred(tau) M)^T)]
// evaluated at the estimate. At the truth r = 0 + noise, so 0 ~ r + H dx + v and the
// innovation is y = -r ~ H dx (H = dr/d(dx), MatchResidualAndJacobian), relinearised
// (iterated EKF, kUpdateIterations) because the delay enters through Exp(omega tau).
// Measurement noise per axis (MeasurementSigma): the master's (config.master_velocity_mps
// through the differentiator's noise gain for order 2, master_attitude_mrad) combined with
// the compensation's truncation error, estimated by the first neglected term of the series
// at tau_eff = |tau| + sigma_tau (order 1: |omega_dot| tau^2/2 and |a| tau + |a_dot| tau^2/2;
// order 2: |omega_ddot| tau^3/6 and |a_ddot| tau^3/6, third derivatives by a backward
// difference). That term is not white (it is in phase with the delay's own column), so the
// filter also accumulates a bound of the bias it leaves in the misalignment and the delay
// (TransferFilterRun::truncation_bound, filter.h), which the reported sigma carry, with
// the covariance the slave's unmodelled instrument errors leave (a consider analysis,
// TransferFilterRun::instrument_sensitivity).
// On the preset the series' real error is larger still (omega tau to 1.9 rad),
// and a chi-square gate then rejects the records that carry the delay (the delay is not
// acquired: delay 3-70 ms at gate probabilities 0.9999 to 0.99999999), so the gate is off (kGateProbability).
// Whitened and passed to the project's Joseph-form ESKF (solvers/eskf.h). Feedback:
// v += dv, q_n_s <- Exp(phi) q_n_s, M <- Exp(mu) M, tau += dtau; the error state is zero again.
#include "problems/transfer_alignment/filter.h"

#include <chrono>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

#include "core/rotation.h"
#include "core/strapdown.h"
#include "problems/transfer_alignment/master.h"
#include "solvers/eskf.h"

namespace navtwin::transfer {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Matrix10 = TransferMatrix;
using Vector10 = TransferVector;
using tstate::kAtt;
using tstate::kMis;
using tstate::kTau;
using tstate::kVel;

constexpr double kGateProbability = 1.0;  // no gate: see the header comment
constexpr int kUpdateIterations = 3;

class TransferFilter {
 public:
  TransferFilter(const TransferInputs& in, const TransferConfig& cfg, DelayOrder order)
      : cfg_(cfg), order_(order),
        master_(in.master, DerivativeMode::kCausal, in.master_path, MasterFitRecords(in.master, cfg.master_fit_window_s)),
        ins_(in.slave_initial), kf_(InitialCovariance(cfg)), q_(TransferProcessNoise(cfg, SlaveBiases::kAsNoise)), slave_imu_(in.slave_imu) {
    misalignment_ = in.misalignment_guess.normalized();
    tau_s_ = cfg.delay_initial_s;
  }

  const Eigen::MatrixXd& P() const { return kf_.P(); }

  void Run(TransferFilterRun* out) {
    WalkSlaveImu(
        slave_imu_, master_, ins_.state().t_s, [this](const ImuSample& s) { Propagate(s); },
        [this, out](std::size_t k) { Update(k, out); });
    out->truncation_bound = TruncationBound();
    out->instrument_sensitivity = sensitivity_.middleRows<4>(kMis);
  }

 private:
  static Eigen::MatrixXd InitialCovariance(const TransferConfig& c) {
    CheckTransferFilterConfig(c, "RunTransferFilter");
    return Eigen::MatrixXd(TransferInitialSigma(c).cwiseAbs2().asDiagonal());
  }

  void Propagate(const ImuSample& s) {
    InstrumentColumns phi_xi;
    const Matrix10 Phi = TransferTransition(ins_.state(), s, &phi_xi);
    const Matrix10 Qd = Matrix10((q_ * s.dt_s).asDiagonal());
    kf_.Predict(Phi, Qd);
    // Consider analysis of the slave's instrument errors p (filter.h,
    // TransferFilterRun::instrument_sensitivity): the sensitivity S = d dx / d p moves with the
    // transition, S <- Phi S + Phi_xi; an accepted update with gain K leaves (I - K H) S.
    sensitivity_ = Phi.lazyProduct(sensitivity_) + phi_xi;
    ins_.Update(s);
  }

  void Update(std::size_t k, TransferFilterRun* out) {
    const MasterKinematics& kin = master_.kinematics(k);
    NavState s = ins_.state();
    ResetSlavePosition(master_.record(k), tau_s_, &s);
    const Remainder remainder = SeriesRemainder(k);
    const Eigen::Matrix<double, 6, 1> sigma = MeasurementSigma(remainder);
    const Eigen::Matrix<double, 6, 1> inv_sigma = sigma.cwiseInverse();
    // Iterated update (Gauss-Newton on the prior plus this record): relinearise at
    // x0 (+) dx_i; dx_{i+1} = K_i (y_i + H_i dx_i), K_i = P H_i^T (H_i P H_i^T + I)^-1
    // (whitened). The delay enters through Exp(omega tau) with omega tau up to ~0.5 rad on
    // the preset, so one linearisation at a poor delay estimate overshoots. The last
    // iteration goes through the ESKF engine (gate, Joseph form) with y + H dx_i.
    Eigen::Matrix<double, 6, 1> r, r0;
    Eigen::Matrix<double, 6, kTransferStates> H;
    Vector10 dx_i = Vector10::Zero();
    Eigen::MatrixXd Hw;
    Eigen::VectorXd y;
    double nis0 = std::nan("");
    for (int it = 0; it < kUpdateIterations; ++it) {
      const Eigen::Quaterniond q_i = ApplyAttitudeError<double>(Vector3d(dx_i.segment<3>(kAtt)), s.q_n_b);
      const Eigen::Quaterniond m_i = ApplyAttitudeError<double>(Vector3d(dx_i.segment<3>(kMis)), misalignment_);
      MatchResidualAndJacobian(q_i.toRotationMatrix(), s.v_n_mps + dx_i.segment<3>(kVel), m_i.toRotationMatrix(), kin,
                               tau_s_ + dx_i(kTau), order_, cfg_.lever_arm_b_m, &r, &H);
      if (it == 0) r0 = r;
      Hw = inv_sigma.asDiagonal() * H;
      y = -r.cwiseProduct(inv_sigma) + Hw * dx_i;
      if (it + 1 == kUpdateIterations) break;
      const Eigen::MatrixXd& P = kf_.P();
      const Eigen::MatrixXd S = Hw * P * Hw.transpose() + Eigen::MatrixXd::Identity(6, 6);
      const Eigen::VectorXd S_inv_y = S.ldlt().solve(y);
      if (it == 0) nis0 = y.dot(S_inv_y);
      dx_i = P * Hw.transpose() * S_inv_y;
      if (!dx_i.allFinite()) Fail(kin.tag_s, "the iterated correction");
    }
    r = r0;
    const ErrorStateKalmanFilter::Update u = kf_.Correct(y, Hw, kGateProbability);
    if (u.accepted) {  // a rejected record moves neither the estimate nor its error terms
      AccumulateTruncation(remainder, sigma, Hw);
      sensitivity_ -= u.K * (Hw * sensitivity_);  // S <- (I - K H) S
    }
    const Eigen::VectorXd& dx = u.dx;
    if (!dx.allFinite()) Fail(kin.tag_s, "the state correction");
    // Feedback (the error state is zero again afterwards).
    s.v_n_mps += dx.segment<3>(kVel);
    s.q_n_b = ApplyAttitudeError<double>(dx.segment<3>(kAtt), s.q_n_b);
    ins_.SetState(s);
    misalignment_ = ApplyAttitudeError<double>(dx.segment<3>(kMis), misalignment_);
    tau_s_ += dx(kTau);
    if (!s.v_n_mps.allFinite() || !s.q_n_b.coeffs().allFinite() || !std::isfinite(tau_s_)) {
      Fail(kin.tag_s, "the slave state");
    }
    TransferEpoch e;
    e.t_s = kin.tag_s;
    e.slave = s;
    e.slave.t_s = kin.tag_s;
    e.misalignment = misalignment_;
    e.delay_s = tau_s_;
    e.sigma = kf_.P().diagonal().cwiseMax(0.0).cwiseSqrt();
    e.innovation = -r;
    e.nis = nis0;
    out->epochs.push_back(e);
  }

  /// The first neglected term of the compensation series at record k, per channel, as a
  /// polynomial in the delay: |term| = sum_n c_n tau^n (c indexed by the power, 0..3).
  /// Order 1: |omega_dot| tau^2 / 2 and |a| tau + |a_dot| tau^2 / 2; order 2: |omega_ddot|
  /// tau^3 / 6 and |a_ddot| tau^3 / 6, the third derivatives by a backward difference of the
  /// second (none at the first record).
  struct Remainder {
    Eigen::Vector4d att = Eigen::Vector4d::Zero();  // rad
    Eigen::Vector4d vel = Eigen::Vector4d::Zero();  // m/s
  };
  Remainder SeriesRemainder(std::size_t k) const {
    const MasterKinematics& m = master_.kinematics(k);
    Remainder rem;
    if (order_ == DelayOrder::kFirst) {
      rem.att(2) = m.omega_dot_nb_b_radps2.norm() / 2.0;
      rem.vel(1) = m.a_n_mps2.norm();
      rem.vel(2) = m.a_dot_n_mps3.norm() / 2.0;
      return rem;
    }
    if (k == 0) return rem;
    const MasterKinematics& p = master_.kinematics(k - 1);
    const double dt = m.tag_s - p.tag_s;
    rem.att(3) = ((m.omega_dot_nb_b_radps2 - p.omega_dot_nb_b_radps2) / dt).norm() / 6.0;
    rem.vel(3) = ((m.a_dot_n_mps3 - p.a_dot_n_mps3) / dt).norm() / 6.0;
    return rem;
  }
  // The delay at which the series' remainder is evaluated, tau_eff = |tau| + sigma_tau, s.
  double EffectiveDelay_s() const { return std::abs(tau_s_) + std::sqrt(std::max(kf_.P()(kTau, kTau), 0.0)); }
  static Eigen::Vector4d Powers(double tau_s) { return Eigen::Vector4d(1.0, tau_s, tau_s * tau_s, tau_s * tau_s * tau_s); }

  // Per-axis 1-sigma of the velocity and attitude matching with remainder rem of the record (see the header
  // comment, "measurement noise"): the master's noise, the velocity noise through the
  // differentiator's gain, and the truncation error of the compensation series estimated
  // by its first neglected term at the delay tau_eff = |tau| + sigma_tau.
  Eigen::Matrix<double, 6, 1> MeasurementSigma(const Remainder& rem) const {
    const double tau = EffectiveDelay_s();
    const double trunc_att = rem.att.dot(Powers(tau)), trunc_vel = rem.vel.dot(Powers(tau));
    // The weights of the v_j in v_k + tau a_k + tau^2/2 a_dot_k (differences or the fit).
    const double gain_v = order_ == DelayOrder::kFirst ? 1.0 : master_.VelocityNoiseGain(tau, order_);
    Eigen::Matrix<double, 6, 1> sigma;
    sigma.head<3>().setConstant(std::hypot(gain_v * cfg_.master_velocity_mps, trunc_vel));
    sigma.tail<3>().setConstant(std::hypot(cfg_.master_attitude_rad, trunc_att));
    return sigma;
  }

  // The bounds of the misalignment's and the delay's bias by the series' truncation
  // (filter.h, TransferFilterRun::truncation_bound). Per record: the whitened squared norm
  // of the remainder as a quadratic form in the powers of tau, and the information the
  // record gives each of mu and tau, |column of H / sigma|^2.
  void AccumulateTruncation(const Remainder& rem, const Eigen::Matrix<double, 6, 1>& sigma, const Eigen::MatrixXd& Hw) {
    truncation_form_ += rem.vel * rem.vel.transpose() / (sigma(0) * sigma(0)) +
                        rem.att * rem.att.transpose() / (sigma(3) * sigma(3));
    information_ += Hw.middleCols<4>(kMis).colwise().squaredNorm().transpose();
  }
  Eigen::Vector4d TruncationBound() const {
    const Eigen::Vector4d t = Powers(EffectiveDelay_s());
    const double remainder = std::max(t.dot(truncation_form_ * t), 0.0);
    Eigen::Vector4d bound = Eigen::Vector4d::Zero();
    for (int i = 0; i < 4; ++i) {
      if (information_(i) > 0.0) bound(i) = std::sqrt(remainder / information_(i));
    }
    return bound;
  }

  [[noreturn]] static void Fail(double t_s, const char* what) { ThrowNonFinite("RunTransferFilter", t_s, what); }

  const TransferConfig& cfg_;
  DelayOrder order_;
  MasterStream master_;
  Strapdown ins_;
  ErrorStateKalmanFilter kf_;
  Eigen::Quaterniond misalignment_;
  double tau_s_ = 0.0;
  Vector10 q_;  // continuous process-noise PSD per state
  const std::vector<ImuSample>& slave_imu_;
  Eigen::Matrix4d truncation_form_ = Eigen::Matrix4d::Zero();  // sum of c c^T / sigma^2
  Eigen::Vector4d information_ = Eigen::Vector4d::Zero();       // sum of |H_(mu, tau) / sigma|^2
  InstrumentColumns sensitivity_ = InstrumentColumns::Zero();   // d dx / d(instrument errors)
};

}  // namespace

void MatchResidualAndJacobian(const Matrix3d& R_n_s, const Vector3d& v_n_s_mps, const Matrix3d& R_b_s,
                              const MasterKinematics& m, double tau_s, DelayOrder order,
                              const Vector3d& lever_arm_b_m, Eigen::Matrix<double, 6, 1>* r,
                              Eigen::Matrix<double, 6, kTransferStates>* H) {
  // Residuals from the one model (problems/transfer_alignment/delay_model.h).
  r->head<3>() = VelocityMatchResidual<double>(v_n_s_mps, m, tau_s, order, lever_arm_b_m);
  const Vector3d r_att = AttitudeMatchResidual<double>(R_n_s, R_b_s, m, tau_s, order);
  r->tail<3>() = r_att;

  // C = R_n_b_pred = R_n_b Exp(theta(tau)); d theta / d tau = omega (+ omega_dot tau).
  const Vector3d theta = DelayRotationVector<double>(m, tau_s, order);
  Vector3d dtheta_dtau = m.omega_nb_b_radps;
  if (order == DelayOrder::kSecond) dtheta_dtau += m.omega_dot_nb_b_radps2 * tau_s;
  const Matrix3d C = CompensatedMasterDcm<double>(m, tau_s, order);
  // C(tau + d) = C Exp(u d) with u = Jr(theta) dtheta/dtau (body axes of the prediction).
  const Vector3d u = RightJacobianSO3(theta) * dtheta_dtau;

  H->setZero();
  // Velocity rows. d r_vel / d dv = I.
  H->block<3, 3>(0, kVel).setIdentity();
  // d r_vel / d tau: -(a + a_dot tau) for order 2 (order 1 holds v constant); the lever
  // term -C w, w = omega x l: C(tau + d) w = C Exp(u d) w = C w + C (u x w) d
  // = C w - C [w x] u d, so it contributes +C [w x] u.
  Vector3d dv_dtau = Vector3d::Zero();
  if (order == DelayOrder::kSecond) dv_dtau = m.a_n_mps2 + m.a_dot_n_mps3 * tau_s;
  Vector3d h_tau_v = -dv_dtau;
  if (!lever_arm_b_m.isZero()) {
    const Vector3d w_l = m.omega_nb_b_radps.cross(lever_arm_b_m);
    h_tau_v += C * Skew<double>(w_l) * u;
  }
  H->block<3, 1>(0, kTau) = h_tau_v;

  // Attitude rows, r = Log(E), E = R_n_s M^T C^T = Exp(r_att).
  //   phi: Log(Exp(phi) E) = r + Jl^-1(r) phi, Jl^-1(r) = Jr^-1(-r).
  //   mu:  (Exp(mu) M)^T = M^T Exp(-mu), and R_n_s M^T Exp(-mu) C^T = E C Exp(-mu) C^T
  //        = E Exp(-C mu): Log(E Exp(-C mu)) = r - Jr^-1(r) C mu.
  //   tau: C(tau + d)^T = Exp(-u d) C^T, so E -> E C Exp(-u d) C^T = E Exp(-C u d):
  //        d r / d tau = -Jr^-1(r) C u.
  const Matrix3d Jr_inv = RightJacobianInverseSO3(r_att);
  H->block<3, 3>(3, kAtt) = RightJacobianInverseSO3<double>(-r_att);
  H->block<3, 3>(3, kMis) = -Jr_inv * C;
  H->block<3, 1>(3, kTau) = -Jr_inv * C * u;
}

Eigen::Matrix4d InstrumentConsiderCovariance(const TransferFilterRun& run, const TransferConfig& config) {
  const Eigen::Matrix<double, 4, kInstrumentStates>& S = run.instrument_sensitivity;
  return S * InstrumentPriorSigma(config).cwiseAbs2().asDiagonal() * S.transpose();
}

TransferFilterRun RunTransferFilter(const TransferInputs& inputs, const TransferConfig& config, DelayOrder order) {
  const auto start = std::chrono::steady_clock::now();
  ValidateInputs(inputs);
  TransferFilterRun run;
  run.order = order;
  TransferFilter filter(inputs, config, order);
  filter.Run(&run);
  run.misalignment_delay_covariance = filter.P().block<4, 4>(kMis, kMis);
  run.run_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

}  // namespace navtwin::transfer
