// One entry point for the methods of issue 6 and their scores: the slave attitude error
// against the truth (roll, pitch, heading, mrad, RMS and max after config.settle_s), the
// delay and misalignment estimates with sigma, JSON and table outputs.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "problems/transfer_alignment/batch.h"
#include "problems/transfer_alignment/config.h"
#include "problems/transfer_alignment/filter.h"
#include "problems/transfer_alignment/history_filter.h"
#include "problems/transfer_alignment/inputs.h"

namespace navtwin::transfer {

enum class Method { kOrder1, kOrder2, kHistory, kBatch };
const char* MethodName(Method m);  ///< "order1", "order2", "history", "batch"
Method ParseMethod(const std::string& name);  ///< throws std::invalid_argument listing the names

struct TransferResult {
  Method method = Method::kOrder2;
  /// Slave attitude error (estimate vs truth R_n_b_true R_b_s_true), as a rotation vector
  /// in the slave's own roll/pitch/heading sense: the ZYX Euler differences, mrad.
  /// NaN without truth. Over the epochs after settle_s.
  Eigen::Vector3d rms_mrad = Eigen::Vector3d::Constant(std::nan(""));
  Eigen::Vector3d max_mrad = Eigen::Vector3d::Constant(std::nan(""));
  double delay_s = 0.0;
  double delay_sigma_s = 0.0;
  Eigen::Vector3d misalignment_deg = Eigen::Vector3d::Zero();  ///< R_b_s as ZYX Euler (roll, pitch, yaw)
  Eigen::Vector3d misalignment_sigma_mrad = Eigen::Vector3d::Zero();
  double misalignment_error_mrad = std::nan("");  ///< |Log(R_true R_est^T)| when known
  /// Joint covariance of [mu (3, master body tangent, rad), tau (s)] of the final estimate.
  Eigen::Matrix4d misalignment_delay_covariance = Eigen::Matrix4d::Zero();
  /// e^T P^-1 e of e = [Log(M_true M_est^T), tau_true - tau_est] with the covariance above
  /// (chi-square with 4 degrees of freedom when the estimate is consistent); NaN without truth.
  double nees_misalignment_delay = std::nan("");
  /// Filters: the mean normalised innovation squared of the records after settle_s (6 when
  /// the filter's sigma are right; much larger: they understate its errors; needs no
  /// truth). NaN for the batch.
  double nis_mean = std::nan("");
  Eigen::Vector3d misalignment_true_deg = Eigen::Vector3d::Constant(std::nan(""));  ///< when known
  double delay_true_s = std::nan("");  ///< when known
  /// What the errors were scored against ("slave truth", "body truth: ..."), or why not.
  std::string note;
  double run_time_s = 0.0;
  /// Per epoch: t_s and the attitude error (mrad) for plots.
  std::vector<double> t_s;
  std::vector<Eigen::Vector3d> error_mrad;
  /// The misalignment and delay estimates with their sigma after each update (filters), or
  /// the batch's one estimate at each of its states, for plots of their convergence.
  struct Estimate {
    double t_s = 0.0;
    Eigen::Vector3d misalignment_deg = Eigen::Vector3d::Zero();  ///< ZYX Euler of R_b_s
    Eigen::Vector3d misalignment_sigma_mrad = Eigen::Vector3d::Zero();
    double delay_s = 0.0;
    double delay_sigma_s = 0.0;
  };
  std::vector<Estimate> estimates;
};

/// Fills r's attitude scores from slave states (t_s, q_n_b = R_n_s estimate): per state the
/// error Euler(R_n_s_est) - Euler(R_n_s_true) wrapped to (-pi, pi], mrad, with R_n_s_true =
/// R_n_b_truth(t) R_b_s_true (truth slerped at t; states outside the truth are skipped);
/// without the true misalignment R_n_s_est M_est^T is scored against R_n_b_truth. RMS / max
/// over the states at or after inputs.slave_initial.t_s + settle_s. Also sets
/// misalignment_true_deg, misalignment_error_mrad, delay_true_s and note.
void ScoreAttitude(const TransferInputs& inputs, const std::vector<NavState>& slave_states,
                   const Eigen::Quaterniond& misalignment_est, double settle_s, TransferResult* r);

TransferResult RunMethod(const TransferInputs& inputs, const TransferConfig& config, Method method);

/// `--format=json`: {"method":..,"roll_rms_mrad":..,"pitch_rms_mrad":..,"heading_rms_mrad":..,
/// "roll_max_mrad":..,"pitch_max_mrad":..,"heading_max_mrad":..,"delay_est_s":..,
/// "delay_sigma_s":..,"misalignment_deg":[..],"run_time_s":..} plus extra keys; NaN -> null.
std::string TransferResultJson(const TransferResult& r);
std::string TransferResultTable(const TransferResult& r);

/// The run folder of `transfer-align --out DIR` (docs/run-folder.md): DIR/summary.json
/// {"command":"transfer-align","methods":{"<method>":TransferResultJson,...}}, and per
/// method DIR/<method>/estimates.csv (t_s, misalignment roll/pitch/yaw deg and their sigma
/// mrad, delay and its sigma s) and, with a truth, DIR/<method>/attitude_errors.csv (t_s,
/// roll/pitch/heading error mrad). Every file is written whole and renamed into place at
/// the end (a failure leaves no file); the folders are created as needed.
void WriteTransferRunFolder(const std::string& dir, const std::vector<TransferResult>& results);

}  // namespace navtwin::transfer
