// SolveTransferBatch (batch.h): the batch twin of the transfer-alignment filter. The model
// and the choices (which master record each state is matched with, why, the priors, the
// covariance) are described in docs/transfer-alignment-batch.md.
//
// Unknowns (tangent sizes): per state i at time t_i (master record tags, at least
// config.batch_state_interval_s apart, inside the filter's span and the slave IMU record)
//   pos_i {lat_rad, lon_rad, h_m} (PositionManifold, 3), v_n_i (3), q_n_s_i (AttitudeManifold, 3);
// once: gyro bias bg (3, rad/s), accelerometer bias ba (3, m/s^2) (random constants), the
// triads' scale factors sg, sa (3 each) and axis misalignments mg, ma (6 each, the
// off-diagonal entries of each triad's error matrix), the misalignment q_b_s
// (AttitudeManifold, 3, master body axes) and the delay tau (1, s).
// Residuals (whitened):
//   IMU preintegration i -> i+1 (factors/imu_preintegration.h, CreateImuInstrumentFactor;
//     slave ARW and VRW of the configuration), linearised at zero errors;
//   matching (problems/transfer_alignment/transfer_match.h = problems/transfer_alignment/delay_model.h, second order, kCentral master
//     derivatives) of state i with the record k whose data time tag_k - tau is nearest t_i:
//     the master carried over dt = tau - (tag_k - t_i), |dt| <= half a record interval;
//   priors: bg ~ N(0, gyro_bias), ba ~ N(0, accel_bias), sg, sa, mg, ma ~ N(0, their
//     configured sigma) (a zero sigma holds the block at zero), q_b_s ~ the misalignment guess
//     with misalignment_deg, tau ~ N(delay_initial_s, delay_s) (the filter's initial
//     uncertainty), pos_0 ~ the master's position at t_0 (plus the lever arm) with
//     kPositionPriorSigma_m (the position gauge: nothing else fixes it).
#include "problems/transfer_alignment/batch.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <ceres/autodiff_cost_function.h>
#include <ceres/problem.h>

#include "core/earth.h"
#include "core/imu_error_model.h"
#include "core/imu_split.h"
#include "core/rotation.h"
#include "core/units.h"
#include "factors/attitude_manifold.h"
#include "factors/attitude_prior.h"
#include "factors/imu_preintegration.h"
#include "factors/position_manifold.h"
#include "factors/state_prior.h"
#include "problems/transfer_alignment/transfer_match.h"
#include "problems/transfer_alignment/master.h"
#include "solvers/batch_driver.h"

namespace navtwin::transfer {
namespace {

constexpr double kTimeEps_s = 1e-6;
/// Prior on the first state's position around the master's (the lever arm added): a gauge
/// for the position, which no other residual fixes. 10 m covers the master's position
/// carried over half a record interval (200 m/s x 10 ms = 2 m) and errors of a lever arm
/// left out; the attitude and velocity do not notice it (gravity changes by 3e-6 m/s^2
/// per metre of height).
constexpr double kPositionPriorSigma_m = 10.0;
/// An instrument error whose posterior sigma is above this fraction of its prior's is named
/// as not observable from the record (the prior, not the data, sets it).
constexpr double kNotObservableRatio = 0.9;
/// Rounds of re-selecting the matched master records after a solve moved the delay.
constexpr int kMaxReselectRounds = 5;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

void CheckBatchConfig(const TransferConfig& c) {
  const auto positive = [](double x, const char* name) {
    if (!(x > 0.0) || !std::isfinite(x)) {
      throw std::invalid_argument(std::string("SolveTransferBatch: config ") + name + " must be positive and finite");
    }
  };
  positive(c.gyro_bias_radps, "gyro_bias_radps");
  positive(c.gyro_arw_rad_per_sqrt_s, "gyro_arw_rad_per_sqrt_s");
  positive(c.accel_bias_mps2, "accel_bias_mps2");
  positive(c.accel_vrw_mps_per_sqrt_s, "accel_vrw_mps_per_sqrt_s");
  positive(c.misalignment_rad, "misalignment_rad");
  positive(c.delay_s, "delay_s");
  positive(c.master_attitude_rad, "master_attitude_rad");
  positive(c.master_velocity_mps, "master_velocity_mps");
  positive(c.batch_state_interval_s, "batch_state_interval_s");
  if (!std::isfinite(c.delay_initial_s) || !c.lever_arm_b_m.allFinite()) {
    throw std::invalid_argument("SolveTransferBatch: config delay_initial_s and lever_arm_b_m must be finite");
  }
  for (const double sigma : {c.gyro_scale_factor, c.accel_scale_factor, c.gyro_axis_misalignment_rad,
                             c.accel_axis_misalignment_rad}) {
    if (!(sigma >= 0.0) || !std::isfinite(sigma)) {
      throw std::invalid_argument("SolveTransferBatch: config scale-factor and axis-misalignment sigmas must be >= 0");
    }
  }
  if (c.batch_max_iterations < 1) {
    throw std::invalid_argument("SolveTransferBatch: config batch_max_iterations must be at least 1");
  }
}

/// r = (x - mean) / sigma: the prior on the delay (AutoDiff).
struct ScalarPrior {
  double mean;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    r[0] = (x[0] - T(mean)) * T(inv_sigma);
    return true;
  }
};

struct State {
  double t_s = 0.0;
  std::array<double, 3> pos{};  ///< lat_rad, lon_rad, h_m
  std::array<double, 3> vel{};  ///< v_n_mps
  std::array<double, 4> q{};    ///< q_n_s x, y, z, w
  std::size_t record = MasterStream::npos;  ///< matched master record (npos: none)
  ceres::ResidualBlockId match = nullptr;
};

class TransferBatch {
 public:
  TransferBatch(const TransferInputs& in, const TransferConfig& cfg, const TransferFilterRun& start)
      : in_(in), cfg_(cfg), start_(start), master_(in.master, DerivativeMode::kCentral, in.master_path) {}

  TransferBatchSolution Run();

 private:
  void PlanStates();
  void Preintegrate();
  void BuildProblem();
  /// Matches every state with the record whose data time is nearest it at the current
  /// delay; re-adds the changed residuals. Returns how many states changed record.
  int SelectRecords();
  void Covariance(TransferBatchSolution* out);
  /// Priors on the biases, scale factors and axis misalignments (zero sigma: held at zero).
  void InstrumentPriors();
  /// The instrument blocks with a prior (estimated), with their sigma and offset into
  /// TransferBatchSolution::instrument_sigma.
  struct InstrumentBlock {
    double* x;
    int size;
    double sigma;
    int offset;         ///< istate offset (filter_model.h)
    const char* triad;  ///< "gyro" or "accel"
    int first_index;    ///< of its first entry in core/imu_error_model.h's triad block
  };
  std::vector<InstrumentBlock> InstrumentBlocks();

  const TransferInputs& in_;
  const TransferConfig& cfg_;
  const TransferFilterRun& start_;
  MasterStream master_;
  double record_interval_s_ = 0.0;  ///< median spacing of the master tags

  std::vector<State> states_;
  std::vector<std::shared_ptr<ImuPreintegration>> pre_;  ///< interval i: states i -> i + 1
  std::array<double, 3> bg_{}, ba_{};
  std::array<double, 3> sg_{}, sa_{};  ///< scale factors
  std::array<double, 6> mg_{}, ma_{};  ///< axis misalignments
  std::array<double, 4> q_b_s_{};
  double tau_s_ = 0.0;

  PositionManifold position_manifold_;
  AttitudeManifold attitude_manifold_;
  std::unique_ptr<ceres::Problem> problem_;
};

void TransferBatch::PlanStates() {
  const std::vector<TransferEpoch>& ep = start_.epochs;
  for (std::size_t i = 1; i < ep.size(); ++i) {
    if (!(ep[i].t_s > ep[i - 1].t_s)) {
      throw std::invalid_argument("SolveTransferBatch: the start run's epochs are not increasing in time");
    }
  }
  const ImuSample& first = in_.slave_imu.front();
  const double t_lo = std::max(ep.front().t_s, first.t_s - first.dt_s);
  const double t_hi = std::min(ep.back().t_s, in_.slave_imu.back().t_s);
  std::vector<double> spacing;
  for (std::size_t k = 1; k < master_.size(); ++k) spacing.push_back(master_.record(k).t_s - master_.record(k - 1).t_s);
  std::nth_element(spacing.begin(), spacing.begin() + spacing.size() / 2, spacing.end());
  record_interval_s_ = spacing[spacing.size() / 2];

  std::size_t e = 0;  // nearest filter epoch, advanced monotonically
  for (std::size_t k = 0; k < master_.size(); ++k) {
    const double t = master_.record(k).t_s;
    if (t < t_lo - kTimeEps_s || t > t_hi + kTimeEps_s) continue;
    if (!states_.empty() && t - states_.back().t_s < cfg_.batch_state_interval_s - kTimeEps_s) continue;
    while (e + 1 < ep.size() && std::abs(ep[e + 1].t_s - t) <= std::abs(ep[e].t_s - t)) ++e;
    // Initial values: the filter's slave state at the nearest epoch (its attitude is R_n_s).
    const NavState& s = ep[e].slave;
    State x;
    x.t_s = t;
    x.pos = {s.lat_rad, s.lon_rad, s.h_m};
    x.vel = {s.v_n_mps.x(), s.v_n_mps.y(), s.v_n_mps.z()};
    const Eigen::Quaterniond q = s.q_n_b.normalized();
    x.q = {q.x(), q.y(), q.z(), q.w()};
    states_.push_back(x);
  }
  if (states_.size() < 2) {
    throw std::invalid_argument("SolveTransferBatch: fewer than two master records inside the filter's span and "
                                "the slave IMU record");
  }
}

void TransferBatch::Preintegrate() {
  // Slave white noise: deg/sqrt(h) -> rad/sqrt(s), m/s/sqrt(h) -> m/s/sqrt(s).
  const double arw = cfg_.gyro_arw_rad_per_sqrt_s;
  const double vrw = cfg_.accel_vrw_mps_per_sqrt_s;
  const std::vector<ImuSample>& imu = in_.slave_imu;
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  // First sample ending after t_0; pieces of samples split at the state times.
  auto it = std::upper_bound(imu.begin(), imu.end(), states_.front().t_s + kTimeEps_s,
                             [](double t, const ImuSample& s) { return t < s.t_s; });
  bool have_piece = false;
  ImuSample piece;
  for (std::size_t i = 0; i + 1 < states_.size(); ++i) {
    const double t_end = states_[i + 1].t_s;
    auto pre = std::make_shared<ImuPreintegration>(zero, zero, arw, vrw);
    pre->TrackAxisMisalignment();
    while (true) {
      if (!have_piece) {
        if (it == imu.end()) throw std::logic_error("SolveTransferBatch: internal error, a state after the IMU record");
        piece = *it++;
        // Only the first sample can start before t_0; later ones continue the last piece.
        const double t0 = states_.front().t_s;
        if (piece.t_s - piece.dt_s < t0 - kTimeEps_s) piece = SplitImuSample(piece, t0).second;
        have_piece = true;
      }
      if (piece.t_s <= t_end + kTimeEps_s) {
        pre->Integrate(piece);
        have_piece = false;
        if (piece.t_s >= t_end - kTimeEps_s) break;
      } else {
        if (t_end > piece.t_s - piece.dt_s + kTimeEps_s) {
          const std::pair<ImuSample, ImuSample> parts = SplitImuSample(piece, t_end);
          pre->Integrate(parts.first);
          piece = parts.second;
        }
        break;
      }
    }
    pre_.push_back(pre);
  }
}

int TransferBatch::SelectRecords() {
  int changed = 0;
  for (State& s : states_) {
    // The record whose data time tag - tau is nearest t_i: tag nearest t_i + tau.
    const double want = s.t_s + tau_s_;
    std::size_t k = master_.LastAtOrBefore(want);
    if (k == MasterStream::npos) {
      k = 0;
    } else if (k + 1 < master_.size() &&
               std::abs(master_.record(k + 1).t_s - want) < std::abs(master_.record(k).t_s - want)) {
      ++k;
    }
    // None when the stream does not reach (the first and last ~tau of the record).
    if (std::abs(master_.record(k).t_s - want) > 0.75 * record_interval_s_) k = MasterStream::npos;
    if (k == s.record) continue;
    ++changed;
    if (s.match != nullptr) problem_->RemoveResidualBlock(s.match);
    s.match = nullptr;
    s.record = k;
    if (k == MasterStream::npos) continue;
    const double lead_s = master_.record(k).t_s - s.t_s;
    s.match = problem_->AddResidualBlock(
        TransferMatch::Create(master_.kinematics(k), lead_s, DelayOrder::kSecond, cfg_.lever_arm_b_m,
                              cfg_.master_attitude_rad, cfg_.master_velocity_mps),
        nullptr, {s.q.data(), s.vel.data(), q_b_s_.data(), &tau_s_});
  }
  return changed;
}

void TransferBatch::BuildProblem() {
  ceres::Problem::Options options;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.enable_fast_removal = true;  // re-selecting records replaces matching residuals
  problem_ = std::make_unique<ceres::Problem>(options);
  for (State& s : states_) {
    problem_->AddParameterBlock(s.pos.data(), 3, &position_manifold_);
    problem_->AddParameterBlock(s.vel.data(), 3);
    problem_->AddParameterBlock(s.q.data(), 4, &attitude_manifold_);
  }
  problem_->AddParameterBlock(bg_.data(), 3);
  problem_->AddParameterBlock(ba_.data(), 3);
  problem_->AddParameterBlock(sg_.data(), 3);
  problem_->AddParameterBlock(sa_.data(), 3);
  problem_->AddParameterBlock(mg_.data(), 6);
  problem_->AddParameterBlock(ma_.data(), 6);
  problem_->AddParameterBlock(q_b_s_.data(), 4, &attitude_manifold_);
  problem_->AddParameterBlock(&tau_s_, 1);

  for (std::size_t i = 0; i + 1 < states_.size(); ++i) {
    State& a = states_[i];
    State& b = states_[i + 1];
    problem_->AddResidualBlock(CreateImuInstrumentFactor(pre_[i]), nullptr,
                               {a.pos.data(), a.vel.data(), a.q.data(), bg_.data(), ba_.data(), sg_.data(), sa_.data(),
                                mg_.data(), ma_.data(), b.pos.data(), b.vel.data(), b.q.data()});
  }
  SelectRecords();

  // Priors (see the file comment).
  InstrumentPriors();
  const double mis_sigma_rad = cfg_.misalignment_rad;
  problem_->AddResidualBlock(
      AttitudePrior::Create(in_.misalignment_guess, Eigen::Matrix3d::Identity() / mis_sigma_rad), nullptr,
      q_b_s_.data());
  problem_->AddResidualBlock(
      new ceres::AutoDiffCostFunction<ScalarPrior, 1, 1>(new ScalarPrior{cfg_.delay_initial_s, 1.0 / cfg_.delay_s}),
      nullptr, &tau_s_);
  // Position gauge: the master's position at the first state's time (record matched to
  // it, or the nearest record), plus the lever arm.
  State& s0 = states_.front();
  std::size_t k0 = s0.record;
  if (k0 == MasterStream::npos) {
    k0 = master_.LastAtOrBefore(s0.t_s + tau_s_);
    if (k0 == MasterStream::npos) k0 = 0;
  }
  const NavState& m0 = master_.record(k0);
  const Eigen::Vector3d l_n = m0.q_n_b * cfg_.lever_arm_b_m;
  const double p_m0[3] = {m0.lat_rad, m0.lon_rad, m0.h_m};
  double p_s0[3];
  PositionPlus(p_m0, l_n.data(), p_s0);
  problem_->AddResidualBlock(PositionPrior::Create(Eigen::Vector3d(p_s0[0], p_s0[1], p_s0[2]), kPositionPriorSigma_m),
                             nullptr, s0.pos.data());
}

std::vector<TransferBatch::InstrumentBlock> TransferBatch::InstrumentBlocks() {
  const InstrumentPrior sigma = InstrumentPriorSigma(cfg_);
  return {{sg_.data(), 3, sigma(istate::kSg), istate::kSg, "gyro", 0},
          {mg_.data(), 6, sigma(istate::kMg), istate::kMg, "gyro", 3},
          {bg_.data(), 3, sigma(istate::kBg), istate::kBg, "gyro", 9},
          {sa_.data(), 3, sigma(istate::kSa), istate::kSa, "accel", 0},
          {ma_.data(), 6, sigma(istate::kMa), istate::kMa, "accel", 3},
          {ba_.data(), 3, sigma(istate::kBa), istate::kBa, "accel", 9}};
}

void TransferBatch::InstrumentPriors() {
  for (const InstrumentBlock& b : InstrumentBlocks()) {
    if (!(b.sigma > 0.0)) {
      problem_->SetParameterBlockConstant(b.x);
    } else if (b.size == 3) {
      problem_->AddResidualBlock(VectorPrior3::Create(Eigen::Vector3d::Zero(), b.sigma), nullptr, b.x);
    } else {
      problem_->AddResidualBlock(IsotropicPrior<6>::Create(Eigen::Matrix<double, 6, 1>::Zero(), b.sigma), nullptr, b.x);
    }
  }
}

void TransferBatch::Covariance(TransferBatchSolution* out) {
  // The joint covariance of the misalignment and the delay (4 tangent coordinates) by
  // ceres::Covariance (sparse QR of the whole Jacobian, then only these columns), with the
  // variance-inflation check of ComputeTangentCovariance.
  std::vector<const double*> blocks = {q_b_s_.data(), &tau_s_};
  std::vector<InstrumentBlock> estimated;
  for (const InstrumentBlock& b : InstrumentBlocks()) {
    if (b.sigma > 0.0) {
      blocks.push_back(b.x);
      estimated.push_back(b);
    }
  }
  const CovarianceResult c = ComputeTangentCovariance(*problem_, blocks);
  if (!c.covariance) {
    throw std::runtime_error("SolveTransferBatch: the misalignment and delay covariance is not computable: " +
                             c.message);
  }
  const Eigen::MatrixXd& P = *c.covariance;
  out->misalignment_sigma_rad = P.diagonal().head<3>().cwiseMax(0.0).cwiseSqrt();
  out->delay_sigma_s = std::sqrt(std::max(0.0, P(3, 3)));
  out->misalignment_delay_covariance = P.topLeftCorner<4, 4>();
  // The instrument errors: sigma, and those the record leaves at their prior.
  int row = 4;
  for (const InstrumentBlock& b : estimated) {
    for (int k = 0; k < b.size; ++k, ++row) {
      const double sigma = std::sqrt(std::max(0.0, P(row, row)));
      out->instrument_sigma[b.offset + k] = sigma;
      if (sigma > kNotObservableRatio * b.sigma) {
        out->instrument_not_observable.push_back(TriadParameterName(b.triad, b.first_index + k));
      }
    }
  }
}

TransferBatchSolution TransferBatch::Run() {
  const auto wall_start = std::chrono::steady_clock::now();
  CheckBatchConfig(cfg_);
  if (start_.epochs.empty()) throw std::invalid_argument("SolveTransferBatch: the start run has no epoch");
  const TransferEpoch& last = start_.epochs.back();
  if (!last.misalignment.coeffs().allFinite() || !std::isfinite(last.delay_s)) {
    throw std::invalid_argument("SolveTransferBatch: the start run's last misalignment or delay is not finite");
  }
  const Eigen::Quaterniond M0 = last.misalignment.normalized();
  q_b_s_ = {M0.x(), M0.y(), M0.z(), M0.w()};
  tau_s_ = last.delay_s;
  PlanStates();
  Preintegrate();
  BuildProblem();

  BatchOptions options;
  options.max_iterations = cfg_.batch_max_iterations;
  options.linear_solver = BatchOptions::LinearSolver::kSparseNormalCholesky;
  // |cost change| / cost: the cost at the optimum is at most half the number of residuals
  // (~1.5e4 on the preset; 247 with the default, conservative master sigmas), so 1e-6
  // stops when a step gains < 0.015 -- far below the 0.5 that one unit of chi-square is
  // worth; the tail that 1e-10 waits for moved the preset's cost by 0.3 in ten iterations.
  options.function_tolerance = 1e-6;
  options.progress = false;
  TransferBatchSolution out;
  BatchReport report = SolveBatch(*problem_, options, nullptr);
  out.iterations = report.iterations;
  // The delay moved past half a record interval for some states: match them with their
  // new nearest records and solve again.
  for (int round = 0; round < kMaxReselectRounds && std::isfinite(report.final_cost) && SelectRecords() > 0;
       ++round) {
    report = SolveBatch(*problem_, options, nullptr);
    out.iterations += report.iterations;
  }
  if (!std::isfinite(report.final_cost) || report.brief_report.find("FAILURE") != std::string::npos) {
    throw std::runtime_error("SolveTransferBatch: Ceres failed: " + report.brief_report);
  }
  out.final_cost = report.final_cost;

  const Eigen::Quaterniond M(q_b_s_[3], q_b_s_[0], q_b_s_[1], q_b_s_[2]);
  out.misalignment = M.normalized();
  out.delay_s = tau_s_;
  out.gyro_bias_radps = Eigen::Map<const Eigen::Vector3d>(bg_.data());
  out.accel_bias_mps2 = Eigen::Map<const Eigen::Vector3d>(ba_.data());
  out.gyro_scale_factor = Eigen::Map<const Eigen::Vector3d>(sg_.data());
  out.accel_scale_factor = Eigen::Map<const Eigen::Vector3d>(sa_.data());
  out.gyro_axis_misalignment_rad = Eigen::Map<const Eigen::Matrix<double, 6, 1>>(mg_.data());
  out.accel_axis_misalignment_rad = Eigen::Map<const Eigen::Matrix<double, 6, 1>>(ma_.data());
  const int week = start_.epochs.front().slave.gps_week;
  for (const State& s : states_) {
    NavState n;
    n.t_s = s.t_s;
    n.gps_week = week;
    n.lat_rad = s.pos[0];
    n.lon_rad = s.pos[1];
    n.h_m = s.pos[2];
    n.v_n_mps = Eigen::Vector3d(s.vel[0], s.vel[1], s.vel[2]);
    n.q_n_b = Eigen::Quaterniond(s.q[3], s.q[0], s.q[1], s.q[2]).normalized();
    out.states.push_back(n);
  }
  Covariance(&out);
  out.run_time_s = Seconds(wall_start);
  return out;
}

}  // namespace

TransferBatchSolution SolveTransferBatch(const TransferInputs& inputs, const TransferConfig& config,
                                         const TransferFilterRun& start) {
  ValidateInputs(inputs);
  TransferBatch batch(inputs, config, start);
  return batch.Run();
}

}  // namespace navtwin::transfer
