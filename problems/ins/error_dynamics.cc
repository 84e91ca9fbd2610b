#include "problems/ins/error_dynamics.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/earth.h"
#include "core/rotation.h"
#include "factors/position_manifold.h"

namespace navtwin::ins {
namespace {

void CheckSize(int n, const char* what) {
  if (n != err::kSize15 && n != err::kSize21) {
    throw std::invalid_argument(std::string(what) + ": error-state size " + std::to_string(n) +
                                " is neither 15 nor 21");
  }
}

// 1 / tau for a Gauss-Markov correlation time (0 for an infinite or non-positive one:
// a random constant).
double InverseTau(double tau_s) {
  return (std::isfinite(tau_s) && tau_s > 0.0) ? 1.0 / tau_s : 0.0;
}

// d gamma / d lat and d gamma / d h of wgs84::NormalGravity (same formula, differentiated):
//   gamma = gamma_0(lat) c(lat, h),  gamma_0 = gamma_e (1 + k s^2) / sqrt(1 - e^2 s^2),
//   c = 1 - 2/a (1 + f + m - 2 f s^2) h + 3 h^2 / a^2,  s = sin lat.
void NormalGravityDerivatives(double lat, double h, double* dg_dlat, double* dg_dh) {
  using namespace wgs84;
  const double s = std::sin(lat), c = std::cos(lat), s2 = s * s;
  const double w = 1.0 - kE2 * s2;
  const double g0 = kGammaE_mps2 * (1.0 + kSomiglianaK * s2) / std::sqrt(w);
  const double dg0 = kGammaE_mps2 * (2.0 * kSomiglianaK * s * c / std::sqrt(w) +
                                     (1.0 + kSomiglianaK * s2) * kE2 * s * c / (w * std::sqrt(w)));
  const double corr = 1.0 - 2.0 / kA_m * (1.0 + kF + kM - 2.0 * kF * s2) * h + 3.0 * h * h / (kA_m * kA_m);
  const double dcorr_dlat = 8.0 * kF * s * c * h / kA_m;
  const double dcorr_dh = -2.0 / kA_m * (1.0 + kF + kM - 2.0 * kF * s2) + 6.0 * h / (kA_m * kA_m);
  *dg_dlat = dg0 * corr + g0 * dcorr_dlat;
  *dg_dh = g0 * dcorr_dh;
}

/// x * y for small fixed-size matrices, coefficient-based (Eigen would otherwise take its
/// blocked GEMM path, slow at 9 x 9).
template <typename X, typename Y>
auto Mul(const Eigen::MatrixBase<X>& x, const Eigen::MatrixBase<Y>& y) {
  return x.lazyProduct(y).eval();
}

/// PropagateCovariance for S IMU-error states (6 or 12) followed by aux_psd.size()
/// auxiliary random walks; see error_dynamics.h for the block form.
template <int S>
void PropagateBlocks(const Eigen::MatrixXd& F, const Eigen::MatrixXd& G, const Eigen::VectorXd& qc,
                     double dt, const Eigen::VectorXd& aux_psd, Eigen::MatrixXd* P, Eigen::MatrixXd* phi_acc) {
  constexpr int N = 9;  // navigation states: dp, dv, phi
  using MatNN = Eigen::Matrix<double, N, N>;
  using MatNS = Eigen::Matrix<double, N, S>;
  using MatSS = Eigen::Matrix<double, S, S>;
  // F dt = [[a, b], [0, c]]  =>  (F dt)^2 = [[a^2, a b + b c], [0, c^2]] and
  // Phi = [[A, B], [0, D]] = I + F dt + (F dt)^2 / 2.
  const MatNN a = F.topLeftCorner<N, N>() * dt;
  const MatNS b = F.topRightCorner<N, S>() * dt;
  const MatSS c = F.bottomRightCorner<S, S>() * dt;
  MatNN A = a + 0.5 * Mul(a, a);
  A.diagonal().array() += 1.0;
  const MatNS B = b + 0.5 * (Mul(a, b) + Mul(b, c));
  MatSS D = c + 0.5 * Mul(c, c);
  D.diagonal().array() += 1.0;
  // G Qc G^T = blockdiag(Qn, diag(qs)).
  const Eigen::Matrix<double, N, 6> Gn = G.topLeftCorner<N, 6>();
  const Eigen::Matrix<double, N, 6> Gq = Gn * qc.head<6>().asDiagonal();
  const MatNN Qn = Mul(Gq, Gn.transpose());
  // G maps the IMU-error driving noises w[6 .. 6 + S) onto the IMU-error rows (identity).
  const Eigen::Matrix<double, S, 1> qs = qc.segment<S>(6);
  // Phi P Phi^T with P = [[Pnn, Pns], [Pns^T, Pss]].
  const MatNN Pnn = P->topLeftCorner<N, N>();
  const MatNS Pns = P->block<N, S>(0, N);
  const MatSS Pss = P->block<S, S>(N, N);
  const MatNN M1 = Mul(A, Pnn) + Mul(B, Pns.transpose());
  const MatNS M2 = Mul(A, Pns) + Mul(B, Pss);
  MatNN Nnn = Mul(M1, A.transpose()) + Mul(M2, B.transpose());
  MatNS Nns = Mul(M2, D.transpose());
  MatSS Nss = Mul(Mul(D, Pss), D.transpose());
  // + Qd = dt/2 (Phi GQG Phi^T + GQG), Phi GQG Phi^T = [[A Qn A^T + B Qs B^T, B Qs D^T], [., D Qs D^T]].
  const MatNS Bq = B * qs.asDiagonal();
  Nnn += (0.5 * dt) * (Mul(Mul(A, Qn), A.transpose()) + Mul(Bq, B.transpose()) + Qn);
  Nns += (0.5 * dt) * Mul(Bq, D.transpose());
  const MatSS Dq = D * qs.asDiagonal();
  MatSS Qss = Mul(Dq, D.transpose());
  Qss.diagonal() += qs;
  Nss += (0.5 * dt) * Qss;
  P->topLeftCorner<N, N>() = 0.5 * (Nnn + Nnn.transpose());
  P->block<N, S>(0, N) = Nns;
  P->block<S, N>(N, 0) = Nns.transpose();
  P->block<S, S>(N, N) = 0.5 * (Nss + Nss.transpose());
  const int n_aux = static_cast<int>(aux_psd.size());
  if (n_aux > 0) {
    // Auxiliary random walks: [[Phi, 0], [0, I]], so P_ia <- Phi P_ia, P_aa += q dt.
    const Eigen::MatrixXd Pna = P->block(0, N + S, N, n_aux);
    const Eigen::MatrixXd Psa = P->block(N, N + S, S, n_aux);
    const Eigen::MatrixXd Nna = A * Pna + B * Psa;
    const Eigen::MatrixXd Nsa = D * Psa;
    P->block(0, N + S, N, n_aux) = Nna;
    P->block(N + S, 0, n_aux, N) = Nna.transpose();
    P->block(N, N + S, S, n_aux) = Nsa;
    P->block(N + S, N, n_aux, S) = Nsa.transpose();
    P->bottomRightCorner(n_aux, n_aux).diagonal() += aux_psd * dt;
  }
  if (phi_acc != nullptr) {
    // [[A, B], [0, D]] [[Xnn, Xns], [0, Xss]] = [[A Xnn, A Xns + B Xss], [0, D Xss]]; the
    // auxiliary block of the product stays I.
    const MatNN Xnn = phi_acc->topLeftCorner<N, N>();
    const MatNS Xns = phi_acc->block<N, S>(0, N);
    const MatSS Xss = phi_acc->block<S, S>(N, N);
    phi_acc->topLeftCorner<N, N>() = Mul(A, Xnn);
    phi_acc->block<N, S>(0, N) = Mul(A, Xns) + Mul(B, Xss);
    phi_acc->block<S, S>(N, N) = Mul(D, Xss);
  }
}

}  // namespace

Eigen::MatrixXd ErrorDynamicsF(const InsState& x, const Eigen::Vector3d& f_b_mps2,
                               const Eigen::Vector3d& omega_ib_b_radps, const ImuNoise& noise,
                               int n) {
  CheckSize(n, "ErrorDynamicsF");
  using Eigen::Matrix3d;
  using Eigen::Vector3d;
  const double lat = x.nav.lat_rad, h = x.nav.h_m;
  const Vector3d& v = x.nav.v_n_mps;
  const double vn = v.x(), ve = v.y(), vd = v.z();
  const double sl = std::sin(lat), cl = std::cos(lat), tl = std::tan(lat);
  const double M = wgs84::MeridianRadius(lat), N = wgs84::PrimeVerticalRadius(lat);
  const double rm = M + h, rn = N + h;
  const double w_e = wgs84::kOmegaIe_radps;
  // dN/dlat (the radii vary with latitude; these e^2-small terms are kept).
  const double dN = N * wgs84::kE2 * sl * cl / (1.0 - wgs84::kE2 * sl * sl);

  const Matrix3d R = x.nav.q_n_b.normalized().toRotationMatrix();
  const Vector3d f_n = R * f_b_mps2;
  const Vector3d w_ie = wgs84::EarthRateNed(lat);
  const Vector3d w_en = wgs84::TransportRateNed(lat, h, v);
  const Vector3d w_in = w_ie + w_en;

  // Partial derivatives of the rates w.r.t. (lat, h, v).
  const Vector3d dwie_dlat(-w_e * sl, 0.0, -w_e * cl);
  // d w_en / d lat, including the radii's variation dN/dlat, dM/dlat (e^2-small terms).
  const double dM = 3.0 * M * wgs84::kE2 * sl * cl / (1.0 - wgs84::kE2 * sl * sl);
  const Vector3d dwen_dlat(-ve * dN / (rn * rn), vn * dM / (rm * rm),
                           -ve / (cl * cl * rn) + ve * tl * dN / (rn * rn));
  const Vector3d dwen_dh(-ve / (rn * rn), vn / (rm * rm), ve * tl / (rn * rn));
  Matrix3d dwen_dv = Matrix3d::Zero();
  dwen_dv(0, 1) = 1.0 / rn;
  dwen_dv(1, 0) = -1.0 / rm;
  dwen_dv(2, 1) = -tl / rn;

  // Position error -> (dlat, dh): dlat = dp_N / rm, dh = -dp_D. As 1x3 rows in dp:
  Eigen::RowVector3d dlat_dp(1.0 / rm, 0.0, 0.0);
  Eigen::RowVector3d dh_dp(0.0, 0.0, -1.0);
  const Matrix3d dwie_dp = dwie_dlat * dlat_dp;
  const Matrix3d dwen_dp = dwen_dlat * dlat_dp + dwen_dh * dh_dp;

  Eigen::MatrixXd F = Eigen::MatrixXd::Zero(n, n);
  using namespace err;

  // Position (docs/ins-error-model.md, sec. 2).
  Matrix3d Fpp = Matrix3d::Zero();
  Fpp(0, 0) = -vd / rm;
  Fpp(0, 2) = vn / rm;
  Fpp(1, 0) = ve * tl / rm - ve * dN / (rn * rm);
  Fpp(1, 1) = vn * dN / (rn * rm) - vd / rn - vn * tl / rm;
  Fpp(1, 2) = ve / rn;
  F.block<3, 3>(kPos, kPos) = Fpp;
  F.block<3, 3>(kPos, kVel) = Matrix3d::Identity();

  // Velocity (sec. 3): d(dv)/dt = -[f_n]x phi + R d f + d g
  //                    - [2 w_ie + w_en]x dv + [v]x (2 d w_ie + d w_en).
  double dg_dlat = 0.0, dg_dh = 0.0;
  NormalGravityDerivatives(lat, h, &dg_dlat, &dg_dh);
  Matrix3d dg_dp = Matrix3d::Zero();
  dg_dp.row(2) = dg_dlat * dlat_dp + dg_dh * dh_dp;
  const Matrix3d Sv = Skew<double>(v);
  F.block<3, 3>(kVel, kPos) = dg_dp + Sv * (2.0 * dwie_dp + dwen_dp);
  F.block<3, 3>(kVel, kVel) = -Skew<double>(2.0 * w_ie + w_en) + Sv * dwen_dv;
  F.block<3, 3>(kVel, kAtt) = -Skew<double>(f_n);

  // Attitude (sec. 4): d(phi)/dt = -[w_in]x phi + R d omega_ib - d w_in.
  F.block<3, 3>(kAtt, kPos) = -(dwie_dp + dwen_dp);
  F.block<3, 3>(kAtt, kVel) = -dwen_dv;
  F.block<3, 3>(kAtt, kAtt) = -Skew<double>(w_in);

  // Sensor errors (sec. 5): d omega = -D_g (dbg + w_g) - D_g diag(omega) dsg with
  // D_g = diag(1 / (1 + sg)), likewise for the accelerometers.
  const Vector3d Dg = (Vector3d::Ones() + x.imu.sg).cwiseInverse();
  const Vector3d Da = (Vector3d::Ones() + x.imu.sa).cwiseInverse();
  const Matrix3d RDg = R * Dg.asDiagonal();
  const Matrix3d RDa = R * Da.asDiagonal();
  F.block<3, 3>(kAtt, kBg) = -RDg;
  F.block<3, 3>(kVel, kBa) = -RDa;
  const double inv_tau = InverseTau(noise.correlation_time_s);
  F.block<3, 3>(kBg, kBg) = -inv_tau * Matrix3d::Identity();
  F.block<3, 3>(kBa, kBa) = -inv_tau * Matrix3d::Identity();
  if (n == kSize21) {
    F.block<3, 3>(kAtt, kSg) = -RDg * omega_ib_b_radps.asDiagonal();
    F.block<3, 3>(kVel, kSa) = -RDa * f_b_mps2.asDiagonal();
    F.block<3, 3>(kSg, kSg) = -inv_tau * Matrix3d::Identity();
    F.block<3, 3>(kSa, kSa) = -inv_tau * Matrix3d::Identity();
  }
  return F;
}

Eigen::MatrixXd ErrorDynamicsG(const InsState& x, int n) {
  CheckSize(n, "ErrorDynamicsG");
  using namespace err;
  const Eigen::Matrix3d R = x.nav.q_n_b.normalized().toRotationMatrix();
  const Eigen::Vector3d Dg = (Eigen::Vector3d::Ones() + x.imu.sg).cwiseInverse();
  const Eigen::Vector3d Da = (Eigen::Vector3d::Ones() + x.imu.sa).cwiseInverse();
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(n, n);
  // w: [gyro noise, accel noise, bg driving, ba driving, (sg driving, sa driving)]
  G.block<3, 3>(kAtt, 0) = -R * Dg.asDiagonal();
  G.block<3, 3>(kVel, 3) = -R * Da.asDiagonal();
  G.block(kBg, 6, n - kBg, n - 6).setIdentity();
  return G;
}

Eigen::VectorXd ErrorDynamicsQc(const ImuNoise& noise, int n) {
  CheckSize(n, "ErrorDynamicsQc");
  const double inv_tau = InverseTau(noise.correlation_time_s);
  auto gm = [inv_tau](double sigma) { return 2.0 * sigma * sigma * inv_tau; };
  Eigen::VectorXd q = Eigen::VectorXd::Zero(n);  // entries past the noise inputs stay 0
  q.segment<3>(0).setConstant(noise.gyro_arw_rad_per_sqrt_s * noise.gyro_arw_rad_per_sqrt_s);
  q.segment<3>(3).setConstant(noise.accel_vrw_mps_per_sqrt_s * noise.accel_vrw_mps_per_sqrt_s);
  q.segment<3>(6).setConstant(gm(noise.gyro_bias_std_radps));
  q.segment<3>(9).setConstant(gm(noise.accel_bias_std_mps2));
  if (n == err::kSize21) {
    q.segment<3>(12).setConstant(gm(noise.gyro_scale_std));
    q.segment<3>(15).setConstant(gm(noise.accel_scale_std));
  }
  return q;
}

void DiscreteErrorDynamics(const InsState& x, const Eigen::Vector3d& f_b_mps2,
                           const Eigen::Vector3d& omega_ib_b_radps, const ImuNoise& noise,
                           int n, double dt_s, Eigen::MatrixXd* Phi, Eigen::MatrixXd* Qd) {
  if (!(dt_s >= 0.0) || !std::isfinite(dt_s)) {
    throw std::invalid_argument("DiscreteErrorDynamics: dt_s = " + std::to_string(dt_s) +
                                " is not a finite non-negative interval");
  }
  const Eigen::MatrixXd Fdt = ErrorDynamicsF(x, f_b_mps2, omega_ib_b_radps, noise, n) * dt_s;
  Eigen::MatrixXd phi = Fdt + 0.5 * Fdt * Fdt;
  phi.diagonal().array() += 1.0;
  if (Qd) {
    const Eigen::MatrixXd G = ErrorDynamicsG(x, n);
    const Eigen::MatrixXd GQG = G * ErrorDynamicsQc(noise, n).asDiagonal() * G.transpose();
    Eigen::MatrixXd q = 0.5 * dt_s * (phi * GQG * phi.transpose() + GQG);
    *Qd = 0.5 * (q + q.transpose());
  }
  if (Phi) *Phi = std::move(phi);
}

void PropagateCovariance(const InsState& x, const Eigen::Vector3d& f_b_mps2,
                         const Eigen::Vector3d& omega_ib_b_radps, const ImuNoise& noise, double dt_s,
                         Eigen::MatrixXd* P, Eigen::MatrixXd* phi_acc, const Eigen::VectorXd& aux_psd) {
  const int total = static_cast<int>(P->rows());
  const int n = total - static_cast<int>(aux_psd.size());
  if ((n != err::kSize15 && n != err::kSize21) || P->cols() != total ||
      (phi_acc != nullptr && (phi_acc->rows() != total || phi_acc->cols() != total))) {
    throw std::invalid_argument(
        "PropagateCovariance: P (and phi_acc) must be 15 x 15 or 21 x 21 plus the auxiliary states");
  }
  if (!(dt_s >= 0.0) || !std::isfinite(dt_s)) {
    throw std::invalid_argument("PropagateCovariance: dt_s must be finite and non-negative");
  }
  const Eigen::MatrixXd F = ErrorDynamicsF(x, f_b_mps2, omega_ib_b_radps, noise, n);
  const Eigen::MatrixXd G = ErrorDynamicsG(x, n);
  const Eigen::VectorXd qc = ErrorDynamicsQc(noise, n);
  if (n == err::kSize15) {
    PropagateBlocks<6>(F, G, qc, dt_s, aux_psd, P, phi_acc);
  } else {
    PropagateBlocks<12>(F, G, qc, dt_s, aux_psd, P, phi_acc);
  }
}

InsState ApplyCorrection(const InsState& x, const Eigen::VectorXd& dx) {
  const int n = static_cast<int>(dx.size());
  CheckSize(n, "ApplyCorrection");
  using namespace err;
  InsState y = x;
  const double p[3] = {x.nav.lat_rad, x.nav.lon_rad, x.nav.h_m};
  const Eigen::Vector3d dp = dx.segment<3>(kPos);
  double py[3];
  PositionPlus<double>(p, dp.data(), py);
  y.nav.lat_rad = py[0];
  y.nav.lon_rad = py[1];
  y.nav.h_m = py[2];
  y.nav.v_n_mps += dx.segment<3>(kVel);
  y.nav.q_n_b = ApplyAttitudeError<double>(dx.segment<3>(kAtt), x.nav.q_n_b);
  y.imu.bg_radps += dx.segment<3>(kBg);
  y.imu.ba_mps2 += dx.segment<3>(kBa);
  if (n == kSize21) {
    y.imu.sg += dx.segment<3>(kSg);
    y.imu.sa += dx.segment<3>(kSa);
  }
  return y;
}

Eigen::VectorXd StateDifference(const InsState& y, const InsState& x, int n) {
  CheckSize(n, "StateDifference");
  using namespace err;
  Eigen::VectorXd dx(n);
  const double px[3] = {x.nav.lat_rad, x.nav.lon_rad, x.nav.h_m};
  const double py[3] = {y.nav.lat_rad, y.nav.lon_rad, y.nav.h_m};
  double dp[3];
  PositionMinus<double>(py, px, dp);
  dx.segment<3>(kPos) = Eigen::Vector3d(dp[0], dp[1], dp[2]);
  dx.segment<3>(kVel) = y.nav.v_n_mps - x.nav.v_n_mps;
  dx.segment<3>(kAtt) = AttitudeError<double>(y.nav.q_n_b, x.nav.q_n_b);
  dx.segment<3>(kBg) = y.imu.bg_radps - x.imu.bg_radps;
  dx.segment<3>(kBa) = y.imu.ba_mps2 - x.imu.ba_mps2;
  if (n == kSize21) {
    dx.segment<3>(kSg) = y.imu.sg - x.imu.sg;
    dx.segment<3>(kSa) = y.imu.sa - x.imu.sa;
  }
  return dx;
}

}  // namespace navtwin::ins
