// The navigation filter's main loop (problems/gnss_ins/filter.h) over the registered aiding
// sources (problems/ins/aiding.h); the initial state comes from initial_state.cc.
#include "problems/gnss_ins/filter.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <ceres/cost_function.h>

#include "core/imu_split.h"
#include "core/io/input_error.h"
#include "core/rotation.h"
#include "core/strapdown.h"
#include "factors/attitude_manifold.h"
#include "factors/position_manifold.h"
#include "problems/gnss_ins/sources.h"
#include "problems/ins/error_dynamics.h"
#include "problems/ins/measurement_rules.h"
#include "solvers/eskf.h"
#include "solvers/linearize.h"
#include "solvers/rts.h"

namespace navtwin::gnss_ins {
namespace {

using ins::AidingSource;
using ins::StateBlock;

class NavigationFilter : public ins::FilterAccess {
 public:
  NavigationFilter(const Inputs& inputs, const GnssInsConfig& config, const FilterStart& start, bool run_rts,
                   FilterKnots knots, const std::function<void(const NavEpoch&)>& output,
                   std::ostream* progress)
      : in_(inputs),
        cfg_(config),
        n_ins_(config.filter.scale_factors ? err::kSize21 : err::kSize15),
        run_rts_(run_rts),
        keep_covariances_(knots == FilterKnots::kAllWithCovariances),
        keep_last_only_(knots == FilterKnots::kLast),
        output_(output),
        progress_(progress),
        start_(start),
        sources_(MakeSources(inputs, config)),
        strapdown_(start.state.nav),
        imu_(start.state.imu) {
    RegisterSources();
    kf_.emplace(InitialCovariance());
    P_ = kf_->P();
    phi_acc_ = Eigen::MatrixXd::Identity(n_, n_);
    epoch_dx_ = Eigen::VectorXd::Zero(n_);
    if (const ins::StillnessConfig* rule = ins::StillnessRule(sources_)) detector_.emplace(*rule);
  }

  FilterResult Run();

  // ins::FilterAccess
  const InsState& nominal() const override {
    nominal_ = InsState{strapdown_.state(), imu_};
    return nominal_;
  }
  double aux(int i) const override { return aux_[aux_begin_[current_] + i]; }
  const Eigen::Vector3d& omega_ib_b_radps() const override { return omega_ib_b_; }
  ins::ImuMotion motion() const override {
    return motion_.Get(std::max(P_(err::kAtt, err::kAtt), P_(err::kAtt + 1, err::kAtt + 1)));
  }
  double time_s() const override { return epoch_t_s_; }
  bool still() const override { return detector_ && detector_->Still(); }
  bool Update(std::unique_ptr<ceres::CostFunction> cost, const std::vector<StateBlock>& blocks,
              const std::string& key, const std::function<void(const Eigen::VectorXd&)>& check) override;
  void Count(const std::string& key, bool used) override {
    MeasurementCount& c = counts_[key];
    ++(used ? c.used : c.rejected);
    Record(key, 0, std::numeric_limits<double>::quiet_NaN(), !used);
  }
  void ResetPositionVelocity(const Eigen::Vector3d& dp_ned_m, const Eigen::Vector3d& dv_n_mps,
                             const Eigen::Vector3d& pos_var, const Eigen::Vector3d& vel_var,
                             const std::string& key) override;

 private:
  /// A row of the filter's measurement residuals at the current epoch (solution.h).
  void Record(const std::string& key, int dof, double nis, bool rejected) {
    measurement_residuals_.push_back({epoch_t_s_, key, dof, nis, rejected});
  }

  /// Count keys, auxiliary states and the sample cursors of the sources.
  void RegisterSources() {
    std::vector<double> aux_values;
    for (const auto& source : sources_) {
      for (const std::string& key : source->keys()) counts_[key];
      aux_begin_.push_back(static_cast<int>(aux_values.size()));
      for (const ins::AuxState& a : source->aux_states()) {
        aux_values.push_back(a.initial);
        aux_std0_.push_back(a.initial_std);
        aux_states_.push_back(a);
      }
    }
    aux_ = Eigen::Map<const Eigen::VectorXd>(aux_values.data(), static_cast<Eigen::Index>(aux_values.size()));
    aux_psd_ = Eigen::VectorXd::Zero(aux_.size());  // random constants
    n_ = n_ins_ + static_cast<int>(aux_.size());
    next_.assign(sources_.size(), 0);
  }

  Eigen::MatrixXd InitialCovariance() const {
    Eigen::VectorXd std(n_);
    std.head(n_ins_) = start_.std.size() == n_ins_ ? start_.std : InitialStdVector(cfg_, n_ins_);
    for (std::size_t i = 0; i < aux_std0_.size(); ++i) std[n_ins_ + static_cast<int>(i)] = aux_std0_[i];
    return std.array().square().matrix().asDiagonal();
  }

  InsState Nominal() const { return InsState{strapdown_.state(), imu_}; }

  /// Mechanizes one (piece of a) sample and adds it to the covariance group.
  void Propagate(const ImuSample& raw) {
    const ImuSample c = ins::CorrectImu(raw, imu_);
    const Eigen::Vector3d v_before_n_mps = strapdown_.state().v_n_mps;
    strapdown_.Update(c);
    motion_.Add(c, strapdown_.state().v_n_mps - v_before_n_mps);
    group_dtheta_ += c.dtheta_b_rad;
    group_dv_ += c.dv_b_mps;
    group_dt_ += c.dt_s;
    omega_ib_b_ = c.dtheta_b_rad / c.dt_s;
  }

  /// Propagates the covariance over the samples of the current group.
  void FlushGroup() {
    if (group_dt_ <= 0.0) return;
    // P <- Phi P Phi^T + Qd (DiscreteErrorDynamics' Phi and Qd, in blocks; error_dynamics.h).
    PropagateCovariance(Nominal(), group_dv_ / group_dt_, group_dtheta_ / group_dt_, cfg_.imu_noise, group_dt_,
                        &P_, run_rts_ ? &phi_acc_ : nullptr, aux_psd_);
    group_dtheta_.setZero();
    group_dv_.setZero();
    group_dt_ = 0.0;
  }

  void BeginEpoch() {
    if (in_epoch_) return;
    FlushGroup();
    P_prior_ = P_;
    epoch_dx_.setZero();
    in_epoch_ = true;
  }

  void EndEpoch(double t_s) {
    if (!in_epoch_) return;
    StoreKnot(t_s, true);
    in_epoch_ = false;
  }

  NavEpoch Epoch(const InsState& state, const Eigen::VectorXd& aux, const Eigen::MatrixXd& P) const {
    NavEpoch e;
    e.state = state;
    e.aux = aux;
    const Eigen::VectorXd sd = P.diagonal().cwiseMax(0.0).cwiseSqrt();
    e.std = sd.head(n_ins_);
    e.aux_std = sd.tail(n_ - n_ins_);
    return e;
  }

  /// A knot at t_s (the covariance must be current): the post-update state and std, and for
  /// the RTS the transition since the previous knot, P_prior, P_post, the feedback.
  void StoreKnot(double t_s, bool after_updates) {
    NavEpoch e = Epoch(Nominal(), aux_, P_);
    e.state.nav.t_s = t_s;
    if (keep_last_only_ && !epochs_.empty()) {
      epochs_.back() = std::move(e);
      ++knots_not_kept_;
    } else {
      epochs_.push_back(std::move(e));
    }
    if (keep_covariances_) filter_covariances_.push_back(P_);
    if (run_rts_) {
      RtsKnot k;
      k.Phi = phi_acc_;
      k.P_prior = after_updates ? P_prior_ : P_;
      k.P_post = P_;
      if (after_updates) k.dx_fed_back = epoch_dx_;
      knots_.push_back(std::move(k));
      phi_acc_.setIdentity();
    }
    last_knot_t_s_ = t_s;
  }

  /// Applies a fed-back correction (n_ entries) to the nominal state.
  void Correct(const Eigen::VectorXd& dx) {
    const InsState corrected = ins::ApplyCorrection(Nominal(), dx.head(n_ins_));
    strapdown_.SetState(corrected.nav);
    imu_ = corrected.imu;
    aux_ += dx.tail(n_ - n_ins_);
    epoch_dx_ += dx;
  }

  /// Source i's samples up to t_s (kExact, kNextEpoch) or its epoch rule (kEveryEpoch).
  void ProcessSource(std::size_t i, double t_s, bool imu_epoch) {
    AidingSource& source = *sources_[i];
    current_ = i;
    epoch_t_s_ = t_s;
    if (source.timing() == AidingSource::Timing::kEveryEpoch) {
      if (imu_epoch) source.FilterEpoch(*this);
      return;
    }
    const std::vector<double>& times = source.times();
    while (next_[i] < times.size() && times[next_[i]] <= t_s + ins::kSameEpoch_s) source.FilterUpdate(next_[i]++, *this);
  }

  /// Measurements at epoch t_s, source by source in registration order.
  void ProcessEpochMeasurements(double t_s, bool imu_epoch) {
    for (std::size_t i = 0; i < sources_.size(); ++i) ProcessSource(i, t_s, imu_epoch);
  }

  /// The source whose next exact-time sample comes first before `before_s` (-1: none).
  long NextExactSource(double before_s) const {
    long best = -1;
    double best_t = before_s;
    for (std::size_t i = 0; i < sources_.size(); ++i) {
      if (sources_[i]->timing() != AidingSource::Timing::kExact) continue;
      const std::vector<double>& times = sources_[i]->times();
      if (next_[i] < times.size() && times[next_[i]] < best_t) {
        best_t = times[next_[i]];
        best = static_cast<long>(i);
      }
    }
    return best;
  }

  /// Skips samples before the start (and at it unless the start allows them).
  void SkipMeasurementsBeforeStart(double t0_s) {
    const double limit = start_.use_measurements_at_start ? t0_s - ins::kSameEpoch_s : t0_s + ins::kSameEpoch_s;
    for (std::size_t i = 0; i < sources_.size(); ++i) {
      const std::vector<double>& times = sources_[i]->times();
      while (next_[i] < times.size() && times[next_[i]] < limit) ++next_[i];
      sources_[i]->BeginFilter(limit);
    }
  }

  /// The real-time state at every IMU epoch (the caller decimates for its files,
  /// OutputDecimator in densify.h), built in a reused epoch: no allocation per sample.
  void Output() {
    if (!output_) return;
    output_epoch_.state = Nominal();
    output_epoch_.aux = aux_;
    output_epoch_.std = P_.diagonal().head(n_ins_).cwiseMax(0.0).cwiseSqrt();
    output_epoch_.aux_std = P_.diagonal().tail(n_ - n_ins_).cwiseMax(0.0).cwiseSqrt();
    output_(output_epoch_);
  }

  /// About every 5 % of [progress_begin_s_, progress_end_s_].
  void Progress(double t_s) {
    if (progress_ == nullptr) return;
    const double fraction =
        progress_end_s_ > progress_begin_s_ ? (t_s - progress_begin_s_) / (progress_end_s_ - progress_begin_s_) : 1.0;
    const int step = static_cast<int>(std::min(20.0, std::floor(20.0 * fraction + 1e-9)));
    if (step <= progress_step_) return;
    progress_step_ = step;
    std::ostringstream line;
    line.precision(10);
    line << "filter: " << 5 * step << " % (t = " << t_s << " s)\n";
    *progress_ << line.str() << std::flush;
  }

  void FirstImuSample(ImuReader& imu, ImuSample* first) const;
  void ProcessImuSample(const ImuSample& sample, const ImuSample* next, double t0_s);
  FilterResult Result(std::chrono::steady_clock::time_point wall_start);

  const Inputs& in_;
  const GnssInsConfig& cfg_;
  const int n_ins_;  ///< 15 or 21
  int n_ = 0;        ///< n_ins_ plus the sources' auxiliary states
  const bool run_rts_;
  const bool keep_covariances_;
  const bool keep_last_only_;       ///< FilterKnots::kLast: epochs_ holds the newest knot
  std::size_t knots_not_kept_ = 0;
  const std::function<void(const NavEpoch&)>& output_;
  std::ostream* progress_;
  const FilterStart start_;
  ins::AidingSources sources_;
  Strapdown strapdown_;
  ImuErrors imu_;
  Eigen::VectorXd aux_;       ///< the sources' auxiliary states (nominal)
  Eigen::VectorXd aux_psd_;
  std::vector<double> aux_std0_;
  std::vector<ins::AuxState> aux_states_;
  std::vector<int> aux_begin_;        ///< per source: its first auxiliary state
  std::vector<std::size_t> next_;     ///< per source: its next sample
  std::size_t current_ = 0;           ///< the source being processed
  double epoch_t_s_ = 0.0;
  std::optional<ins::StillnessDetector> detector_;
  NavEpoch output_epoch_;
  mutable InsState nominal_;
  int progress_step_ = 0;
  /// The span Progress measures: the IMU record's, or up to the last GNSS epoch while a
  /// streamed record's end is not known.
  double progress_begin_s_ = 0.0, progress_end_s_ = 0.0;

  // Covariance group.
  Eigen::Vector3d group_dtheta_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d group_dv_ = Eigen::Vector3d::Zero();
  double group_dt_ = 0.0;
  Eigen::Vector3d omega_ib_b_ = Eigen::Vector3d::Zero();  ///< of the last (piece of a) sample
  ins::MotionWindow motion_{cfg_.imu_noise.gyro_arw_rad_per_sqrt_s, cfg_.imu_noise.accel_vrw_mps_per_sqrt_s};
  Eigen::MatrixXd P_;
  Eigen::MatrixXd phi_acc_;  ///< transition since the previous knot (RTS)
  std::optional<ErrorStateKalmanFilter> kf_;  ///< the update engine; P_ is propagated here

  // Update epoch and knots.
  bool in_epoch_ = false;
  Eigen::MatrixXd P_prior_;
  Eigen::VectorXd epoch_dx_;
  double last_knot_t_s_ = -INFINITY;
  std::vector<NavEpoch> epochs_;
  std::vector<Eigen::MatrixXd> filter_covariances_;
  std::vector<RtsKnot> knots_;
  std::map<std::string, MeasurementCount> counts_;
  std::map<std::string, InnovationStats> innovations_;
  std::vector<MeasurementResidual> measurement_residuals_;

  // Measurement models' scratch.
  PositionManifold position_manifold_;
  AttitudeManifold attitude_manifold_;
  Linearization lin_;
  std::vector<const double*> block_ptrs_;
  std::vector<const ceres::Manifold*> manifolds_;
  std::vector<int> columns_;
  Eigen::MatrixXd H_;
  Eigen::VectorXd y_;
};

bool NavigationFilter::Update(std::unique_ptr<ceres::CostFunction> cost, const std::vector<StateBlock>& blocks,
                              const std::string& key, const std::function<void(const Eigen::VectorXd&)>& check) {
  const NavState& s = strapdown_.state();
  const double pos[3] = {s.lat_rad, s.lon_rad, s.h_m};
  const double vel[3] = {s.v_n_mps.x(), s.v_n_mps.y(), s.v_n_mps.z()};
  const Eigen::Vector4d q = s.q_n_b.coeffs();
  block_ptrs_.clear();
  manifolds_.clear();
  columns_.clear();
  for (const StateBlock& b : blocks) {
    switch (b.kind) {
      case StateBlock::Kind::kPosition:
        block_ptrs_.push_back(pos);
        manifolds_.push_back(&position_manifold_);
        columns_.push_back(err::kPos);
        break;
      case StateBlock::Kind::kVelocity:
        block_ptrs_.push_back(vel);
        manifolds_.push_back(nullptr);
        columns_.push_back(err::kVel);
        break;
      case StateBlock::Kind::kAttitude:
        block_ptrs_.push_back(q.data());
        manifolds_.push_back(&attitude_manifold_);
        columns_.push_back(err::kAtt);
        break;
      case StateBlock::Kind::kAux: {
        const int index = aux_begin_[current_] + b.aux;
        block_ptrs_.push_back(aux_.data() + index);
        manifolds_.push_back(nullptr);
        columns_.push_back(n_ins_ + index);
        break;
      }
    }
  }
  Linearize(*cost, block_ptrs_, manifolds_, &lin_);
  if (check) check(lin_.residual);
  const int m = static_cast<int>(lin_.residual.size());
  H_.setZero(m, n_);
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    H_.middleCols(columns_[i], lin_.jacobians[i].cols()) = lin_.jacobians[i];
  }
  y_ = -lin_.residual;
  BeginEpoch();
  kf_->SetP(P_);
  const ErrorStateKalmanFilter::Update u = kf_->Correct(y_, H_, cfg_.filter.gate_probability);
  MeasurementCount& count = counts_[key];
  InnovationStats& stats = innovations_[key];
  ++stats.updates;
  stats.nis_capped += std::min(u.nis, u.gate);
  stats.log_det_s += u.log_det_s;
  Record(key, m, u.nis, !u.accepted);
  if (!u.accepted) {
    ++count.rejected;
    ++stats.rejected;
    return false;
  }
  ++count.used;
  stats.nis += u.nis;
  stats.dof += m;
  P_ = kf_->P();
  Correct(u.dx);
  return true;
}

void NavigationFilter::ResetPositionVelocity(const Eigen::Vector3d& dp_ned_m, const Eigen::Vector3d& dv_n_mps,
                                             const Eigen::Vector3d& pos_var, const Eigen::Vector3d& vel_var,
                                             const std::string& key) {
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(n_);
  dx.segment<3>(err::kPos) = dp_ned_m;
  dx.segment<3>(err::kVel) = dv_n_mps;
  BeginEpoch();
  P_.middleRows(err::kPos, 6).setZero();
  P_.middleCols(err::kPos, 6).setZero();
  P_.diagonal().segment<3>(err::kPos) = pos_var;
  P_.diagonal().segment<3>(err::kVel) = vel_var;
  const InsState corrected = ins::ApplyCorrection(Nominal(), dx.head(n_ins_));
  strapdown_.SetState(corrected.nav);
  epoch_dx_ += dx;
  ++counts_[key].used;
  Record(key, 0, std::numeric_limits<double>::quiet_NaN(), false);
}

/// The first sample of `imu` ending after the start (the one holding it).
void NavigationFilter::FirstImuSample(ImuReader& imu, ImuSample* first) const {
  const double t0 = start_.state.nav.t_s;
  double last_t_s = -INFINITY;
  while (imu.Next(first)) {
    if (first->t_s > t0 + ins::kSameEpoch_s) return;
    last_t_s = first->t_s;
  }
  std::ostringstream reason;
  reason.precision(12);
  reason << "the filter starts at t = " << t0 << " s, at or after the end of the IMU record (" << last_t_s << " s)";
  throw InputError(in_.paths.imu, 0, "t", reason.str());
}

/// One IMU sample (next: the following one, null at the end): exact-time samples inside it
/// split it (update there, continue with the rest), then the epoch's measurements, the knot
/// or the covariance group's end, output.
void NavigationFilter::ProcessImuSample(const ImuSample& sample, const ImuSample* next, double t0_s) {
  ImuSample rest = sample;
  if (rest.t_s - rest.dt_s < t0_s - ins::kSameEpoch_s) rest = SplitImuSample(rest, t0_s).second;
  for (long i = NextExactSource(rest.t_s - ins::kSameEpoch_s); i >= 0; i = NextExactSource(rest.t_s - ins::kSameEpoch_s)) {
    const std::size_t si = static_cast<std::size_t>(i);
    const double tg = sources_[si]->times()[next_[si]];
    if (tg > rest.t_s - rest.dt_s + ins::kSameEpoch_s) {
      const std::pair<ImuSample, ImuSample> parts = SplitImuSample(rest, tg);
      Propagate(parts.first);
      rest = parts.second;
    }
    current_ = si;
    epoch_t_s_ = tg;
    sources_[si]->FilterUpdate(next_[si]++, *this);
    EndEpoch(tg);
  }
  Propagate(rest);
  const double t = rest.t_s;
  if (detector_) detector_->Add(ins::CorrectImu(sample, imu_));
  ProcessEpochMeasurements(t, true);
  if (in_epoch_) {
    EndEpoch(t);
  } else if (t - last_knot_t_s_ >= cfg_.filter.store_interval_s - ins::kSameEpoch_s) {
    FlushGroup();
    StoreKnot(t, false);
  } else if (next == nullptr || group_dt_ + next->dt_s > cfg_.filter.covariance_interval_s * (1.0 + 1e-9)) {
    FlushGroup();
  }
  Output();
}

FilterResult NavigationFilter::Run() {
  const auto wall_start = std::chrono::steady_clock::now();
  const double t0 = start_.state.nav.t_s;
  const std::unique_ptr<ImuReader> imu = in_.imu.Read();
  ImuSample sample, next;
  FirstImuSample(*imu, &sample);
  progress_begin_s_ = in_.imu.begin_s();
  progress_end_s_ = in_.imu.end_known()   ? in_.imu.back().t_s
                    : in_.gnss.empty() ? progress_begin_s_
                                       : in_.gnss.back().t_s;

  // Knot 0: the initial state, with the measurements at the start time.
  SkipMeasurementsBeforeStart(t0);
  ProcessEpochMeasurements(t0, false);
  if (in_epoch_) {
    EndEpoch(t0);
  } else {
    StoreKnot(t0, false);
  }

  for (;;) {
    const bool more = imu->Next(&next);
    ProcessImuSample(sample, more ? &next : nullptr, t0);
    Progress(sample.t_s);
    if (!more) break;
    sample = next;
  }
  const double t = sample.t_s;
  FlushGroup();
  if (t > last_knot_t_s_ + ins::kSameEpoch_s) StoreKnot(t, false);
  return Result(wall_start);
}

FilterResult NavigationFilter::Result(std::chrono::steady_clock::time_point wall_start) {
  FilterResult result;
  result.filter.method = "filter";
  result.filter.epochs = std::move(epochs_);
  result.filter.knots_not_kept = knots_not_kept_;
  result.filter.counts = counts_;
  result.filter.aux_states = aux_states_;
  result.filter.measurement_residuals = std::move(measurement_residuals_);
  result.filter.run_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  if (run_rts_) {
    const RtsResult smoothed = RunRts(knots_);
    knots_.clear();
    knots_.shrink_to_fit();
    Solution rts;
    rts.method = "rts";
    rts.counts = counts_;
    rts.aux_states = aux_states_;
    rts.epochs.reserve(smoothed.dx.size());
    for (std::size_t i = 0; i < smoothed.dx.size(); ++i) {
      const NavEpoch& knot = result.filter.epochs[i];
      const InsState x = ins::ApplyCorrection(knot.state, smoothed.dx[i].head(n_ins_));
      const Eigen::VectorXd aux = knot.aux + smoothed.dx[i].tail(n_ - n_ins_);
      rts.epochs.push_back(Epoch(x, aux, smoothed.P[i]));
    }
    if (keep_covariances_) result.rts_covariances = smoothed.P;
    rts.run_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    result.rts = std::move(rts);
  }
  result.filter_covariances = std::move(filter_covariances_);
  // NIS of the accepted updates per measurement kind (a consistent filter: E[NIS] = dimension).
  for (const auto& [key, stats] : innovations_) {
    if (stats.dof == 0) continue;
    ResidualStats& r = result.filter.residuals[key];
    r.rows = static_cast<std::size_t>(stats.dof);
    r.chi2 = stats.nis;
    r.dof = stats.dof;
  }
  result.innovations = std::move(innovations_);
  return result;
}

void RequireKnotsForRts(FilterKnots knots, bool run_rts) {
  if (knots == FilterKnots::kLast && run_rts) {
    throw std::invalid_argument("RunFilter: the RTS smoother needs every knot (FilterKnots::kLast with run_rts)");
  }
}

}  // namespace

FilterResult RunFilter(const Inputs& inputs, const GnssInsConfig& config, const FilterStart& start, bool run_rts,
                       const std::function<void(const NavEpoch&)>& output, std::ostream* progress,
                       FilterKnots knots) {
  RequireKnotsForRts(knots, run_rts);
  NavigationFilter filter(inputs, config, start, run_rts, knots, output, progress);
  return filter.Run();
}

FilterResult RunFilter(const Inputs& inputs, const GnssInsConfig& config, bool run_rts,
                       const std::function<void(const NavEpoch&)>& output, std::ostream* progress,
                       FilterKnots knots) {
  RequireKnotsForRts(knots, run_rts);  // before the alignment, not after it
  const FilterStart start = InitialFilterState(inputs, config, progress);
  return RunFilter(inputs, config, start, run_rts, output, progress, knots);
}

}  // namespace navtwin::gnss_ins
