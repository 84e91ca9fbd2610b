#include "problems/ins/sources/baro.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "factors/baro_height.h"
#include "problems/ins/association.h"

namespace navtwin::ins {
namespace {

const char* const kBaro = "baro";

class BaroSource : public AidingSource {
 public:
  BaroSource(const std::vector<BaroSample>& samples, const BaroConfig& config, std::vector<double> reference_times_s)
      : samples_(samples), config_(config), reference_times_s_(std::move(reference_times_s)) {
    times_.reserve(samples.size());
    for (const BaroSample& b : samples) times_.push_back(b.t_s);
  }

  std::vector<std::string> keys() const override { return {kBaro}; }
  Timing timing() const override { return Timing::kNextEpoch; }
  const std::vector<double>& times() const override { return times_; }

  void BeginFilter(double first_time_s) override {
    const auto it = std::lower_bound(reference_times_s_.begin(), reference_times_s_.end(), first_time_s);
    first_reference_s_ = it == reference_times_s_.end() ? INFINITY : *it;
  }

  void FilterUpdate(std::size_t k, FilterAccess& filter) override {
    if (!config_.use) return;
    const BaroSample& b = samples_[k];
    if (!std::isfinite(b.altitude_m)) {
      filter.Count(kBaro, false);
      return;
    }
    if (!offset_m_) {
      // Earlier samples than the first height reference are not used.
      if (!reference_times_s_.empty() && first_reference_s_ > filter.time_s() + kSameEpoch_s) {
        filter.Count(kBaro, false);
        return;
      }
      offset_m_ = b.altitude_m - filter.nominal().nav.h_m;
    }
    filter.Update(std::unique_ptr<ceres::CostFunction>(BaroHeight::Create(b.altitude_m - *offset_m_, config_.std_m)),
                  {StateBlock::Position()}, kBaro);
  }

  void AddToBatch(BatchAccess& batch) override {
    if (!config_.use || samples_.empty() || batch.num_states() == 0) return;
    std::optional<double> offset_m;
    double offset_t_s = 0.0;
    TakeOffset(batch, &offset_m, &offset_t_s);
    std::vector<double> times(batch.num_states());
    for (std::size_t i = 0; i < times.size(); ++i) times[i] = batch.state(i).t_s;
    const std::vector<long> nearest = AssociateNearest(samples_, times);
    for (std::size_t i = 0; i < times.size(); ++i) {
      if (nearest[i] < 0) continue;
      const BatchAccess::State& s = batch.state(i);
      const BaroSample& b = samples_[static_cast<std::size_t>(nearest[i])];
      if (!offset_m || b.t_s < offset_t_s - kSameEpoch_s || !std::isfinite(b.altitude_m)) {
        batch.Count(kBaro, false);
        continue;
      }
      // Carried to the state time with the initial vertical velocity: dh/dt = -v_d.
      const double h_m = b.altitude_m - *offset_m - s.initial->nav.v_n_mps.z() * (s.t_s - b.t_s);
      batch.Add(BaroHeight::Create(h_m, config_.std_m), false, {s.pos}, kBaro);
    }
  }

 private:
  /// The offset altitude - height at the first usable sample at or after the first
  /// anchored state (or the first state), the initial height interpolated between the
  /// states around the sample.
  void TakeOffset(BatchAccess& batch, std::optional<double>* offset_m, double* offset_t_s) const {
    const std::size_t n = batch.num_states();
    double from_s = batch.state(0).t_s;
    for (std::size_t i = 0; i < n; ++i) {
      if (batch.state(i).anchor >= 0) {
        from_s = batch.state(i).t_s;
        break;
      }
    }
    for (const BaroSample& b : samples_) {
      if (b.t_s < from_s - kSameEpoch_s || !std::isfinite(b.altitude_m)) continue;
      if (b.t_s > batch.state(n - 1).t_s + kSameEpoch_s) break;
      std::size_t hi = 0;
      while (hi < n && !(b.t_s < batch.state(hi).t_s)) ++hi;
      const BatchAccess::State& upper = hi == n ? batch.state(n - 1) : batch.state(hi);
      const BatchAccess::State& lower = hi == 0 ? batch.state(0) : batch.state(hi - 1);
      const double span = upper.t_s - lower.t_s;
      const double a = span > 0.0 ? (b.t_s - lower.t_s) / span : 0.0;
      const double h = (1.0 - a) * lower.initial->nav.h_m + a * upper.initial->nav.h_m;
      *offset_m = b.altitude_m - h;
      *offset_t_s = b.t_s;
      return;
    }
  }

  const std::vector<BaroSample>& samples_;
  BaroConfig config_;
  std::vector<double> reference_times_s_;
  std::vector<double> times_;
  double first_reference_s_ = INFINITY;
  std::optional<double> offset_m_;
};

}  // namespace

std::unique_ptr<AidingSource> MakeBaroSource(const std::vector<BaroSample>& samples, const BaroConfig& config,
                                             std::vector<double> reference_times_s) {
  return std::make_unique<BaroSource>(samples, config, std::move(reference_times_s));
}

}  // namespace navtwin::ins
