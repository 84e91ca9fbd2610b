#include "problems/ins/sources/nhc.h"

#include <cmath>

#include "core/rotation.h"
#include "factors/nhc_velocity.h"

namespace navtwin::ins {
namespace {

const char* const kNhc = "nhc";
/// Below this speed a vehicle whose IMU is still counts as standing (an IMU alone cannot
/// tell standing from cruising straight at constant speed, so the speed decides too).
constexpr double kStandingSpeed_mps = 0.5;

bool Standing(bool imu_still, const Eigen::Vector3d& v_n_mps) {
  return imu_still && v_n_mps.norm() < kStandingSpeed_mps;
}

class NhcSource : public AidingSource {
 public:
  NhcSource(const NhcConfig& config, const VehicleConfig& vehicle, const StillnessConfig& still_rule)
      : config_(config),
        lever_b_m_(vehicle.lever_arm_b_m),
        R_v_b_(DcmFromEuler<double>(vehicle.mounting_rpy_rad[0], vehicle.mounting_rpy_rad[1],
                                    vehicle.mounting_rpy_rad[2])),
        still_rule_(still_rule) {}

  std::vector<std::string> keys() const override { return {kNhc}; }
  bool noise_estimable() const override { return false; }
  Timing timing() const override { return Timing::kEveryEpoch; }
  const std::vector<double>& times() const override { return none_; }
  const StillnessConfig* stillness_rule() const override { return &still_rule_; }

  void FilterEpoch(FilterAccess& filter) override {
    const double t_s = filter.time_s();
    if (t_s - last_s_ < config_.interval_s - kSameEpoch_s) return;
    if (Standing(filter.still(), filter.nominal().nav.v_n_mps)) return;
    last_s_ = t_s;
    filter.Update(std::unique_ptr<ceres::CostFunction>(Create(filter.omega_ib_b_radps())),
                  {StateBlock::Velocity(), StateBlock::Attitude()}, kNhc);
  }

  void AddToBatch(BatchAccess& batch) override {
    for (std::size_t i = 0; i < batch.num_states(); ++i) {
      const BatchAccess::State& s = batch.state(i);
      if (!Standing(s.still, s.initial->nav.v_n_mps)) batch.Add(Create(s.omega_ib_b_radps), false, {s.vel, s.q}, kNhc);
    }
  }

 private:
  ceres::CostFunction* Create(const Eigen::Vector3d& omega_ib_b_radps) const {
    return NhcVelocity::Create(R_v_b_, lever_b_m_, omega_ib_b_radps, config_.std_mps, config_.std_mps);
  }

  NhcConfig config_;
  Eigen::Vector3d lever_b_m_;
  Eigen::Matrix3d R_v_b_;
  StillnessConfig still_rule_;
  std::vector<double> none_;
  double last_s_ = -INFINITY;
};

}  // namespace

std::unique_ptr<AidingSource> MakeNhcSource(const NhcConfig& config, const VehicleConfig& vehicle,
                                            const StillnessConfig& still_rule) {
  return std::make_unique<NhcSource>(config, vehicle, still_rule);
}

}  // namespace navtwin::ins
