// Aiding sources of the aided INS as plug-ins. A source (GNSS, magnetometer, barometer,
// ZUPT, NHC, odometer, ...) owns its samples, its configuration and its measurement rules
// (association to IMU epochs or batch states, sigma, gating decisions), and states each
// measurement as a Ceres cost function over the state blocks it depends on. The filter
// linearises that cost function in the error-state tangent (solvers/linearize.h) and the
// batch adds it as a residual block: one model, two estimators. Neither estimator names
// a sensor: both iterate over the registered sources (docs/architecture.md).
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/types.h"
#include "problems/ins/ins_state.h"
#include "problems/ins/measurement_rules.h"

namespace ceres {
class CostFunction;
}  // namespace ceres

namespace navtwin::ins {

struct StillnessConfig;

/// A state block a measurement depends on, in the order of the cost function's parameter
/// blocks: position {lat_rad, lon_rad, h_m} (PositionManifold), v_n_mps (3),
/// q_n_b {x, y, z, w} (AttitudeManifold), or one of the source's own auxiliary states (1).
struct StateBlock {
  enum class Kind { kPosition, kVelocity, kAttitude, kAux };
  Kind kind = Kind::kPosition;
  int aux = 0;  ///< kAux: index among the source's auxiliary states
  static StateBlock Position() { return {Kind::kPosition, 0}; }
  static StateBlock Velocity() { return {Kind::kVelocity, 0}; }
  static StateBlock Attitude() { return {Kind::kAttitude, 0}; }
  static StateBlock Aux(int i) { return {Kind::kAux, i}; }
};

/// A scalar state a source adds to the estimators (an installation or sensor parameter):
/// a random constant with prior `initial` and standard deviation initial_std (0: held at
/// `initial`). The filter appends it to the error state, the batch estimates one
/// parameter block over the record.
struct AuxState {
  std::string name;  ///< e.g. "odometer_scale"
  double initial = 0.0;
  double initial_std = 0.0;
  /// What in a record makes it observable, for the report of a state whose posterior std
  /// stays near its prior ("rotation about the body x and y axes").
  std::string observed_by;
};

/// The filter as a source sees it at an update epoch.
class FilterAccess {
 public:
  virtual ~FilterAccess() = default;
  /// The nominal state at the epoch.
  virtual const InsState& nominal() const = 0;
  /// The source's auxiliary state i (nominal value).
  virtual double aux(int i) const = 0;
  /// Bias-corrected angular rate of the last (piece of an) IMU sample, body axes.
  virtual const Eigen::Vector3d& omega_ib_b_radps() const = 0;
  /// The nominal mechanization's motion at the epoch (rate, angular acceleration, NED
  /// acceleration and jerk) from the last IMU samples (MotionWindow, measurement_rules.h).
  virtual ImuMotion motion() const = 0;
  /// The epoch's time (an IMU epoch, or a sample time where the IMU sample is split).
  virtual double time_s() const = 0;
  /// The stillness rule over the IMU samples up to this epoch (the first source's
  /// stillness_rule(); false when no source has one).
  virtual bool still() const = 0;
  /// Linearises `cost` (whitened residual) at the nominal state over `blocks`, runs the
  /// chi-square gated update and feeds the correction back; counts it under `key`. Before
  /// the gate, `check` (when given) sees the whitened residual and may throw. Returns
  /// whether the update was accepted.
  virtual bool Update(std::unique_ptr<ceres::CostFunction> cost, const std::vector<StateBlock>& blocks,
                      const std::string& key,
                      const std::function<void(const Eigen::VectorXd& residual)>& check = nullptr) = 0;
  /// Counts a sample under `key` without an update (used: false = rejected by a rule).
  virtual void Count(const std::string& key, bool used) = 0;
  /// Resets position and velocity: the nominal state is corrected by dp_ned_m and dv_n_mps
  /// (true minus estimate), their covariance becomes diag(pos_var, vel_var) with no
  /// correlation to the other states; counted as used under `key`.
  virtual void ResetPositionVelocity(const Eigen::Vector3d& dp_ned_m, const Eigen::Vector3d& dv_n_mps,
                                     const Eigen::Vector3d& pos_var, const Eigen::Vector3d& vel_var,
                                     const std::string& key) = 0;
};

/// The batch problem as a source sees it while adding its residuals.
class BatchAccess {
 public:
  /// One state of the batch: its parameter blocks and what the start solution says there.
  struct State {
    double t_s = 0.0;
    double* pos = nullptr;  ///< lat_rad, lon_rad, h_m
    double* vel = nullptr;  ///< v_n_mps
    double* q = nullptr;    ///< q_n_b x, y, z, w
    const InsState* initial = nullptr;  ///< mechanized from the start solution
    Eigen::Vector3d omega_ib_b_radps = Eigen::Vector3d::Zero();  ///< bias-corrected, at t_s
    /// The mechanization's motion at t_s from the IMU samples before it (MotionWindow,
    /// measurement_rules.h; zero at the first state).
    ImuMotion motion;
    bool still = false;     ///< the stillness rule holds at t_s
    long anchor = -1;       ///< the anchoring source's sample placed at this state (-1: none)
  };
  virtual ~BatchAccess() = default;
  virtual std::size_t num_states() const = 0;
  virtual const State& state(std::size_t i) const = 0;
  /// The body rotation from t = a_s to t = b_s (a_s <= b_s, inside the states' span) by
  /// BodyRotation over the IMU increments corrected with `errors`, for sources that carry
  /// a sample to a state's time.
  virtual Eigen::Quaterniond BodyRotation(double a_s, double b_s, const ImuErrors& errors) const = 0;
  /// The anchoring source's samples in the span that got no state (state_interval_s).
  virtual const std::vector<std::size_t>& thinned_anchors() const = 0;
  /// The parameter block (1 double) of the source's auxiliary state i.
  virtual double* aux(int i) = 0;
  /// Adds a residual block (the problem takes ownership of cost); robust: with the batch's
  /// robust loss on the whitened residual vector. Counts it as used under `key`.
  virtual void Add(ceres::CostFunction* cost, bool robust, const std::vector<double*>& blocks,
                   const std::string& key) = 0;
  /// Counts a sample under `key` without a residual (used: false = not used by a rule).
  virtual void Count(const std::string& key, bool used) = 0;
};

/// An aiding source. Filter side: the filter calls FilterUpdate for each sample at the
/// epoch its timing() gives, or FilterEpoch at every IMU epoch; batch side: AddToBatch once.
class AidingSource {
 public:
  enum class Timing {
    kExact,       ///< at its sample times: the filter splits the IMU sample there
    kNextEpoch,   ///< at the first IMU epoch at or after the sample's time
    kEveryEpoch,  ///< a pseudo-measurement decided at every IMU epoch (ZUPT, NHC)
  };
  virtual ~AidingSource() = default;
  /// Count keys, in the order they are reported.
  virtual std::vector<std::string> keys() const = 0;
  /// The residual groups of the rows of a measurement counted under `key` (statistics and
  /// noise estimation, solvers/residual_groups.h): one name for every row, or one per row
  /// (e.g. horizontal and vertical axes of a GNSS position).
  virtual std::vector<std::string> row_groups(const std::string& key) const { return {key}; }
  /// Whether the batch may estimate the noise of this source's residual groups (variance
  /// components). False for pseudo-measurements whose sigma is a modelling choice (ZUPT,
  /// NHC): tightening one pins the states it touches, its redundancy collapses and the
  /// estimate runs away.
  virtual bool noise_estimable() const { return true; }
  virtual Timing timing() const = 0;
  /// Sample times, increasing (empty for kEveryEpoch).
  virtual const std::vector<double>& times() const = 0;
  /// Whether the batch places a state at each sample time (at most one source does).
  virtual bool anchors_batch_states() const { return false; }
  /// Whether AddToBatch calls BatchAccess::BodyRotation: the batch keeps the IMU pieces
  /// of every interval until the problem is built only when a source says so.
  virtual bool rotates_samples_to_states() const { return false; }
  /// The stillness rule this source decides with (null: none).
  virtual const StillnessConfig* stillness_rule() const { return nullptr; }
  virtual std::vector<AuxState> aux_states() const { return {}; }
  /// The filter starts; samples before first_time_s are not used.
  virtual void BeginFilter(double first_time_s) { (void)first_time_s; }
  /// Filter: sample k (kExact, kNextEpoch).
  virtual void FilterUpdate(std::size_t k, FilterAccess& filter) {
    (void)k;
    (void)filter;
  }
  /// Filter: at an IMU epoch (kEveryEpoch).
  virtual void FilterEpoch(FilterAccess& filter) { (void)filter; }
  /// Batch: adds the source's residuals.
  virtual void AddToBatch(BatchAccess& batch) = 0;
};

using AidingSources = std::vector<std::unique_ptr<AidingSource>>;

/// The first stillness rule among the sources (null: none).
inline const StillnessConfig* StillnessRule(const AidingSources& sources) {
  for (const auto& s : sources) {
    if (s->stillness_rule() != nullptr) return s->stillness_rule();
  }
  return nullptr;
}

/// R_{b(a) b(b)} for a <= b: the body rotation over [a, b] as the product of Exp of the
/// bias-corrected gyro increments (pieces of samples pro rata), v_{b(a)} = R v_{b(b)}. The
/// rotation of the navigation frame over |b - a| <= kMaxSensorAssociation_s (< 4e-5 rad)
/// is left out.
Eigen::Quaterniond BodyRotation(const std::vector<ImuSample>& imu, double a, double b, const ImuErrors& e);

}  // namespace navtwin::ins
