// Linearised INS error dynamics in the error-state layout of ins_state.h (errors TRUE
// MINUS ESTIMATE, NED metres for position, R_true = Exp(phi) R_est for attitude) and the
// correction / difference maps between InsState and that error state. The derivation,
// with every sign checked against the mechanization (core/strapdown.h) by the tests, is
// in docs/ins-error-model.md.
#pragma once

#include <Eigen/Core>

// ins_state.h first: config.h uses InsState without including it.
#include "problems/gnss_ins/ins_state.h"
// (keep this order)
#include "problems/gnss_ins/config.h"

namespace navtwin::gnss_ins {

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

/// Applies an error-state correction dx (true minus estimate, ins_state.h layout, 15 or 21)
/// to a nominal state: position via the position manifold's Plus, velocity +, attitude
/// q <- Exp(phi) q, biases +, scale factors + (ignored/unchanged for n = 15).
InsState ApplyCorrection(const InsState& x, const Eigen::VectorXd& dx);

/// The inverse: dx with ApplyCorrection(x, dx) = y (n = 15 or 21).
Eigen::VectorXd StateDifference(const InsState& y, const InsState& x, int n);

}  // namespace navtwin::gnss_ins
