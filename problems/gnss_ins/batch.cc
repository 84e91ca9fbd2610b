// RunBatch (problems/gnss_ins/batch.h): the state epochs (batch_plan.h), the initial values
// and the preintegrations (one pass over the IMU record), the Ceres problem, the solve with
// reintegration rounds, and the per-state standard deviations.
#include "problems/gnss_ins/batch.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/problem.h>

#include "core/imu_split.h"
#include "core/io/input_error.h"
#include "core/rotation.h"
#include "core/strapdown.h"
#include "factors/attitude_manifold.h"
#include "factors/attitude_prior.h"
#include "factors/bias_process.h"
#include "factors/imu_preintegration.h"
#include "factors/position_manifold.h"
#include "factors/state_prior.h"
#include "problems/gnss_ins/batch_plan.h"
#include "problems/gnss_ins/initial_state.h"
#include "problems/ins/association.h"
#include "problems/gnss_ins/sources.h"
#include "problems/ins/measurement_rules.h"
#include "solvers/batch_driver.h"
#include "solvers/residual_groups.h"
#include "problems/ins/ins_state.h"

namespace navtwin::gnss_ins {
namespace {

using ins::AidingSource;

/// Residual groups of the batch's own residuals (the sources name theirs). The IMU factor is
/// whitened by S = L^-1 (L the lower Cholesky factor of its covariance, order attitude,
/// velocity, position): S is lower triangular, so its first three rows see the attitude
/// residual alone (the gyro noise) and the other six the velocity and position residuals
/// given the attitude one (mostly the accelerometer noise).
constexpr const char* kImuRotationGroup = "imu_rotation";
constexpr const char* kImuTranslationGroup = "imu_velocity_position";
constexpr const char* kPriorGroup = "prior";
/// Variance components: a group's factor is estimated when its redundancy is at least this
/// (its chi-square per degree of freedom then has a relative std of sqrt(2 / 10) = 0.45 or
/// less); the rounds stop when every estimable group's chi2 / dof is within the tolerance
/// of 1: 10 % in variance is 5 % in sigma, below the estimate's own scatter for groups of
/// up to 800 dof (sqrt(2 / 800) = 5 %). The iteration converges linearly, slowest for groups
/// that share states (IMU and bias processes): a few rounds reach 10 %, 5 % can take ten.
constexpr double kMinVarianceRedundancy = 10.0;
constexpr double kVarianceTolerance = 0.1;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// The variance of a start-solution knot's horizontal attitude error (the larger axis; 0
/// without a std).
double KnotTiltVariance(const NavEpoch& knot) {
  if (knot.std.size() < err::kAtt + 2) return 0.0;
  const double n = knot.std[err::kAtt], e = knot.std[err::kAtt + 1];
  const double v = std::max(n * n, e * e);
  return std::isfinite(v) ? v : 0.0;
}

/// The IMU errors the batch carries per state: the biases always, the scale factors with
/// config.filter.scale_factors (the 21-state model). Each kind is a Gauss-Markov process
/// over the states or, with no process noise, one block shared by all states.
enum ImuErrorKind { kGyroBias, kAccelBias, kGyroScale, kAccelScale, kImuErrorKinds };

struct ImuErrorKindInfo {
  Eigen::Vector3d ImuErrors::*member;
  int err_index;           ///< in the error state (ins_state.h)
  const char* process_group;
  double tiny_std;         ///< floor of the prior std (a zero std holds the block)
};

constexpr ImuErrorKindInfo kImuErrorKindTable[kImuErrorKinds] = {
    {&ImuErrors::bg_radps, err::kBg, "gyro_bias_process", 1e-12},
    {&ImuErrors::ba_mps2, err::kBa, "accel_bias_process", 1e-10},
    {&ImuErrors::sg, err::kSg, "gyro_scale_process", 1e-9},
    {&ImuErrors::sa, err::kSa, "accel_scale_process", 1e-9},
};

/// The parameter blocks and the initial information of one state.
struct BatchState {
  double t_s = 0.0;
  long anchor = -1;
  std::array<double, 3> pos{};  ///< lat_rad, lon_rad, h_m
  std::array<double, 3> vel{};  ///< v_n_mps
  std::array<double, 4> q{};    ///< q_n_b x, y, z, w
  /// Own IMU-error blocks per ImuErrorKind (unused when shared): rad/s, m/s^2, -, -.
  std::array<std::array<double, 3>, kImuErrorKinds> own{};
  std::array<double*, kImuErrorKinds> imu{};  ///< this state's blocks (own or shared; null: not estimated)
  InsState initial;             ///< mechanized from the start solution
  Eigen::Vector3d omega_ib_b_radps = Eigen::Vector3d::Zero();  ///< bias-corrected, at t_s
  ins::ImuMotion motion;        ///< MotionWindow at t_s
  bool still = false;           ///< the stillness rule holds at t_s
};

/// The biases and scale factors a state's blocks hold (the start's where not estimated).
ImuErrors ErrorsOf(const BatchState& s) {
  ImuErrors e = s.initial.imu;
  for (int k = 0; k < kImuErrorKinds; ++k) {
    if (s.imu[k] != nullptr) e.*kImuErrorKindTable[k].member = Eigen::Map<const Eigen::Vector3d>(s.imu[k]);
  }
  return e;
}

/// How an IMU error (a bias or a scale factor) is modelled.
struct BiasModel {
  bool shared = false;     ///< one block for all states (no process noise)
  bool constant = false;   ///< shared and held (zero initial std)
  double steady_std = 0.0; ///< Gauss-Markov steady-state std (per-state blocks)
  double tau_s = 0.0;
  Eigen::Vector3d prior_std = Eigen::Vector3d::Zero();
};

BiasModel MakeBiasModel(double steady_std, double tau_s, const Eigen::Vector3d& initial_std, double tiny) {
  BiasModel m;
  m.steady_std = steady_std;
  m.tau_s = tau_s;
  m.shared = !(steady_std > 0.0 && tau_s > 0.0 && std::isfinite(tau_s));
  m.constant = m.shared && (initial_std.array() <= 0.0).all();
  m.prior_std = initial_std.cwiseMax(tiny);
  return m;
}

/// Per group: the final statistics, the sigma scale and chi2 / dof with the configured noise.
std::map<std::string, ResidualStats> ResidualSummary(const std::vector<ResidualGroupStats>& configured,
                                                     const std::vector<ResidualGroupStats>& final_stats) {
  std::map<std::string, ResidualStats> out;
  for (std::size_t g = 0; g < final_stats.size(); ++g) {
    const ResidualGroupStats& f = final_stats[g];
    if (f.rows == 0) continue;
    ResidualStats& r = out[f.name];
    r.rows = f.rows;
    r.chi2 = f.chi2;
    r.dof = f.redundancy;
    r.sigma_scale = std::sqrt(f.factor);
    r.adapted = f.factor != 1.0;
    if (g < configured.size()) r.configured_chi2_per_dof = configured[g].ChiSquarePerDof();
  }
  return out;
}

class BatchSmoother : public ins::BatchAccess {
 public:
  BatchSmoother(const Inputs& inputs, const GnssInsConfig& config, const Solution& start, const FilterStart* initial,
                std::ostream* progress)
      : in_(inputs),
        cfg_(config),
        start_(start),
        initial_(initial),
        progress_(progress),
        sources_(MakeSources(inputs, config)) {}

  Solution Run();

  // ins::BatchAccess
  std::size_t num_states() const override { return views_.size(); }
  const State& state(std::size_t i) const override { return views_[i]; }
  Eigen::Quaterniond BodyRotation(double a_s, double b_s, const ImuErrors& errors) const override;
  const std::vector<std::size_t>& thinned_anchors() const override { return thinned_; }
  double* aux(int i) override { return &aux_[static_cast<std::size_t>(aux_begin_[current_] + i)]; }
  void Add(ceres::CostFunction* cost, bool robust, const std::vector<double*>& blocks,
           const std::string& key) override {
    const ceres::ResidualBlockId id =
        problem_->AddResidualBlock(groups_.Wrap(cost, SourceRowGroups(key)), robust ? huber_.get() : nullptr, blocks);
    measurement_blocks_.push_back({id, key, StateTime(blocks)});
    ++counts_[key].used;
  }
  void Count(const std::string& key, bool used) override {
    MeasurementCount& c = counts_[key];
    ++(used ? c.used : c.rejected);
  }

 private:
  void Check() const;
  void Initialise(const Plan& plan);
  void MechanizeAndPreintegrate();
  bool ReadToStart(ImuReader& reader, ImuSample* sample, const std::function<void(const ImuSample&)>& before) const;
  using PieceSink = std::function<void(const ImuSample& piece, const ImuSample& sample, std::size_t interval, bool last)>;
  std::size_t WalkPieces(ImuReader& reader, ImuSample sample, const std::function<void(double)>& on_time,
                         const PieceSink& on_piece) const;
  void ReintegrateFromFile(const std::vector<std::size_t>& intervals);
  void MakeViews();
  void BuildProblem();
  void AddImuFactor(std::size_t i);
  void AddPriors();
  void AddAuxPriors();
  int Reintegrate();
  BatchReport SolveWithReintegration(const BatchOptions& options, const std::string& label,
                                     std::ostringstream* report);
  void EstimateVarianceComponents(const BatchOptions& options, std::ostringstream* report);
  void Covariance(Solution* solution, std::ostringstream* report);
  std::vector<int> SourceRowGroups(const std::string& key);
  double StateTime(const std::vector<double*>& blocks) const;
  std::vector<MeasurementResidual> MeasurementResiduals() const;
  ceres::CostFunction* Group(ceres::CostFunction* cost, const char* group, bool estimable = true) {
    return groups_.Wrap(cost, {groups_.Group(group, estimable)});
  }
  void Say(const std::string& line) const {
    if (progress_ != nullptr) *progress_ << "batch: " << line << '\n' << std::flush;
  }

  const Inputs& in_;
  const GnssInsConfig& cfg_;
  const Solution& start_;
  const FilterStart* initial_;  ///< the filter's initial state (null: computed for the prior)
  std::ostream* progress_;

  ins::AidingSources sources_;
  std::vector<State> views_;             ///< the states as the sources see them
  std::vector<std::size_t> thinned_;
  std::vector<double> aux_;              ///< the sources' auxiliary parameter blocks (1 each)
  std::vector<ins::AuxState> aux_states_;
  std::vector<int> aux_begin_;           ///< per source: its first auxiliary block
  std::size_t current_ = 0;              ///< the source adding its residuals

  int imu_kinds_ = 2;  ///< the ImuErrorKinds estimated: the biases, and the scale factors
  std::array<BiasModel, kImuErrorKinds> imu_models_;
  std::array<std::array<double, 3>, kImuErrorKinds> shared_imu_{};
  std::vector<BatchState> states_;
  std::vector<std::shared_ptr<ImuPreintegration>> pre_;  ///< interval i: states i -> i + 1
  /// The IMU samples (and the piece of the one holding t0) in the kMaxSensorAssociation_s
  /// before the first state: with the preintegrated pieces, the increments BodyRotation needs.
  std::vector<ImuSample> before_start_;
  bool keep_pieces_ = false;     ///< a source calls BodyRotation: the pieces are stored
  bool pieces_dropped_ = false;  ///< after BuildProblem: BodyRotation no longer available
  std::vector<ceres::ResidualBlockId> imu_factors_;
  std::map<std::string, MeasurementCount> counts_;
  /// A source's residual block (BatchAccess::Add): its count key and the time of its state.
  struct MeasurementBlock {
    ceres::ResidualBlockId id;
    std::string key;
    double t_s;
  };
  std::vector<MeasurementBlock> measurement_blocks_;
  std::map<const double*, double> state_time_;  ///< a state's position, velocity, attitude block -> its time
  std::size_t imu_samples_ = 0;
  ResidualGroups groups_;
  std::map<std::string, std::vector<int>> source_groups_;  ///< "source index/key" -> row groups
  std::vector<ResidualGroupStats> configured_stats_;        ///< with the configured noise
  std::vector<ResidualGroupStats> final_stats_;

  // Declared before the problem, which does not own them (shared by many blocks).
  PositionManifold position_manifold_;
  AttitudeManifold attitude_manifold_;
  std::unique_ptr<ceres::LossFunction> huber_;
  std::unique_ptr<ceres::Problem> problem_;
};

void BatchSmoother::Check() const {
  if (start_.epochs.empty()) throw std::invalid_argument("RunBatch: the start solution has no epoch");
  for (std::size_t i = 1; i < start_.epochs.size(); ++i) {
    if (!(start_.epochs[i].state.nav.t_s > start_.epochs[i - 1].state.nav.t_s)) {
      throw std::invalid_argument("RunBatch: the start solution's epochs are not increasing in time");
    }
  }
  if (in_.imu.empty()) throw std::invalid_argument("RunBatch: no IMU samples");
  const double t0 = start_.epochs.front().state.nav.t_s;
  const double imu_begin = in_.imu.front().t_s - in_.imu.front().dt_s;
  if (t0 < imu_begin - ins::kSameEpoch_s || t0 >= in_.imu.back().t_s - ins::kSameEpoch_s) {
    std::ostringstream text;
    text.precision(12);
    text << "RunBatch: the start solution begins at t = " << t0 << " s, outside the IMU record [" << imu_begin
         << ", " << in_.imu.back().t_s << "] s";
    throw std::invalid_argument(text.str());
  }
  const ImuNoise& n = cfg_.imu_noise;
  if (!(n.gyro_arw_rad_per_sqrt_s > 0.0) || !(n.accel_vrw_mps_per_sqrt_s > 0.0)) {
    throw std::invalid_argument("RunBatch: the IMU preintegration needs a positive gyro ARW and accelerometer VRW");
  }
}

void BatchSmoother::Initialise(const Plan& plan) {
  imu_kinds_ = cfg_.filter.scale_factors ? kImuErrorKinds : kGyroScale;
  const Eigen::VectorXd init_std = InitialStdVector(cfg_, err::kSize21);
  const ImuNoise& n = cfg_.imu_noise;
  const double steady_std[kImuErrorKinds] = {n.gyro_bias_std_radps, n.accel_bias_std_mps2, n.gyro_scale_std,
                                             n.accel_scale_std};
  for (int k = 0; k < imu_kinds_; ++k) {
    const ImuErrorKindInfo& kind = kImuErrorKindTable[k];
    imu_models_[k] = MakeBiasModel(steady_std[k], n.correlation_time_s, init_std.segment<3>(kind.err_index),
                                   kind.tiny_std);
  }
  states_.resize(plan.states.size());
  for (std::size_t i = 0; i < states_.size(); ++i) {
    BatchState& s = states_[i];
    s.t_s = plan.states[i].t_s;
    s.anchor = plan.states[i].anchor;
    for (int k = 0; k < imu_kinds_; ++k) s.imu[k] = imu_models_[k].shared ? shared_imu_[k].data() : s.own[k].data();
  }
  thinned_ = plan.thinned;
  for (const auto& source : sources_) {
    for (const std::string& key : source->keys()) counts_[key];
    aux_begin_.push_back(static_cast<int>(aux_states_.size()));
    for (const ins::AuxState& a : source->aux_states()) aux_states_.push_back(a);
  }
  aux_.resize(aux_states_.size());
  for (std::size_t i = 0; i < aux_.size(); ++i) aux_[i] = aux_states_[i].initial;
}

void BatchSmoother::MakeViews() {
  views_.resize(states_.size());
  for (std::size_t i = 0; i < states_.size(); ++i) {
    BatchState& s = states_[i];
    State& v = views_[i];
    v.t_s = s.t_s;
    v.pos = s.pos.data();
    v.vel = s.vel.data();
    v.q = s.q.data();
    v.initial = &s.initial;
    v.omega_ib_b_radps = s.omega_ib_b_radps;
    v.motion = s.motion;
    v.still = s.still;
    v.anchor = s.anchor;
    for (const double* block : {v.pos, v.vel, v.q}) state_time_[block] = s.t_s;
  }
}

/// The time of the first state whose block is among `blocks` (NaN: none, only auxiliary
/// parameters).
double BatchSmoother::StateTime(const std::vector<double*>& blocks) const {
  for (const double* block : blocks) {
    const auto it = state_time_.find(block);
    if (it != state_time_.end()) return it->second;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

/// Per source residual block, in time order (the sources' order within a time): the squared
/// norm of its whitened residual at the current values, with the groups' current variance
/// factors and without the robust loss.
std::vector<MeasurementResidual> BatchSmoother::MeasurementResiduals() const {
  std::vector<MeasurementResidual> rows;
  rows.reserve(measurement_blocks_.size());
  Eigen::VectorXd r;
  for (const MeasurementBlock& m : measurement_blocks_) {
    const int dof = problem_->GetCostFunctionForResidualBlock(m.id)->num_residuals();
    r.resize(dof);
    double cost = 0.0;
    const bool ok = problem_->EvaluateResidualBlock(m.id, false, &cost, r.data(), nullptr);
    rows.push_back({m.t_s, m.key, dof, ok ? r.squaredNorm() : std::numeric_limits<double>::quiet_NaN(), false});
  }
  // NaN times (no state block) last.
  std::stable_sort(rows.begin(), rows.end(), [](const MeasurementResidual& a, const MeasurementResidual& b) {
    return !std::isnan(a.t_s) && (std::isnan(b.t_s) || a.t_s < b.t_s);
  });
  return rows;
}

/// One pass over the IMU record: the strapdown mechanization from the latest knot of the
/// start solution (reset at every knot, with that knot's IMU errors) gives each state's
/// initial value; the same pieces of samples, split at the state (and knot) times, go into
/// that interval's preintegration, linearised at the first state's IMU errors (its blocks'
/// initial values; the start solution's scale factors where they are not estimated).
void BatchSmoother::MechanizeAndPreintegrate() {
  const std::vector<NavEpoch>& knots = start_.epochs;
  const std::size_t n = states_.size();
  const double t0 = states_.front().t_s;
  const ImuNoise& noise = cfg_.imu_noise;

  Strapdown strapdown(knots.front().state.nav);
  ImuErrors errors = knots.front().state.imu;
  std::size_t kn = 1, si = 0;
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  const ins::StillnessConfig* still_rule = ins::StillnessRule(sources_);
  keep_pieces_ = std::any_of(sources_.begin(), sources_.end(),
                             [](const auto& source) { return source->rotates_samples_to_states(); });
  std::optional<ins::StillnessDetector> detector;
  if (still_rule != nullptr) detector.emplace(*still_rule);
  ins::MotionWindow motion(noise.gyro_arw_rad_per_sqrt_s, noise.accel_vrw_mps_per_sqrt_s);
  double tilt_var = KnotTiltVariance(knots.front());  // of the knot the mechanization started at

  // The bias blocks' initial values: each state's from its knot, shared ones from the first.
  const auto record_state = [&]() {
    BatchState& s = states_[si];
    s.initial.nav = strapdown.state();
    s.initial.nav.t_s = s.t_s;
    s.initial.imu = errors;
    s.omega_ib_b_radps = omega;
    s.motion = motion.Get(tilt_var);
    s.still = detector && detector->Still();
    const NavState& nav = s.initial.nav;
    s.pos = {nav.lat_rad, nav.lon_rad, nav.h_m};
    s.vel = {nav.v_n_mps.x(), nav.v_n_mps.y(), nav.v_n_mps.z()};
    const Eigen::Quaterniond q = nav.q_n_b.normalized();
    s.q = {q.x(), q.y(), q.z(), q.w()};
    for (int k = 0; k < imu_kinds_; ++k) {
      const Eigen::Vector3d& value = errors.*kImuErrorKindTable[k].member;
      Eigen::Map<Eigen::Vector3d>(s.own[k].data()) = value;
      if (si == 0) Eigen::Map<Eigen::Vector3d>(shared_imu_[k].data()) = value;
    }
    if (si + 1 < n) {
      pre_[si] = std::make_shared<ImuPreintegration>(ErrorsOf(s), noise.gyro_arw_rad_per_sqrt_s,
                                                     noise.accel_vrw_mps_per_sqrt_s);
      // Without a source that rotates samples to states nothing reads the pieces: none
      // are stored (tens of MB for an hour, and the holes they leave in the heap).
      if (!keep_pieces_) pre_[si]->DropSamples();
    }
    ++si;
  };
  const auto events = [&](double t) {
    while (kn < knots.size() && knots[kn].state.nav.t_s <= t + ins::kSameEpoch_s) {
      NavState nav = knots[kn].state.nav;
      nav.t_s = strapdown.state().t_s;
      strapdown.SetState(nav);
      errors = knots[kn].state.imu;
      tilt_var = KnotTiltVariance(knots[kn]);
      ++kn;
    }
    while (si < n && states_[si].t_s <= t + ins::kSameEpoch_s) record_state();
  };
  const auto step = [&](const ImuSample& piece) {
    const ImuSample c = CorrectImu(piece, errors);
    const Eigen::Vector3d v_before_n_mps = strapdown.state().v_n_mps;
    strapdown.Update(c);
    motion.Add(c, strapdown.state().v_n_mps - v_before_n_mps);
    omega = c.dtheta_b_rad / c.dt_s;
    pre_[si - 1]->Integrate(piece);
    ++imu_samples_;
  };

  pre_.assign(n > 0 ? n - 1 : 0, nullptr);
  // One pass over the IMU record. Samples ending at or before t0 only feed the stillness
  // window (and are kept for BodyRotation when close to t0); the angular rate at t0 is the
  // one of the sample that ends at or contains t0.
  const std::unique_ptr<ImuReader> reader = in_.imu.Read();
  bool omega_set = false;
  ImuSample sample;
  const bool have = ReadToStart(*reader, &sample, [&](const ImuSample& s) {
    if (!omega_set && s.t_s >= t0 - ins::kSameEpoch_s) {
      omega = CorrectImu(s, errors).dtheta_b_rad / s.dt_s;
      omega_set = true;
    }
    if (detector && s.t_s > t0 - still_rule->window_s - 1.0) detector->Add(CorrectImu(s, errors));
    if (s.t_s > t0 - ins::kMaxSensorAssociation_s - 1.0) before_start_.push_back(s);
  });
  if (have && !omega_set) omega = CorrectImu(sample, errors).dtheta_b_rad / sample.dt_s;
  if (have && sample.t_s - sample.dt_s < t0 - ins::kSameEpoch_s) {
    before_start_.push_back(SplitImuSample(sample, t0).first);
  }
  record_state();
  if (have) {
    WalkPieces(*reader, sample, events, [&](const ImuSample& piece, const ImuSample& whole, std::size_t, bool last) {
      step(piece);
      if (last && detector) detector->Add(CorrectImu(whole, errors));
    });
  }
  if (si < n) {
    std::ostringstream text;
    text.precision(12);
    text << "RunBatch: internal error, state at t = " << states_[si].t_s << " s beyond the IMU record";
    throw std::logic_error(text.str());
  }
}

/// Reads `reader` to the first sample ending after t0 (into *sample; false: none), giving
/// each sample before it to `before`.
bool BatchSmoother::ReadToStart(ImuReader& reader, ImuSample* sample,
                                const std::function<void(const ImuSample&)>& before) const {
  const double t0 = states_.front().t_s;
  while (reader.Next(sample)) {
    if (sample->t_s > t0 + ins::kSameEpoch_s) return true;
    before(*sample);
  }
  return false;
}

/// The IMU samples from `sample` (the first ending after t0) on, in pieces split at every
/// knot and state time after t0: on_piece(piece, sample, interval, last) for each piece
/// (interval i: between states i and i + 1; last: the sample's last piece), on_time(t) at
/// each of those times once the pieces before it are done. Stops at the last state;
/// returns the number of states reached (all of them when the record covers them).
std::size_t BatchSmoother::WalkPieces(ImuReader& reader, ImuSample sample, const std::function<void(double)>& on_time,
                                      const PieceSink& on_piece) const {
  const std::vector<NavEpoch>& knots = start_.epochs;
  const std::size_t n = states_.size();
  const double t0 = states_.front().t_s;
  std::size_t kn = 1, si = 1;  // the next knot and state after t0
  const auto reach = [&](double t) {
    while (kn < knots.size() && knots[kn].state.nav.t_s <= t + ins::kSameEpoch_s) ++kn;
    while (si < n && states_[si].t_s <= t + ins::kSameEpoch_s) ++si;
    on_time(t);
  };
  for (bool have = true; have && si < n; have = reader.Next(&sample)) {
    ImuSample piece = sample;
    if (piece.t_s - piece.dt_s < t0 - ins::kSameEpoch_s) piece = SplitImuSample(piece, t0).second;
    while (true) {
      const double next_knot = kn < knots.size() ? knots[kn].state.nav.t_s : INFINITY;
      const double next = std::min(next_knot, states_[si].t_s);
      if (next >= piece.t_s - ins::kSameEpoch_s) break;
      if (next > piece.t_s - piece.dt_s + ins::kSameEpoch_s) {
        const std::pair<ImuSample, ImuSample> parts = SplitImuSample(piece, next);
        on_piece(parts.first, sample, si - 1, false);
        piece = parts.second;
      }
      reach(next);
      if (si >= n) break;
    }
    if (si >= n) break;
    on_piece(piece, sample, si - 1, true);
    reach(piece.t_s);
  }
  return si;
}

/// New preintegrations of the given intervals at their states' current IMU errors, from the
/// IMU file read again and split exactly as MechanizeAndPreintegrate split it.
void BatchSmoother::ReintegrateFromFile(const std::vector<std::size_t>& intervals) {
  const ImuNoise& noise = cfg_.imu_noise;
  std::vector<std::shared_ptr<ImuPreintegration>> fresh(pre_.size());
  for (std::size_t i : intervals) {
    fresh[i] = std::make_shared<ImuPreintegration>(ErrorsOf(states_[i]), noise.gyro_arw_rad_per_sqrt_s,
                                                   noise.accel_vrw_mps_per_sqrt_s);
    fresh[i]->DropSamples();  // integrates without keeping the pieces
  }
  const std::unique_ptr<ImuReader> reader = in_.imu.Read();
  ImuSample sample;
  if (ReadToStart(*reader, &sample, [](const ImuSample&) {})) {
    WalkPieces(*reader, sample, [](double) {}, [&](const ImuSample& piece, const ImuSample&, std::size_t i, bool) {
      if (fresh[i]) fresh[i]->Integrate(piece);
    });
  }
  for (std::size_t i : intervals) {
    if (fresh[i]->num_samples() != pre_[i]->num_samples()) {  // the IMU file changed under the run
      std::ostringstream text;
      text.precision(12);
      text << "interval t = " << states_[i].t_s << " .. " << states_[i + 1].t_s << " s: " << fresh[i]->num_samples()
           << " IMU pieces on reading the file again, " << pre_[i]->num_samples() << " before";
      throw InputError(in_.paths.imu, 0, "t", text.str());
    }
    pre_[i] = fresh[i];
  }
}

void BatchSmoother::AddImuFactor(std::size_t i) {
  BatchState& a = states_[i];
  BatchState& b = states_[i + 1];
  const int rotation = groups_.Group(kImuRotationGroup), translation = groups_.Group(kImuTranslationGroup);
  const std::vector<int> rows = {rotation,    rotation,    rotation,    translation, translation,
                                 translation, translation, translation, translation};
  std::vector<double*> blocks = {a.pos.data(), a.vel.data(), a.q.data()};
  for (int k = 0; k < imu_kinds_; ++k) blocks.push_back(a.imu[k]);
  for (double* block : {b.pos.data(), b.vel.data(), b.q.data()}) blocks.push_back(block);
  ceres::CostFunction* cost = imu_kinds_ == kImuErrorKinds ? CreateImuScaleFactor(pre_[i]) : CreateImuFactor(pre_[i]);
  imu_factors_[i] = problem_->AddResidualBlock(groups_.Wrap(cost, rows), nullptr, blocks);
}

void BatchSmoother::AddPriors() {
  // Centred on the filter's initial state when it starts at the first state's time (the
  // prior the filter used), else on the first knot.
  InsState centre = start_.epochs.front().state;
  std::optional<FilterStart> computed;
  if (initial_ == nullptr) {
    try {
      computed = InitialFilterState(in_, cfg_);
    } catch (const std::exception&) {
      // No initial state from the configuration: the first knot.
    }
  }
  const FilterStart* fs = initial_ != nullptr ? initial_ : (computed ? &*computed : nullptr);
  if (fs != nullptr && std::abs(fs->state.nav.t_s - states_.front().t_s) <= ins::kSameEpoch_s) centre = fs->state;
  const Eigen::VectorXd std = InitialStdVector(cfg_, err::kSize15);
  BatchState& s = states_.front();
  const NavState& c = centre.nav;
  const auto prior = [this](ceres::CostFunction* cost) { return Group(cost, kPriorGroup, false); };
  problem_->AddResidualBlock(
      prior(PositionPrior::Create(Eigen::Vector3d(c.lat_rad, c.lon_rad, c.h_m), std.segment<3>(err::kPos).cwiseMax(1e-6))),
      nullptr, s.pos.data());
  problem_->AddResidualBlock(prior(VectorPrior3::Create(c.v_n_mps, std.segment<3>(err::kVel).cwiseMax(1e-6))), nullptr,
                             s.vel.data());
  const Eigen::Vector3d att_std = std.segment<3>(err::kAtt).cwiseMax(1e-8);
  problem_->AddResidualBlock(
      prior(AttitudePrior::Create(c.q_n_b, Eigen::Matrix3d(att_std.cwiseInverse().asDiagonal()))), nullptr,
      s.q.data());
  for (int k = 0; k < imu_kinds_; ++k) {
    if (imu_models_[k].constant) continue;
    const Eigen::Vector3d& value = centre.imu.*kImuErrorKindTable[k].member;
    problem_->AddResidualBlock(prior(VectorPrior3::Create(value, imu_models_[k].prior_std)), nullptr, s.imu[k]);
  }
}

void BatchSmoother::BuildProblem() {
  ceres::Problem::Options options;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.enable_fast_removal = true;  // reintegration replaces IMU factors
  problem_ = std::make_unique<ceres::Problem>(options);
  if (cfg_.batch.huber_k > 0.0) huber_ = std::make_unique<ceres::HuberLoss>(cfg_.batch.huber_k);

  for (BatchState& s : states_) {
    problem_->AddParameterBlock(s.pos.data(), 3, &position_manifold_);
    problem_->AddParameterBlock(s.vel.data(), 3);
    problem_->AddParameterBlock(s.q.data(), 4, &attitude_manifold_);
    for (int k = 0; k < imu_kinds_; ++k) {
      if (!imu_models_[k].shared || &s == &states_.front()) problem_->AddParameterBlock(s.imu[k], 3);
    }
  }
  for (int k = 0; k < imu_kinds_; ++k) {
    if (imu_models_[k].constant) problem_->SetParameterBlockConstant(shared_imu_[k].data());
  }

  imu_factors_.assign(pre_.size(), nullptr);
  for (std::size_t i = 0; i + 1 < states_.size(); ++i) {
    AddImuFactor(i);
    const double dt = states_[i + 1].t_s - states_[i].t_s;
    for (int k = 0; k < imu_kinds_; ++k) {
      const BiasModel& m = imu_models_[k];
      if (m.shared) continue;
      problem_->AddResidualBlock(
          Group(BiasGaussMarkov::Create(dt, m.tau_s, m.steady_std), kImuErrorKindTable[k].process_group), nullptr,
          states_[i].imu[k], states_[i + 1].imu[k]);
    }
  }
  for (std::size_t i = 0; i < sources_.size(); ++i) {
    current_ = i;
    sources_[i]->AddToBatch(*this);
  }
  AddPriors();
  AddAuxPriors();
}

/// The sources' auxiliary parameters: priors (held constant with a zero initial std).
void BatchSmoother::AddAuxPriors() {
  for (std::size_t i = 0; i < aux_.size(); ++i) {
    double* block = &aux_[i];
    if (!problem_->HasParameterBlock(block)) problem_->AddParameterBlock(block, 1);
    if (aux_states_[i].initial_std > 0.0) {
      problem_->AddResidualBlock(
          Group(ScalarPrior::Create(aux_states_[i].initial, aux_states_[i].initial_std), kPriorGroup, false), nullptr,
          block);
    } else {
      problem_->SetParameterBlockConstant(block);
    }
  }
}

/// ins::BodyRotation over the pieces of the intervals overlapping [a_s, b_s] (and the
/// samples before the first state).
Eigen::Quaterniond BatchSmoother::BodyRotation(double a_s, double b_s, const ImuErrors& errors) const {
  if (pieces_dropped_) throw std::logic_error("BatchSmoother::BodyRotation: called after the problem was built");
  if (!keep_pieces_) {
    throw std::logic_error("BatchSmoother::BodyRotation: no source declared rotates_samples_to_states()");
  }
  std::vector<ImuSample> pieces;
  if (a_s < states_.front().t_s) pieces = before_start_;
  const auto first = std::upper_bound(states_.begin(), states_.end(), a_s,
                                      [](double t, const BatchState& s) { return t < s.t_s; });
  std::size_t i = first == states_.begin() ? 0 : static_cast<std::size_t>(first - states_.begin()) - 1;
  for (; i < pre_.size() && states_[i].t_s < b_s; ++i) {
    const std::vector<ImuSample>& p = pre_[i]->samples();
    pieces.insert(pieces.end(), p.begin(), p.end());
  }
  return ins::BodyRotation(pieces, a_s, b_s, errors);
}

/// Reintegrates the intervals whose gyro bias (or gyro scale factor) moved too far from the
/// linearisation point and replaces their factors; returns how many. Too far: the bias by
/// batch.relinearize_bias_radps when set, else the first-order attitude correction
/// |J_R_bg dbg + J_R_sg dsg| beyond a tenth of the interval's gyro noise arw sqrt(dt).
int BatchSmoother::Reintegrate() {
  const double arw = cfg_.imu_noise.gyro_arw_rad_per_sqrt_s;
  const double fixed = cfg_.batch.relinearize_bias_radps;
  std::vector<std::size_t> too_far;
  for (std::size_t i = 0; i < pre_.size(); ++i) {
    const ImuPreintegration& pre = *pre_[i];
    const ImuErrors now = ErrorsOf(states_[i]);
    const double dt = pre.dt_s();
    const Eigen::Vector3d dbg = now.bg_radps - pre.bg_lin_radps();
    const Eigen::Vector3d correction_rad = pre.J_R_bg() * dbg + pre.J_R_sg() * (now.sg - pre.lin().sg);
    if (fixed > 0.0 ? dbg.norm() > fixed : correction_rad.norm() > 0.1 * arw * std::sqrt(dt)) too_far.push_back(i);
  }
  if (too_far.empty()) return 0;
  ReintegrateFromFile(too_far);
  for (std::size_t i : too_far) {
    problem_->RemoveResidualBlock(imu_factors_[i]);
    AddImuFactor(i);
  }
  return static_cast<int>(too_far.size());
}

std::vector<int> BatchSmoother::SourceRowGroups(const std::string& key) {
  const std::string id = std::to_string(current_) + "/" + key;
  auto it = source_groups_.find(id);
  if (it == source_groups_.end()) {
    std::vector<int> groups;
    const AidingSource& source = *sources_[current_];
    for (const std::string& name : source.row_groups(key)) {
      groups.push_back(groups_.Group(name, source.noise_estimable()));
    }
    it = source_groups_.emplace(id, std::move(groups)).first;
  }
  return it->second;
}

/// Solves, then reintegrates the intervals whose gyro bias moved and solves again, at most
/// kMaxReintegrationRounds times.
BatchReport BatchSmoother::SolveWithReintegration(const BatchOptions& options, const std::string& label,
                                                  std::ostringstream* report) {
  BatchReport solve = SolveBatch(*problem_, options, progress_);
  *report << label << " 1: " << solve.brief_report << '\n';
  for (int round = 1; round <= kMaxReintegrationRounds; ++round) {
    const int reintegrated = Reintegrate();
    if (reintegrated == 0) break;
    std::ostringstream line;
    line << "reintegration round " << round << ": " << reintegrated << " of " << pre_.size()
         << " intervals (gyro bias moved past the threshold)";
    *report << line.str() << '\n';
    Say(line.str());
    solve = SolveBatch(*problem_, options, progress_);
    *report << label << " " << round + 1 << ": " << solve.brief_report << '\n';
  }
  return solve;
}

/// The residual statistics with the configured noise, and with config.batch.variance_components
/// the iterated variance-component estimate: factors updated, problem solved again, until
/// every estimable group's chi2 / dof is within kVarianceTolerance of 1.
void BatchSmoother::EstimateVarianceComponents(const BatchOptions& options, std::ostringstream* report) {
  const int threads = std::max(1, cfg_.batch.threads);
  std::string failure;
  configured_stats_ = groups_.Evaluate(*problem_, true, threads, &failure);
  final_stats_ = configured_stats_;
  if (!failure.empty()) {
    *report << "residual statistics without redundancy: " << failure << '\n';
    Say("residual statistics without redundancy: " + failure);
    return;
  }
  if (!cfg_.batch.variance_components) return;
  int round = 0;
  double worst = 0.0;
  for (; round < cfg_.batch.variance_rounds; ++round) {
    worst = groups_.UpdateFactors(final_stats_, kMinVarianceRedundancy, kVarianceTolerance);
    if (worst <= kVarianceTolerance) break;
    std::ostringstream line;
    line.precision(3);
    line << "variance components round " << round + 1 << ": largest |chi2/dof - 1| " << worst
         << ", noise rescaled, solving again";
    Say(line.str());
    *report << line.str() << '\n';
    SolveWithReintegration(options, "vce solve", report);
    final_stats_ = groups_.Evaluate(*problem_, true, threads, &failure);
    if (!failure.empty()) break;
  }
  std::ostringstream line;
  line.precision(3);
  if (!failure.empty()) {
    line << "variance components stopped: " << failure;
  } else if (round == cfg_.batch.variance_rounds) {
    line << "variance components not converged after " << round << " rounds (largest |chi2/dof - 1| "
         << worst << ")";
  } else {
    line << "variance components converged after " << round << " round(s)";
  }
  *report << line.str() << '\n';
  Say(line.str());
}

void BatchSmoother::Covariance(Solution* solution, std::ostringstream* report) {
  std::vector<const double*> blocks;
  std::set<const double*> seen;
  for (const BatchState& s : states_) {
    std::vector<const double*> own = {s.pos.data(), s.vel.data(), s.q.data()};
    for (int k = 0; k < imu_kinds_; ++k) own.push_back(s.imu[k]);
    for (const double* b : own) {
      if (seen.insert(b).second && !problem_->IsParameterBlockConstant(b)) blocks.push_back(b);
    }
  }
  for (const double& a : aux_) {
    if (!problem_->IsParameterBlockConstant(&a)) blocks.push_back(&a);
  }
  BlockCovarianceOptions options;
  options.num_threads = std::max(1, cfg_.batch.threads);
  const BlockCovarianceResult result = ComputeBlockDiagonalCovariance(*problem_, blocks, options);
  std::map<const double*, Eigen::VectorXd> stds;
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const int size = problem_->ParameterBlockTangentSize(blocks[i]);
    stds[blocks[i]] = result.covariances[i]
                          ? Eigen::VectorXd(result.covariances[i]->diagonal().cwiseMax(0.0).cwiseSqrt())
                          : Eigen::VectorXd::Constant(size, std::numeric_limits<double>::quiet_NaN());
  }
  for (std::size_t i = 0; i < states_.size(); ++i) {
    const BatchState& s = states_[i];
    Eigen::VectorXd& std = solution->epochs[i].std;
    std.resize(imu_kinds_ == kImuErrorKinds ? err::kSize21 : err::kSize15);
    std.segment<3>(err::kPos) = stds[s.pos.data()];
    std.segment<3>(err::kVel) = stds[s.vel.data()];
    std.segment<3>(err::kAtt) = stds[s.q.data()];
    for (int k = 0; k < imu_kinds_; ++k) {
      const auto it = stds.find(s.imu[k]);  // absent: held constant
      std.segment<3>(kImuErrorKindTable[k].err_index) =
          it != stds.end() ? Eigen::Vector3d(it->second) : Eigen::Vector3d::Zero();
    }
    Eigen::VectorXd& aux_std = solution->epochs[i].aux_std;
    aux_std = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(aux_.size()));
    for (std::size_t k = 0; k < aux_.size(); ++k) {
      const auto it = stds.find(&aux_[k]);
      if (it != stds.end()) aux_std[static_cast<Eigen::Index>(k)] = it->second[0];
    }
  }
  std::ostringstream line;
  line.precision(3);
  line << "covariance: " << blocks.size() << " blocks by selected inversion in " << result.run_time_s << " s";
  if (!result.message.empty()) line << "; " << result.message << " (their std are NaN)";
  *report << line.str() << '\n';
  Say(line.str());
}

Solution BatchSmoother::Run() {
  const auto wall_start = std::chrono::steady_clock::now();
  Check();
  const double t0 = start_.epochs.front().state.nav.t_s;
  const Plan plan = PlanStates(AnchorTimes(sources_), cfg_, t0, in_.imu.back().t_s);
  Initialise(plan);
  MechanizeAndPreintegrate();
  MakeViews();
  BuildProblem();
  // The sources have carried their samples to the states (BodyRotation): the pieces go;
  // a reintegration reads the IMU file again.
  for (const std::shared_ptr<ImuPreintegration>& pre : pre_) pre->DropSamples();
  std::vector<ImuSample>().swap(before_start_);
  pieces_dropped_ = true;
  {
    std::ostringstream line;
    line.precision(3);
    line << states_.size() << " states, " << imu_samples_ << " IMU pieces preintegrated";
    for (const auto& [key, count] : counts_) line << ", " << count.used << " " << key;
    line << "; setup " << Seconds(wall_start) << " s";
    Say(line.str());
  }

  BatchOptions options;
  options.max_iterations = cfg_.batch.max_iterations;
  options.num_threads = std::max(1, cfg_.batch.threads);
  options.linear_solver = BatchOptions::LinearSolver::kSparseNormalCholesky;
  options.function_tolerance = 1e-8;  // |cost change| / cost: far below one unit of chi-square
  options.progress = progress_ != nullptr;
  std::ostringstream report;
  SolveWithReintegration(options, "solve", &report);
  EstimateVarianceComponents(options, &report);

  Solution solution;
  solution.method = "batch";
  solution.epochs.resize(states_.size());
  for (std::size_t i = 0; i < states_.size(); ++i) {
    const BatchState& s = states_[i];
    InsState& x = solution.epochs[i].state;
    x.nav.t_s = s.t_s;
    x.nav.gps_week = start_.epochs.front().state.nav.gps_week;
    x.nav.lat_rad = s.pos[0];
    x.nav.lon_rad = s.pos[1];
    x.nav.h_m = s.pos[2];
    x.nav.v_n_mps = Eigen::Vector3d(s.vel[0], s.vel[1], s.vel[2]);
    x.nav.q_n_b = Eigen::Quaterniond(s.q[3], s.q[0], s.q[1], s.q[2]).normalized();
    x.imu = ErrorsOf(s);
    solution.epochs[i].aux = Eigen::Map<const Eigen::VectorXd>(aux_.data(), static_cast<Eigen::Index>(aux_.size()));
  }
  if (cfg_.batch.covariance) Covariance(&solution, &report);
  solution.counts = counts_;
  solution.residuals = ResidualSummary(configured_stats_, final_stats_);
  solution.measurement_residuals = MeasurementResiduals();
  solution.aux_states = aux_states_;
  solution.solver_report = report.str();
  if (!solution.solver_report.empty() && solution.solver_report.back() == '\n') solution.solver_report.pop_back();
  solution.run_time_s = Seconds(wall_start);
  {
    std::ostringstream line;
    line.precision(3);
    line << "done in " << solution.run_time_s << " s";
    Say(line.str());
  }
  return solution;
}

}  // namespace

Solution RunBatch(const Inputs& inputs, const GnssInsConfig& config, const Solution& start, std::ostream* progress) {
  return RunBatch(inputs, config, start, nullptr, progress);
}

Solution RunBatch(const Inputs& inputs, const GnssInsConfig& config, const Solution& start, const FilterStart* initial,
                  std::ostream* progress) {
  BatchSmoother smoother(inputs, config, start, initial, progress);
  return smoother.Run();
}

}  // namespace navtwin::gnss_ins
