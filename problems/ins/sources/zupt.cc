#include "problems/ins/sources/zupt.h"

#include <cmath>

#include "factors/zero_velocity.h"

namespace navtwin::ins {
namespace {

const char* const kZupt = "zupt";

class ZuptSource : public AidingSource {
 public:
  explicit ZuptSource(const ZuptConfig& config) : config_(config) {}

  std::vector<std::string> keys() const override { return {kZupt}; }
  bool noise_estimable() const override { return false; }
  Timing timing() const override { return Timing::kEveryEpoch; }
  const std::vector<double>& times() const override { return none_; }
  const StillnessConfig* stillness_rule() const override { return config_.enabled ? &config_ : nullptr; }

  void FilterEpoch(FilterAccess& filter) override {
    const double t_s = filter.time_s();
    if (!config_.enabled || !filter.still() || t_s - last_s_ < config_.interval_s - kSameEpoch_s) return;
    last_s_ = t_s;
    filter.Update(std::unique_ptr<ceres::CostFunction>(ZeroVelocity::Create(config_.std_mps)),
                  {StateBlock::Velocity()}, kZupt);
  }

  void AddToBatch(BatchAccess& batch) override {
    if (!config_.enabled) return;
    for (std::size_t i = 0; i < batch.num_states(); ++i) {
      const BatchAccess::State& s = batch.state(i);
      if (s.still) batch.Add(ZeroVelocity::Create(config_.std_mps), false, {s.vel}, kZupt);
    }
  }

 private:
  ZuptConfig config_;
  std::vector<double> none_;
  double last_s_ = -INFINITY;
};

}  // namespace

std::unique_ptr<AidingSource> MakeZuptSource(const ZuptConfig& config) {
  return std::make_unique<ZuptSource>(config);
}

}  // namespace navtwin::ins
