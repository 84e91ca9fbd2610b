#include "problems/ins/sources/gnss.h"

#include <sstream>

#include "core/io/input_error.h"
#include "factors/gnss_position.h"
#include "factors/gnss_velocity.h"
#include "factors/position_manifold.h"
#include "problems/ins/measurement_rules.h"

namespace navtwin::ins {
namespace {

const char* const kPosition = "gnss_position";
const char* const kVelocity = "gnss_velocity";
const char* const kReset = "gnss_reset";

class GnssSource : public AidingSource {
 public:
  GnssSource(const std::vector<GnssSample>& fixes, const GnssConfig& config, const Eigen::Vector3d& lever_b_m,
             int reset_rejections, std::string path)
      : fixes_(fixes), config_(config), lever_b_m_(lever_b_m), reset_after_(reset_rejections), path_(std::move(path)) {
    times_.reserve(fixes.size());
    for (const GnssSample& g : fixes) times_.push_back(g.t_s);
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
    const bool position_used =
        filter.Update(std::unique_ptr<ceres::CostFunction>(
                          GnssPosition::Create(Eigen::Vector3d(g.lat_rad, g.lon_rad, g.h_m), lever_b_m_, sp)),
                      {StateBlock::Position(), StateBlock::Attitude()}, kPosition, check);
    const bool use_velocity = config_.use_velocity && g.has_velocity;
    const Eigen::Vector3d sv = VelocitySigma(g);
    if (use_velocity) {
      filter.Update(std::unique_ptr<ceres::CostFunction>(
                        GnssVelocity::Create(g.v_n_mps, lever_b_m_, filter.omega_ib_b_radps(), sv)),
                    {StateBlock::Velocity(), StateBlock::Attitude()}, kVelocity);
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
    for (std::size_t i = 0; i < batch.num_states(); ++i) {
      const BatchAccess::State& s = batch.state(i);
      if (s.anchor < 0) continue;
      const GnssSample& g = fixes_[static_cast<std::size_t>(s.anchor)];
      batch.Add(GnssPosition::Create(Eigen::Vector3d(g.lat_rad, g.lon_rad, g.h_m), lever_b_m_, PositionSigma(g)),
                true, {s.pos, s.q}, kPosition);
      if (config_.use_velocity && g.has_velocity) {
        batch.Add(GnssVelocity::Create(g.v_n_mps, lever_b_m_, s.omega_ib_b_radps, VelocitySigma(g)), true,
                  {s.vel, s.q}, kVelocity);
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

  /// The filter no longer believes the receiver (its covariance is too small for its own
  /// error): position (and velocity, when the fix has it) are reset to the fix; without a
  /// GNSS velocity the velocity keeps its value with 1 (m/s)^2 of variance.
  void Reset(const GnssSample& g, const Eigen::Vector3d& sigma_pos_m, const Eigen::Vector3d* sigma_vel_mps,
             FilterAccess& filter) const {
    const NavState& s = filter.nominal().nav;
    const Eigen::Matrix3d R_n_b = s.q_n_b.toRotationMatrix();
    const double antenna[3] = {g.lat_rad, g.lon_rad, g.h_m};
    const double pos[3] = {s.lat_rad, s.lon_rad, s.h_m};
    Eigen::Vector3d ins_minus_fix_ned;
    PositionMinus(pos, antenna, ins_minus_fix_ned.data());
    const Eigen::Vector3d dp = -(ins_minus_fix_ned + R_n_b * lever_b_m_);
    Eigen::Vector3d dv = Eigen::Vector3d::Zero();
    Eigen::Vector3d vel_var = Eigen::Vector3d::Ones();
    if (sigma_vel_mps != nullptr) {
      dv = g.v_n_mps - (s.v_n_mps + R_n_b * filter.omega_ib_b_radps().cross(lever_b_m_));
      vel_var = sigma_vel_mps->cwiseAbs2();
    }
    filter.ResetPositionVelocity(dp, dv, sigma_pos_m.cwiseAbs2(), vel_var, kReset);
  }

  const std::vector<GnssSample>& fixes_;
  GnssConfig config_;
  Eigen::Vector3d lever_b_m_;
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
