// The methods of issue 6 behind one entry point (run.h) and their scores.
//
// Score (the seed's "alignment error"): the slave's attitude estimate R_n_s_est against the
// truth R_n_s_true = R_n_b_true(t) R_b_s_true, as differences of ZYX Euler angles
//   e = wrap(Euler(R_n_s_est) - Euler(R_n_s_true))   (roll, pitch, heading; mrad)
// each wrapped to (-pi, pi] so that a heading near +-180 deg does not give a 2 pi error.
// R_n_b_true(t) is the truth slerped between the two records around t (the truth is at
// the IMU rate, so this is exact at its records and accurate to O(h^2 omega^2) between).
// RMS and max |e| are taken over the epochs at or after the initial time + settle_s.
#include "problems/transfer_alignment/run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

#include "core/io/json_writer.h"
#include "core/rotation.h"
#include "problems/ins/nav_error.h"

namespace navtwin::transfer {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kMatchDimension = 6.0;  // velocity and attitude matching: chi-square dof
// A mean NIS above this multiple of its expectation is reported: over thousands of records
// the mean of a consistent filter's NIS is within a few percent of 6 (or below, with the
// conservative master sigmas), so twice it is far outside its spread.
constexpr double kNisAlarm = 2.0;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// R_n_b of the truth at t (slerp between the records around t); empty outside its span.
std::optional<Eigen::Quaterniond> TruthAttitudeAt(const std::vector<NavState>& truth, double t_s) {
  const std::optional<NavState> s = NavAt(truth, t_s, 1e-9);
  if (!s) return std::nullopt;
  return s->q_n_b.normalized();  // Eigen's slerp takes the short way
}

Eigen::Vector3d EulerOf(const Eigen::Quaterniond& q) { return EulerFromDcm(Eigen::Matrix3d(q.toRotationMatrix())); }

/// The covariance of [mu, tau] and, with the true misalignment and delay, its NEES.
void ScoreConsistency(const TransferInputs& inputs, const Eigen::Quaterniond& misalignment_est, double delay_s,
                      const Eigen::Matrix4d& P, TransferResult* r) {
  r->misalignment_delay_covariance = P;
  if (!inputs.true_misalignment || !inputs.true_delay_s) return;
  Eigen::Vector4d e;
  e.head<3>() = LogSO3(Eigen::Matrix3d((*inputs.true_misalignment * misalignment_est.conjugate()).toRotationMatrix()));
  e(3) = *inputs.true_delay_s - delay_s;
  const Eigen::LDLT<Eigen::Matrix4d> ldlt(P);
  if (ldlt.info() == Eigen::Success && ldlt.isPositive()) r->nees_misalignment_delay = e.dot(ldlt.solve(e));
}

/// The filter's mean NIS after t_settled_s, and a note when it is far above its expectation.
void NisMean(const TransferFilterRun& run, double t_settled_s, TransferResult* r) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const TransferEpoch& e : run.epochs) {
    if (e.t_s < t_settled_s - 1e-9 || !std::isfinite(e.nis)) continue;
    sum += e.nis;
    ++n;
  }
  if (n == 0) return;
  r->nis_mean = sum / static_cast<double>(n);
  if (r->nis_mean > kNisAlarm * kMatchDimension) {
    std::ostringstream note;
    note << "; innovations inconsistent: mean NIS " << r->nis_mean << " over " << n << " records, expected "
         << kMatchDimension << " -- the sigma understate the errors";
    r->note += note.str();
  }
}

TransferResult RunFilterMethod(const TransferInputs& inputs, const TransferConfig& config, Method method) {
  TransferResult r;
  r.method = method;
  const auto start = std::chrono::steady_clock::now();
  const TransferFilterRun run =
      method == Method::kHistory
          ? RunHistoryFilter(inputs, config)
          : RunTransferFilter(inputs, config, method == Method::kOrder1 ? DelayOrder::kFirst : DelayOrder::kSecond);
  r.run_time_s = Seconds(start);
  if (run.epochs.empty()) throw std::runtime_error("the filter made no update (no master record inside the IMU data)");
  const TransferEpoch& last = run.epochs.back();
  std::vector<NavState> states;
  states.reserve(run.epochs.size());
  for (const TransferEpoch& e : run.epochs) {
    NavState s = e.slave;
    s.t_s = e.t_s;
    states.push_back(s);
  }
  // The filter's misalignment estimate changes along the run; each epoch is scored with the
  // R_n_s it had (the misalignment only enters the body-truth fallback, which uses the last).
  ScoreAttitude(inputs, states, last.misalignment, config.settle_s, &r);
  for (const TransferEpoch& e : run.epochs) {
    r.estimates.push_back({e.t_s, EulerOf(e.misalignment) * kRadToDeg, e.sigma.segment<3>(6) / kMrad_rad, e.delay_s,
                           e.sigma[9]});
  }
  NisMean(run, inputs.slave_initial.t_s + config.settle_s, &r);
  if (run.records_outside_history > 0) {
    r.note += "; " + std::to_string(run.records_outside_history) + " of " + std::to_string(run.epochs.size()) +
              " master records not used (data time outside the slave history kept)";
  }
  r.delay_s = last.delay_s;
  r.misalignment_deg = EulerOf(last.misalignment) * kRadToDeg;
  // The order filters' sigma carry the unmodelled instrument errors and the series'
  // truncation bounds (filter.h).
  const Eigen::Vector4d& bound = run.truncation_bound;
  const Eigen::Matrix4d instrument = InstrumentConsiderCovariance(run, config);
  Eigen::Matrix4d covariance = run.misalignment_delay_covariance + instrument;
  covariance.diagonal() += bound.cwiseAbs2();
  const Eigen::Vector4d sigma = covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  r.misalignment_sigma_mrad = sigma.head<3>() / kMrad_rad;
  r.delay_sigma_s = sigma(3);
  if (method != Method::kHistory) {
    std::ostringstream note;
    note << "; sigma include the slave's unmodelled instrument errors ("
         << (instrument.diagonal().head<3>().cwiseMax(0.0).cwiseSqrt() / kMrad_rad).transpose()
         << " mrad, " << std::sqrt(std::max(instrument(3, 3), 0.0)) * 1e3
         << " ms) and the compensation series' truncation bounds: misalignment "
         << (bound.head<3>() / kMrad_rad).transpose() << " mrad, delay " << bound(3) * 1e3
         << " ms (the covariance alone: " << (last.sigma.segment<3>(6) / kMrad_rad).transpose() << " mrad, "
         << last.sigma[9] * 1e3 << " ms)";
    r.note += note.str();
  }
  ScoreConsistency(inputs, last.misalignment, last.delay_s, covariance, &r);
  return r;
}

TransferResult RunBatchMethod(const TransferInputs& inputs, const TransferConfig& config) {
  TransferResult r;
  r.method = Method::kBatch;
  // The batch starts from the history filter's run (batch.h): its delay is right where the
  // Taylor-series filters' is tens of ms off (the batch from order 2 diverged at 500 ms on
  // the preset). Its time is part of the method.
  const auto start = std::chrono::steady_clock::now();
  const TransferFilterRun filter = RunHistoryFilter(inputs, config);
  const TransferBatchSolution sol = SolveTransferBatch(inputs, config, filter);
  r.run_time_s = Seconds(start);
  ScoreAttitude(inputs, sol.states, sol.misalignment, config.settle_s, &r);
  r.delay_s = sol.delay_s;
  r.delay_sigma_s = sol.delay_sigma_s;
  r.misalignment_deg = EulerOf(sol.misalignment) * kRadToDeg;
  r.misalignment_sigma_mrad = sol.misalignment_sigma_rad / kMrad_rad;
  ScoreConsistency(inputs, sol.misalignment, sol.delay_s, sol.misalignment_delay_covariance, &r);
  for (const NavState& state : sol.states) {
    r.estimates.push_back({state.t_s, r.misalignment_deg, r.misalignment_sigma_mrad, r.delay_s, r.delay_sigma_s});
  }
  std::ostringstream note;
  note << (r.note.empty() ? "" : "; ") << "batch: " << sol.states.size() << " states, " << sol.iterations
       << " iterations, final cost " << sol.final_cost;
  if (!sol.instrument_not_observable.empty()) {
    note << "; not observable (posterior sigma above 0.9 of the prior's):";
    for (std::size_t i = 0; i < sol.instrument_not_observable.size(); ++i) {
      note << (i == 0 ? " " : ", ") << sol.instrument_not_observable[i];
    }
  }
  r.note += note.str();
  return r;
}

}  // namespace

const char* MethodName(Method m) {
  switch (m) {
    case Method::kOrder1:
      return "order1";
    case Method::kOrder2:
      return "order2";
    case Method::kHistory:
      return "history";
    case Method::kBatch:
      return "batch";
  }
  return "unknown";
}

Method ParseMethod(const std::string& name) {
  for (const Method m : {Method::kOrder1, Method::kOrder2, Method::kHistory, Method::kBatch}) {
    if (name == MethodName(m)) return m;
  }
  throw std::invalid_argument("unknown method '" + name + "' (expected order1, order2, history or batch)");
}

void ScoreAttitude(const TransferInputs& inputs, const std::vector<NavState>& slave_states,
                   const Eigen::Quaterniond& misalignment_est, double settle_s, TransferResult* r) {
  r->t_s.clear();
  r->error_mrad.clear();
  r->rms_mrad.setConstant(kNaN);
  r->max_mrad.setConstant(kNaN);
  r->delay_true_s = inputs.true_delay_s ? *inputs.true_delay_s : kNaN;
  if (inputs.true_misalignment) {
    const Eigen::Quaterniond& m_true = *inputs.true_misalignment;
    r->misalignment_true_deg = EulerOf(m_true) * kRadToDeg;
    r->misalignment_error_mrad = LogSO3(Eigen::Matrix3d((m_true * misalignment_est.conjugate()).toRotationMatrix())).norm() / kMrad_rad;
  } else {
    r->misalignment_true_deg.setConstant(kNaN);
    r->misalignment_error_mrad = kNaN;
  }
  if (inputs.truth.empty()) {
    r->note = "no truth: attitude errors unknown";
    return;
  }
  const bool slave_truth = inputs.true_misalignment.has_value();
  r->note = slave_truth ? "scored against the slave truth R_n_b_true R_b_s_true"
                        : "true misalignment unknown: R_n_s_est R_b_s_est^T scored against the body truth";
  const double t_settled = inputs.slave_initial.t_s + settle_s;
  Eigen::Vector3d sum2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (const NavState& s : slave_states) {
    const std::optional<Eigen::Quaterniond> q_n_b_true = TruthAttitudeAt(inputs.truth, s.t_s);
    if (!q_n_b_true) continue;
    // Estimate and truth in the same axes: slave (R_n_s) or, without the true mounting, body.
    const Eigen::Quaterniond q_true = slave_truth ? *q_n_b_true * *inputs.true_misalignment : *q_n_b_true;
    const Eigen::Quaterniond q_est = slave_truth ? s.q_n_b : s.q_n_b * misalignment_est.conjugate();
    const Eigen::Vector3d d = EulerOf(q_est) - EulerOf(q_true);
    const Eigen::Vector3d e_mrad(WrapPi(d.x()) / kMrad_rad, WrapPi(d.y()) / kMrad_rad, WrapPi(d.z()) / kMrad_rad);
    r->t_s.push_back(s.t_s);
    r->error_mrad.push_back(e_mrad);
    if (s.t_s < t_settled - 1e-9) continue;
    sum2 += e_mrad.cwiseAbs2();
    max = max.cwiseMax(e_mrad.cwiseAbs());
    ++n;
  }
  if (n == 0) {
    r->note += "; no epoch with truth after settle_s";
    return;
  }
  r->rms_mrad = (sum2 / static_cast<double>(n)).cwiseSqrt();
  r->max_mrad = max;
}

TransferResult RunMethod(const TransferInputs& inputs, const TransferConfig& config, Method method) {
  ValidateInputs(inputs);
  return method == Method::kBatch ? RunBatchMethod(inputs, config) : RunFilterMethod(inputs, config, method);
}

std::string TransferResultJson(const TransferResult& r) {
  std::ostringstream out;
  JsonWriter w(out);
  const auto vec = [&](const std::string& key, const Eigen::Vector3d& v) {
    w.Key(key).BeginArray().Value(v.x()).Value(v.y()).Value(v.z()).EndArray();
  };
  w.BeginObject()
      .Field("method", MethodName(r.method))
      .Field("roll_rms_mrad", r.rms_mrad.x())
      .Field("pitch_rms_mrad", r.rms_mrad.y())
      .Field("heading_rms_mrad", r.rms_mrad.z())
      .Field("roll_max_mrad", r.max_mrad.x())
      .Field("pitch_max_mrad", r.max_mrad.y())
      .Field("heading_max_mrad", r.max_mrad.z())
      .Field("delay_est_s", r.delay_s)
      .Field("delay_sigma_s", r.delay_sigma_s);
  vec("misalignment_deg", r.misalignment_deg);
  w.Field("run_time_s", r.run_time_s);
  // Extras: what the estimates are compared with, and their standard deviations.
  w.Field("delay_true_s", r.delay_true_s).Field("delay_error_s", r.delay_s - r.delay_true_s);
  vec("misalignment_sigma_mrad", r.misalignment_sigma_mrad);
  vec("misalignment_true_deg", r.misalignment_true_deg);
  w.Field("misalignment_error_mrad", r.misalignment_error_mrad)
      .Field("nees_misalignment_delay", r.nees_misalignment_delay)
      .Field("nis_mean", r.nis_mean)
      .Field("epochs", r.t_s.size())
      .Field("note", r.note)
      .EndObject();
  return out.str();
}

std::string TransferResultTable(const TransferResult& r) {
  std::ostringstream out;
  char line[256];
  const auto cell = [](double x, const char* fmt) {
    if (std::isnan(x)) return std::string("-");
    char buf[32];
    std::snprintf(buf, sizeof buf, fmt, x);
    return std::string(buf);
  };
  out << "method " << MethodName(r.method) << ": slave attitude error (estimate - truth, ZYX Euler), mrad\n";
  std::snprintf(line, sizeof line, "  %-8s %10s %10s\n", "axis", "rms_mrad", "max_mrad");
  out << line;
  const char* axes[3] = {"roll", "pitch", "heading"};
  for (int i = 0; i < 3; ++i) {
    std::snprintf(line, sizeof line, "  %-8s %10s %10s\n", axes[i], cell(r.rms_mrad[i], "%.3f").c_str(),
                  cell(r.max_mrad[i], "%.3f").c_str());
    out << line;
  }
  std::snprintf(line, sizeof line, "  delay %s ms, sigma %s ms (true %s ms)\n", cell(r.delay_s * 1e3, "%.3f").c_str(),
                cell(r.delay_sigma_s * 1e3, "%.3f").c_str(), cell(r.delay_true_s * 1e3, "%.3f").c_str());
  out << line;
  std::snprintf(line, sizeof line,
                "  misalignment R_b_s (roll, pitch, yaw) [%s, %s, %s] deg, sigma [%s, %s, %s] mrad\n",
                cell(r.misalignment_deg.x(), "%.4f").c_str(), cell(r.misalignment_deg.y(), "%.4f").c_str(),
                cell(r.misalignment_deg.z(), "%.4f").c_str(), cell(r.misalignment_sigma_mrad.x(), "%.3f").c_str(),
                cell(r.misalignment_sigma_mrad.y(), "%.3f").c_str(), cell(r.misalignment_sigma_mrad.z(), "%.3f").c_str());
  out << line;
  std::snprintf(line, sizeof line, "  true misalignment [%s, %s, %s] deg, error %s mrad\n",
                cell(r.misalignment_true_deg.x(), "%.4f").c_str(), cell(r.misalignment_true_deg.y(), "%.4f").c_str(),
                cell(r.misalignment_true_deg.z(), "%.4f").c_str(), cell(r.misalignment_error_mrad, "%.3f").c_str());
  out << line;
  if (!std::isnan(r.nees_misalignment_delay)) {
    std::snprintf(line, sizeof line, "  NEES of (misalignment, delay) %.2f (chi-square, 4 degrees of freedom: 95 %% below 9.49)\n",
                  r.nees_misalignment_delay);
    out << line;
  }
  std::snprintf(line, sizeof line, "  run time %.3f s, %zu epochs with truth (RMS / max after settle_s)\n", r.run_time_s, r.t_s.size());
  out << line;
  if (!r.note.empty()) out << "  note: " << r.note << "\n";
  return out.str();
}

}  // namespace navtwin::transfer
