// The seed's transfer-alignment Kalman filter (seed 002, figure 1): 10 states
//   [0,3) dv_n_mps     slave velocity error (true minus estimate)
//   [3,6) phi_n_rad    slave attitude error, R_n_s_true = Exp(phi) R_n_s_est (core/rotation.h)
//   [6,9) mu_b_rad     misalignment residual, R_b_s_true = Exp(mu) R_b_s_est (master body axes)
//   [9]   dtau_s       delay residual, tau_true = tau_est + dtau
// with velocity matching (3) and attitude matching (3, rotation vector) against the
// delay-compensated master (problems/transfer_alignment/delay_model.h; order 1 or 2), at every master record. The
// slave INS is the project's strapdown (core/strapdown.h) on the raw slave IMU; position
// is taken from the master (transfer alignment matches velocity and attitude, and the
// position errors over a minute barely enter the velocity dynamics). Feedback after each
// update, as the seed: the velocity error into the slave velocity, the attitude error
// rotation vector as a quaternion multiplied into the slave quaternion, the misalignment
// and delay residuals accumulated into the estimates the matcher uses. Jacobians of the
// two residuals with respect to the states: analytic, checked against autodiff of the
// problems/transfer_alignment/delay_model.h residuals in the tests. Process noise: slave ARW / VRW, small random walks
// on misalignment and delay (flexure, clock wander; configurable).
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "problems/transfer_alignment/config.h"
#include "problems/transfer_alignment/delay_model.h"
#include "problems/transfer_alignment/filter_model.h"
#include "problems/transfer_alignment/inputs.h"

namespace navtwin::transfer {

/// The filter's estimate after one master record.
struct TransferEpoch {
  double t_s = 0.0;                  ///< record tag = slave time of the update
  NavState slave;                    ///< corrected slave INS state (attitude R_n_s)
  Eigen::Quaterniond misalignment = Eigen::Quaterniond::Identity();  ///< R_b_s estimate
  double delay_s = 0.0;
  Eigen::Matrix<double, kTransferStates, 1> sigma;  ///< sqrt diag P after the update
  Eigen::Matrix<double, 6, 1> innovation;           ///< [velocity m/s, attitude rad]
  /// Normalised innovation squared of the record at the prior estimate, y^T S^-1 y with
  /// S = H P H^T + R (chi-square with 6 degrees of freedom when the filter is consistent);
  /// NaN when the record was not used.
  double nis = std::nan("");
};

struct TransferFilterRun {
  DelayOrder order = DelayOrder::kSecond;
  std::vector<TransferEpoch> epochs;  ///< one per master record inside the slave IMU span
  /// History filter: records not used because their data time (tag - tau) lay outside the
  /// slave history kept (before the start, or older than config.history_window_s).
  std::size_t records_outside_history = 0;
  /// After the last update: the joint covariance of [mu (3), dtau].
  Eigen::Matrix4d misalignment_delay_covariance = Eigen::Matrix4d::Zero();
  /// Order filters: bounds of the misalignment's and the delay's bias by the compensation
  /// series' truncation, [mu_b_rad (3), tau_s], which the covariance does not hold. Each
  /// record's remainder r_k (the first neglected term, at the final delay) is not noise: on
  /// a manoeuvre it is in phase with the delay's own column (a sine's remainder
  /// -A w^3 tau^3 / 6 cos wt against H_tau = A w cos wt), so it biases the estimate alike at
  /// every record and the covariance, shrinking as 1/N, cannot cover it. A least-squares
  /// estimate of one parameter with residual remainders r_k is biased by sum h_k r_k / sum
  /// h_k^2 <= sqrt(sum |r_k|^2 / sum |h_k|^2) (Cauchy-Schwarz; h_k its column of H, all
  /// whitened): that bound per parameter. The first neglected term understates the remainder
  /// where the series does not converge (omega tau near 1); the innovations show it there.
  /// Zero for the history filter (no series).
  Eigen::Vector4d truncation_bound = Eigen::Vector4d::Zero();
  /// Order filters: the sensitivity of the final [mu (3), dtau] to the slave's instrument
  /// errors p (filter_model.h's 24: scale factors, axis misalignments, biases), which these
  /// filters do not estimate, through the filter's own transitions and gains — a consider
  /// analysis (B. D. Tapley, B. E. Schutz, G. H. Born, "Statistical Orbit Determination",
  /// 2004, section 6.3): an error p moves the estimate by about S p, so the covariance it
  /// leaves is S P_p S^T (InstrumentConsiderCovariance), which the reported sigma carry.
  /// Zero for the history filter (it estimates them).
  Eigen::Matrix<double, 4, kInstrumentStates> instrument_sensitivity =
      Eigen::Matrix<double, 4, kInstrumentStates>::Zero();
  double run_time_s = 0.0;
};

/// S P_p S^T of TransferFilterRun::instrument_sensitivity with the configuration's priors
/// (InstrumentPriorSigma): the covariance of [mu, dtau] the unmodelled instrument errors leave.
Eigen::Matrix4d InstrumentConsiderCovariance(const TransferFilterRun& run, const TransferConfig& config);

/// The matching residuals of problems/transfer_alignment/delay_model.h at the estimate, r = [VelocityMatchResidual;
/// AttitudeMatchResidual] (m/s, rad), and their analytic Jacobian H = dr/d(dx) with respect
/// to the 10 error states above (exact: it includes the SO(3) Jacobians of the residual's
/// Log and of the compensation's Exp; checked against autodiff in the tests). The filter's
/// innovation is y = -r ~ H dx.
void MatchResidualAndJacobian(const Eigen::Matrix3d& R_n_s, const Eigen::Vector3d& v_n_s_mps,
                              const Eigen::Matrix3d& R_b_s, const MasterKinematics& master, double tau_s,
                              DelayOrder order, const Eigen::Vector3d& lever_arm_b_m,
                              Eigen::Matrix<double, 6, 1>* r,
                              Eigen::Matrix<double, 6, kTransferStates>* H);

/// Runs the filter (ValidateInputs first; MasterStream with kCausal derivatives). Throws
/// InputError for bad inputs, std::invalid_argument for a bad configuration, and
/// std::runtime_error naming the time if the state becomes non-finite.
TransferFilterRun RunTransferFilter(const TransferInputs& inputs, const TransferConfig& config, DelayOrder order);

}  // namespace navtwin::transfer
