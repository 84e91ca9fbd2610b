// The batch twin of transfer alignment (issue 6): one Ceres problem over the whole record.
// Unknowns: slave navigation states (position, velocity, attitude R_n_s) every
// config.batch_state_interval_s at master records, the slave IMU biases (constant), the
// misalignment R_b_s (AttitudeManifold) and the delay tau (1, continuous). Residuals:
// IMU preintegration between consecutive states (factors/imu_preintegration.h), and per
// state, with the master record whose DATA time (tag - tau) is nearest the state (so the
// series carries over at most half a record interval, not over tau; re-selected after
// each solve at the new tau), the attitude and velocity matching residuals of
// problems/transfer_alignment/delay_model.h (second order, master derivatives kCentral; the delay enters through the
// compensation series, which is differentiable in tau) whitened by the master noise,
// plus bias priors. The initial values come from a filter run (RunMethod: the history filter). Standard deviations
// of the misalignment and the delay from ceres::Covariance. The matching residual
// functor lives in problems/transfer_alignment/transfer_match.h (AutoDiff; checked against central
// differences).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "problems/transfer_alignment/config.h"
#include "problems/transfer_alignment/filter.h"
#include "problems/transfer_alignment/inputs.h"

namespace navtwin::transfer {

struct TransferBatchSolution {
  Eigen::Quaterniond misalignment = Eigen::Quaterniond::Identity();  ///< R_b_s
  Eigen::Vector3d misalignment_sigma_rad = Eigen::Vector3d::Zero();  ///< tangent (master body) axes
  double delay_s = 0.0;
  double delay_sigma_s = 0.0;
  /// Joint covariance of [mu (3, tangent), tau].
  Eigen::Matrix4d misalignment_delay_covariance = Eigen::Matrix4d::Zero();
  Eigen::Vector3d gyro_bias_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias_mps2 = Eigen::Vector3d::Zero();
  /// The slave triads' scale factors (dimensionless) and axis misalignments (rad, entries
  /// 01, 02, 10, 12, 20, 21 of the error matrix), with their sigma (0 when not estimated).
  Eigen::Vector3d gyro_scale_factor = Eigen::Vector3d::Zero(), accel_scale_factor = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 6, 1> gyro_axis_misalignment_rad = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 1> accel_axis_misalignment_rad = Eigen::Matrix<double, 6, 1>::Zero();
  /// sigma of the instrument errors, in filter_model.h's istate layout (per triad: scale
  /// factors, misalignments, bias; gyro, then accelerometer).
  Eigen::Matrix<double, kInstrumentStates, 1> instrument_sigma = Eigen::Matrix<double, kInstrumentStates, 1>::Zero();
  /// The instrument errors the record does not determine, named as TriadParameterName
  /// (core/imu_error_model.h) gives them ("accel.scale_factor.x", ...): their posterior
  /// sigma is above 0.9 of the prior's.
  std::vector<std::string> instrument_not_observable;
  std::vector<NavState> states;  ///< the smoothed slave states (attitude R_n_s)
  int iterations = 0;
  double final_cost = 0.0;
  double run_time_s = 0.0;
};

/// Solves the batch, starting from `start` (RunMethod: the history filter run on the same
/// inputs). Throws std::runtime_error if Ceres fails or the covariance is rank-deficient.
TransferBatchSolution SolveTransferBatch(const TransferInputs& inputs, const TransferConfig& config,
                                         const TransferFilterRun& start);

}  // namespace navtwin::transfer
