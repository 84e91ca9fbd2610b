// Transfer alignment by delayed-state fusion (`--method history`): the master record
// tagged t carries the master's state at t - tau; instead of carrying the master forward
// over tau with a Taylor series (filter.h, the seed's order 1 and 2), the filter matches
// the record against the slave's own state at t - tau, taken from a short history of the
// slave, and carries the correction to the present through the cross-covariances of
// stochastic clones (S. I. Roumeliotis, J. W. Burdick, "Stochastic cloning: a generalized
// framework for processing relative state measurements", ICRA 2002).
// docs/transfer-alignment.md, "Delayed-state fusion", has the derivation.
//
// State: the 10 error states of filter_model.h (dv, phi of the slave now, mu, dtau), the
// slave triads' scale factors, axis misalignments and biases (24, filter_model.h's
// instrument states; random constants with the batch's priors from the configuration;
// their estimates correct every sample before the strapdown) and, per clone j, the slave's [dv, phi] at the clone's time
// c_j (6 each). A clone is taken at the start and after an update when the newest is
// kCloneSpacing_s old (at a record's tag); clones older than the
// history the delay needs (|tau| + 4 sigma_tau + a margin, at most
// config.history_window_s) are dropped. Clones and instrument errors are constants; the
// present's errors propagate with filter_model.h's transition and process noise, applied
// to P once per update as the product of the transitions since the last one.
//
// Measurement at record k (tag t, data time s = t - tau): the residuals of delay_model.h
// with no carry (delay 0), the master's attitude and velocity at its data time against the
// slave's at s:
//   r = [v_s(s) - v_m - R_n_b (omega x l);  Log(R_n_s(s) (R_n_b M)^T)],
// the slave's nominal state at s interpolated between its stored IMU epochs (linear in
// velocity, geodesic in attitude), its error interpolated linearly between the two error
// nodes around s (clones, or the present after the newest clone). The delay moves s:
// dr/dtau comes from the slave's own motion around s (its acceleration and body rate), as
// in the batch. Iterated update (relinearised at the new tau and errors); feedback into
// the present, the misalignment, the delay, and the stored history.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "problems/transfer_alignment/config.h"
#include "problems/transfer_alignment/delay_model.h"
#include "problems/transfer_alignment/filter.h"
#include "problems/transfer_alignment/inputs.h"

namespace navtwin::transfer {

/// The slave's nominal state at one stored epoch.
struct SlaveNode {
  double t_s = 0.0;
  Eigen::Quaterniond q_n_s = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_n_mps = Eigen::Vector3d::Zero();
};

/// The slave around a record's data time s: nominal epochs n0, n1 (n0.t_s < n1.t_s, normally
/// n0.t_s <= s <= n1.t_s; outside, the segment is extrapolated) and error nodes at
/// c0_s < c1_s with error estimates e = [dv_n (3), phi_n (3)].
struct HistoryBracket {
  SlaveNode n0, n1;
  double c0_s = 0.0, c1_s = 1.0;
  Eigen::Matrix<double, 6, 1> e0 = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> e1 = Eigen::Matrix<double, 6, 1>::Zero();
};

/// Columns of the history Jacobian: e0 (6), e1 (6), mu (3), dtau (1).
constexpr int kHistoryColumns = 16;

/// The measurement of the header comment at s = master.tag_s - tau_s, misalignment R_b_s:
/// r (velocity m/s, attitude rad) and H = dr/d[e0, e1, mu, dtau] (analytic; checked against
/// central differences in the tests).
void HistoryMatchResidualAndJacobian(const HistoryBracket& b, const Eigen::Matrix3d& R_b_s,
                                     const MasterKinematics& master, double tau_s,
                                     const Eigen::Vector3d& lever_arm_b_m, Eigen::Matrix<double, 6, 1>* r,
                                     Eigen::Matrix<double, 6, kHistoryColumns>* H);

/// Runs the filter (ValidateInputs first). One epoch per master record in the slave span;
/// records whose data time lies outside the kept history are not used
/// (TransferFilterRun::records_outside_history). Throws as RunTransferFilter.
TransferFilterRun RunHistoryFilter(const TransferInputs& inputs, const TransferConfig& config);

}  // namespace navtwin::transfer
