#include "problems/ins/sources/gnss.h"

#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/io/input_error.h"
#include "factors/gnss_installation.h"
#include "factors/gnss_position.h"
#include "factors/gnss_velocity.h"
#include "factors/position_manifold.h"
#include "problems/ins/measurement_rules.h"

namespace navtwin::ins {
namespace {

const char* const kPosition = "gnss_position";
const char* const kVelocity = "gnss_velocity";
const char* const kReset = "gnss_reset";

/// What observes each installation parameter (AuxState::observed_by): a lever-arm component
/// through rotations about the two other body axes (R_n_b l_b and omega x l_b change only
/// there), the time offset through changes of velocity.
const char* const kLeverArmAxes[3] = {"x", "y", "z"};
const char* const kLeverArmObservedBy[3] = {
    "rotation about the body y and z axes (pitch changes, turns)",
    "rotation about the body x and z axes (roll changes, turns)",
    "rotation about the body x and y axes (roll and pitch changes)"};
const char* const kTimeOffsetObservedBy =
    "changes of speed or course (at one speed along the body x axis, tau v is a lever arm along x)";

class GnssSource : public AidingSource {
 public:
  GnssSource(const std::vector<GnssSample>& fixes, const GnssConfig& config, const Eigen::Vector3d& lever_b_m,
             int reset_rejections, std::string path)
      : fixes_(fixes), config_(config), lever_b_m_(lever_b_m), reset_after_(reset_rejections), path_(std::move(path)) {
    times_.reserve(fixes.size());
    for (const GnssSample& g : fixes) times_.push_back(g.t_s);
    installation_.lever_arm = config.estimate_lever_arm;
    installation_.time_offset = config.estimate_time_offset;
    installation_.lever_arm_b_m = lever_b_m;
    installation_.time_offset_s = config.time_offset_s;
    installed_ = installation_.lever_arm || installation_.time_offset || config.time_offset_s != 0.0;
  }

  std::vector<std::string> keys() const override { return {kPosition, kVelocity, kReset}; }
  /// North and east rows share a group, down has its own: receivers' vertical errors are
  /// larger and differently mis-stated than their horizontal ones.
  std::vector<std::string> row_groups(const std::string& key) const override {
    return {key + "_h", key + "_h", key + "_v"};
  }
  Timing timing() const override { return Timing::kExact; }
  const std::vector<double>& times() const override { return times_; }
  bool anchors_batch_states() const override { return true; }

  /// The estimated installation parameters, in the order of the models' unknown blocks.
  std::vector<AuxState> aux_states() const override {
    std::vector<AuxState> states;
    if (installation_.lever_arm) {
      for (int i = 0; i < 3; ++i) {
        states.push_back({std::string("gnss_lever_arm_") + kLeverArmAxes[i] + "_m", lever_b_m_[i],
                          config_.lever_arm_std_m[i], kLeverArmObservedBy[i]});
      }
    }
    if (installation_.time_offset) {
      states.push_back({"gnss_time_offset_s", config_.time_offset_s, config_.time_offset_std_s, kTimeOffsetObservedBy});
    }
    return states;
  }

  void FilterUpdate(std::size_t k, FilterAccess& filter) override {
    const GnssSample& g = fixes_[k];
    const Eigen::Vector3d sp = PositionSigma(g);
    const auto check = [&](const Eigen::VectorXd& r) {
      // The whitened residual times sigma is the antenna offset from the prediction, m.
      const double distance_m = r.cwiseProduct(sp).norm();
      if (distance_m <= config_.max_distance_m) return;
      std::ostringstream reason;
      reason.precision(12);
      reason << "the GNSS fix at t = " << g.t_s << " s is " << distance_m
             << " m from the INS prediction (gnss.max_distance_m = " << config_.max_distance_m << ")";
      throw InputError(path_, 0, "position", reason.str());
    };
    std::vector<StateBlock> position_blocks = {StateBlock::Position(), StateBlock::Attitude()};
    std::vector<StateBlock> velocity_blocks = {StateBlock::Velocity(), StateBlock::Attitude()};
    if (installed_) {
      position_blocks.push_back(StateBlock::Velocity());
      for (int i = 0; i < installation_.NumUnknownBlocks(); ++i) {
        position_blocks.push_back(StateBlock::Aux(i));
        velocity_blocks.push_back(StateBlock::Aux(i));
      }
    }
    const BodyMotion motion = Motion(filter);
    const bool position_used = filter.Update(std::unique_ptr<ceres::CostFunction>(PositionCost(g, sp, motion)),
                                             position_blocks, kPosition, check);
    const bool use_velocity = config_.use_velocity && g.has_velocity;
    const Eigen::Vector3d sv = VelocitySigma(g);
    if (use_velocity) {
      filter.Update(std::unique_ptr<ceres::CostFunction>(VelocityCost(g, sv, filter.omega_ib_b_radps(), motion)),
                    velocity_blocks, kVelocity);
    }
    rejected_in_row_ = position_used ? 0 : rejected_in_row_ + 1;
    if (reset_after_ > 0 && rejected_in_row_ >= reset_after_) {
      Reset(g, sp, use_velocity ? &sv : nullptr, filter);
      rejected_in_row_ = 0;
    }
  }

  void AddToBatch(BatchAccess& batch) override {
    for (const std::size_t k : batch.thinned_anchors()) {
      batch.Count(kPosition, false);
      if (config_.use_velocity && fixes_[k].has_velocity) batch.Count(kVelocity, false);
    }
    std::vector<double*> unknowns;
    for (int i = 0; i < installation_.NumUnknownBlocks(); ++i) unknowns.push_back(batch.aux(i));
    for (std::size_t i = 0; i < batch.num_states(); ++i) {
      const BatchAccess::State& s = batch.state(i);
      if (s.anchor < 0) continue;
      const GnssSample& g = fixes_[static_cast<std::size_t>(s.anchor)];
      std::vector<double*> position_blocks = {s.pos, s.q};
      std::vector<double*> velocity_blocks = {s.vel, s.q};
      if (installed_) {
        position_blocks.push_back(s.vel);
        position_blocks.insert(position_blocks.end(), unknowns.begin(), unknowns.end());
        velocity_blocks.insert(velocity_blocks.end(), unknowns.begin(), unknowns.end());
      }
      const BodyMotion motion = ToBodyMotion(s.motion);
      batch.Add(PositionCost(g, PositionSigma(g), motion), true, position_blocks, kPosition);
      if (config_.use_velocity && g.has_velocity) {
        batch.Add(VelocityCost(g, VelocitySigma(g), s.omega_ib_b_radps, motion), true, velocity_blocks, kVelocity);
      }
    }
  }

 private:
  Eigen::Vector3d PositionSigma(const GnssSample& g) const {
    return MeasurementSigma(g.pos_std_ned_m, config_.pos_std_floor_m, config_.default_pos_std_m)
        .cwiseProduct(Eigen::Vector3d(config_.pos_sigma_scale_h, config_.pos_sigma_scale_h, config_.pos_sigma_scale_v));
  }
  Eigen::Vector3d VelocitySigma(const GnssSample& g) const {
    return MeasurementSigma(g.vel_std_ned_mps, config_.vel_std_floor_mps, config_.default_vel_std_mps)
        .cwiseProduct(Eigen::Vector3d(config_.vel_sigma_scale_h, config_.vel_sigma_scale_h, config_.vel_sigma_scale_v));
  }

  /// The position model: with the installation (blocks pos, q, v, unknowns) or with the
  /// fixed lever arm and no time offset (blocks pos, q).
  ceres::CostFunction* PositionCost(const GnssSample& g, const Eigen::Vector3d& sigma,
                                    const BodyMotion& motion) const {
    const Eigen::Vector3d p(g.lat_rad, g.lon_rad, g.h_m);
    if (!installed_) return GnssPosition::Create(p, lever_b_m_, sigma);
    return GnssAntennaPosition::Create(p, installation_, motion, sigma);
  }
  /// The velocity model: blocks v, q (and the unknowns with the installation). Without the
  /// installation it takes the last IMU sample's rate (omega_sample), as it always has.
  ceres::CostFunction* VelocityCost(const GnssSample& g, const Eigen::Vector3d& sigma,
                                    const Eigen::Vector3d& omega_sample, const BodyMotion& motion) const {
    if (!installed_) return GnssVelocity::Create(g.v_n_mps, lever_b_m_, omega_sample, sigma);
    return GnssAntennaVelocity::Create(g.v_n_mps, installation_, motion, sigma);
  }

  /// The models' known inputs from the motion window.
  static BodyMotion ToBodyMotion(const ImuMotion& m) {
    return {m.omega_ib_b_radps, m.alpha_ib_b_radps2, m.a_n_mps2, m.j_n_mps3};
  }
  /// The motion at the filter's epoch (the models' known inputs).
  static BodyMotion Motion(const FilterAccess& filter) { return ToBodyMotion(filter.motion()); }

  /// The installation at the filter's nominal state: the estimated parameters' values.
  GnssInstallation Current(const FilterAccess& filter) const {
    GnssInstallation x = installation_;
    int k = 0;
    if (x.lever_arm) {
      for (int i = 0; i < 3; ++i) x.lever_arm_b_m[i] = filter.aux(k++);
    }
    if (x.time_offset) x.time_offset_s = filter.aux(k);
    return x;
  }

  /// The filter no longer believes the receiver (its covariance is too small for its own
  /// error): position (and velocity, when the fix has it) are reset so that the models
  /// predict the fix; without a GNSS velocity the velocity keeps its value with 1 (m/s)^2
  /// of variance.
  void Reset(const GnssSample& g, const Eigen::Vector3d& sigma_pos_m, const Eigen::Vector3d* sigma_vel_mps,
             FilterAccess& filter) const {
    const NavState& s = filter.nominal().nav;
    const Eigen::Matrix3d R_n_b = s.q_n_b.toRotationMatrix();
    const GnssInstallation now = Current(filter);
    const Eigen::Vector3d& lever_b_m = now.lever_arm_b_m;
    const double tau_s = now.time_offset_s;
    const double antenna[3] = {g.lat_rad, g.lon_rad, g.h_m};
    const double pos[3] = {s.lat_rad, s.lon_rad, s.h_m};
    Eigen::Vector3d ins_minus_fix_ned;
    PositionMinus(pos, antenna, ins_minus_fix_ned.data());
    Eigen::Vector3d dp = -(ins_minus_fix_ned + R_n_b * lever_b_m);
    Eigen::Vector3d dv = Eigen::Vector3d::Zero();
    Eigen::Vector3d vel_var = Eigen::Vector3d::Ones();
    const BodyMotion motion = Motion(filter);
    // The rate the models take: the motion window's with the installation, else the sample's.
    const Eigen::Vector3d& omega = installed_ ? motion.omega_ib_b_radps : filter.omega_ib_b_radps();
    const Eigen::Vector3d lever_velocity_n = R_n_b * omega.cross(lever_b_m);
    Eigen::Vector3d v_ant_n, a_ant_n;
    if (tau_s != 0.0) motion.Antenna(R_n_b, s.v_n_mps, lever_b_m, &v_ant_n, &a_ant_n);
    const double tau2_s2 = tau_s * tau_s;
    if (sigma_vel_mps != nullptr) {
      dv = g.v_n_mps - (s.v_n_mps + lever_velocity_n);
      if (tau_s != 0.0) dv += tau_s * a_ant_n - 0.5 * tau2_s2 * motion.j_n_mps3;
      vel_var = sigma_vel_mps->cwiseAbs2();
    }
    // The fix describes the antenna tau earlier: the models carry the reset antenna back.
    if (tau_s != 0.0) {
      dp += tau_s * (v_ant_n + dv) - 0.5 * tau2_s2 * a_ant_n + tau2_s2 * tau_s / 6.0 * motion.j_n_mps3;
    }
    filter.ResetPositionVelocity(dp, dv, sigma_pos_m.cwiseAbs2(), vel_var, kReset);
  }

  const std::vector<GnssSample>& fixes_;
  GnssConfig config_;
  Eigen::Vector3d lever_b_m_;
  GnssInstallation installation_;  ///< the unknowns and the fixed values
  bool installed_ = false;         ///< the installation models (an unknown, or a time offset)
  int reset_after_;
  std::string path_;
  std::vector<double> times_;
  int rejected_in_row_ = 0;
};

}  // namespace

std::unique_ptr<AidingSource> MakeGnssSource(const std::vector<GnssSample>& fixes, const GnssConfig& config,
                                             const Eigen::Vector3d& antenna_lever_arm_b_m, int reset_rejections,
                                             const std::string& path) {
  return std::make_unique<GnssSource>(fixes, config, antenna_lever_arm_b_m, reset_rejections, path);
}

}  // namespace navtwin::ins
