#include "problems/ins/sources/odometer.h"

#include <algorithm>
#include <vector>

#include "core/rotation.h"
#include "factors/odometer_speed.h"
#include "problems/ins/association.h"

namespace navtwin::ins {
namespace {

const char* const kOdometer = "odometer";

class OdometerSource : public AidingSource {
 public:
  OdometerSource(const std::vector<OdometerSample>& samples, const OdometerConfig& config,
                 const VehicleConfig& vehicle)
      : config_(config),
        lever_b_m_(vehicle.lever_arm_b_m),
        R_v_b_(DcmFromEuler<double>(vehicle.mounting_rpy_rad[0], vehicle.mounting_rpy_rad[1],
                                    vehicle.mounting_rpy_rad[2])),
        samples_(samples) {
    times_.reserve(samples_.size());
    for (const OdometerSample& s : samples_) times_.push_back(s.t_s);
  }

  std::vector<std::string> keys() const override { return {kOdometer}; }
  Timing timing() const override { return Timing::kExact; }
  const std::vector<double>& times() const override { return times_; }
  std::vector<AuxState> aux_states() const override {
    return {{"odometer_scale", 0.0, config_.scale_std, "driving with GNSS (the odometer's speeds against the aided "
                                                       "velocity)"}};
  }

  void FilterUpdate(std::size_t k, FilterAccess& filter) override {
    filter.Update(std::unique_ptr<ceres::CostFunction>(Create(filter.omega_ib_b_radps(), samples_[k].speed_mps)),
                  {StateBlock::Velocity(), StateBlock::Attitude(), StateBlock::Aux(0)}, kOdometer);
  }

  void AddToBatch(BatchAccess& batch) override {
    double* scale = batch.aux(0);
    for (std::size_t i = 0; i < batch.num_states(); ++i) {
      const BatchAccess::State& s = batch.state(i);
      const auto hi = std::lower_bound(times_.begin(), times_.end(), s.t_s);
      if (hi == times_.end() || hi == times_.begin()) continue;  // not between two samples
      const std::size_t b = static_cast<std::size_t>(hi - times_.begin()), a = b - 1;
      if (times_[b] - times_[a] > 2.0 * kMaxSensorAssociation_s) {
        batch.Count(kOdometer, false);  // a gap in the record
        continue;
      }
      const double w = (s.t_s - times_[a]) / (times_[b] - times_[a]);
      const double speed_mps = (1.0 - w) * samples_[a].speed_mps + w * samples_[b].speed_mps;
      batch.Add(Create(s.omega_ib_b_radps, speed_mps), false, {s.vel, s.q, scale}, kOdometer);
    }
  }

 private:
  ceres::CostFunction* Create(const Eigen::Vector3d& omega_ib_b_radps, double speed_mps) const {
    return OdometerSpeed::Create(R_v_b_, lever_b_m_, omega_ib_b_radps, speed_mps, config_.std_mps);
  }

  OdometerConfig config_;
  Eigen::Vector3d lever_b_m_;
  Eigen::Matrix3d R_v_b_;
  const std::vector<OdometerSample>& samples_;
  std::vector<double> times_;
};

}  // namespace

std::unique_ptr<AidingSource> MakeOdometerSource(const std::vector<OdometerSample>& samples,
                                                 const OdometerConfig& config, const VehicleConfig& vehicle) {
  return std::make_unique<OdometerSource>(samples, config, vehicle);
}

}  // namespace navtwin::ins
