// Linearised INS error dynamics in the error-state layout of ins_state.h (errors TRUE
// MINUS ESTIMATE, NED metres for position, R_true = Exp(phi) R_est for attitude) and the
// correction / difference maps between InsState and that error state. The derivation,
// with every sign checked against the mechanization (core/strapdown.h) by the tests, is
// in docs/ins-error-model.md.
#pragma once

#include <Eigen/Core>

#include "problems/ins/imu_noise.h"
#include "problems/ins/ins_state.h"

namespace navtwin::ins {

/// Continuous-time error dynamics d(dx)/dt = F dx + G w at the nominal state `x`, for the
/// bias-corrected specific force f_b_mps2 and angular rate omega_ib_b_radps (body axes),
/// n = 15 or 21 (ins_state.h layout). w = [gyro white noise(3), accel white noise(3),
/// gyro bias driving(3), accel bias driving(3), (sg driving(3), sa driving(3))].
/// Throws std::invalid_argument unless n is 15 or 21.
Eigen::MatrixXd ErrorDynamicsF(const InsState& x, const Eigen::Vector3d& f_b_mps2,
                               const Eigen::Vector3d& omega_ib_b_radps, const ImuNoise& noise,
                               int n);

/// The noise input matrix G (n x n) of the model above, w ordered as documented there.
Eigen::MatrixXd ErrorDynamicsG(const InsState& x, int n);

/// The continuous white-noise PSD diag Qc (n entries) of w: ARW^2, VRW^2 (per axis), then
/// 2 sigma^2 / tau for each Gauss-Markov process (0 when tau is infinite).
Eigen::VectorXd ErrorDynamicsQc(const ImuNoise& noise, int n);

/// Discrete transition and process noise over dt_s (second-order Phi = I + F dt + (F dt)^2/2,
/// Qd = (Phi G Qc G^T Phi^T + G Qc G^T) dt / 2, Qc from ARW, VRW and the Gauss-Markov
/// steady-state stds 2 sigma^2 / tau).
void DiscreteErrorDynamics(const InsState& x, const Eigen::Vector3d& f_b_mps2,
                           const Eigen::Vector3d& omega_ib_b_radps, const ImuNoise& noise,
                           int n, double dt_s, Eigen::MatrixXd* Phi, Eigen::MatrixXd* Qd);

/// Covariance propagation over one covariance group: P <- Phi P Phi^T + Qd with Phi and Qd
/// as DiscreteErrorDynamics defines them, Phi = I + F dt + (F dt)^2 / 2,
/// Qd = (Phi G Qc G^T Phi^T + G Qc G^T) dt / 2, F, G, Qc from ErrorDynamicsF/G/Qc at x, but
/// computed in fixed-size blocks that use the model's structure: with the error state split
/// into navigation (pos, vel, att: 9) and IMU errors (6 or 12), F = [[Fnn, Fns], [0, Fss]]
/// (IMU errors are driven by themselves only) and G Qc G^T = blockdiag(Qn, Qs) (white
/// sensor noise into the navigation rows, the bias driving noise into the IMU-error rows;
/// G's IMU-error block is I). About 10 times faster than the dense 15 x 15 products; the
/// tests check it against DiscreteErrorDynamics and ErrorStateKalmanFilter::Predict.
/// Auxiliary states of the aiding sources (aux_psd.size() of them, appended after the 15 or
/// 21 INS states) are random walks: transition I, process noise aux_psd dt, and their
/// correlations with the INS states follow the INS transition. When phi_acc is not null,
/// *phi_acc <- Phi * phi_acc (phi_acc must be block upper triangular in the same split, as
/// every product of such transitions is). P->rows() = 15 or 21, plus aux_psd.size().
void PropagateCovariance(const InsState& x, const Eigen::Vector3d& f_b_mps2,
                         const Eigen::Vector3d& omega_ib_b_radps, const ImuNoise& noise, double dt_s,
                         Eigen::MatrixXd* P, Eigen::MatrixXd* phi_acc,
                         const Eigen::VectorXd& aux_psd = Eigen::VectorXd());

/// Applies an error-state correction dx (true minus estimate, ins_state.h layout, 15 or 21)
/// to a nominal state: position via the position manifold's Plus, velocity +, attitude
/// q <- Exp(phi) q, biases +, scale factors + (ignored/unchanged for n = 15).
InsState ApplyCorrection(const InsState& x, const Eigen::VectorXd& dx);

/// The inverse: dx with ApplyCorrection(x, dx) = y (n = 15 or 21).
Eigen::VectorXd StateDifference(const InsState& y, const InsState& x, int n);

}  // namespace navtwin::ins
