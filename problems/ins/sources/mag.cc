#include "problems/ins/sources/mag.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "core/rotation.h"
#include "factors/mag_heading.h"
#include "factors/mag_vector.h"
#include "problems/ins/association.h"

namespace navtwin::ins {

Eigen::Quaterniond BodyRotation(const std::vector<ImuSample>& imu, double a, double b, const ImuErrors& e) {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  auto it = std::upper_bound(imu.begin(), imu.end(), a + kSameEpoch_s,
                             [](double t, const ImuSample& s) { return t < s.t_s; });
  for (; it != imu.end() && it->t_s - it->dt_s < b - kSameEpoch_s; ++it) {
    const double lo = std::max(it->t_s - it->dt_s, a);
    const double hi = std::min(it->t_s, b);
    if (hi <= lo) continue;
    const ImuSample c = CorrectImu(*it, e);
    q = q * QuatFromRotVec<double>(c.dtheta_b_rad * ((hi - lo) / it->dt_s));
  }
  return q.normalized();
}

namespace {

const char* const kMag = "mag";

class MagSource : public AidingSource {
 public:
  MagSource(const std::vector<MagSample>& samples, const MagConfig& config) : samples_(samples), config_(config) {
    if (config.mode == MagConfig::Mode::kVector && config.field_ned_uT.isZero(0.0)) {
      throw std::invalid_argument("magnetometer mode vector needs mag.field_ned_uT");
    }
    times_.reserve(samples.size());
    for (const MagSample& m : samples) times_.push_back(m.t_s);
  }

  std::vector<std::string> keys() const override { return {kMag}; }
  Timing timing() const override { return Timing::kNextEpoch; }
  const std::vector<double>& times() const override { return times_; }
  bool rotates_samples_to_states() const override { return config_.mode != MagConfig::Mode::kOff && !samples_.empty(); }

  void FilterUpdate(std::size_t k, FilterAccess& filter) override {
    const MagSample& sample = samples_[k];
    if (config_.mode == MagConfig::Mode::kOff) return;
    if (sample.t_s - last_used_s_ < config_.min_interval_s - kSameEpoch_s) return;
    const Eigen::Vector3d m = CalibrateMag(sample.m_b_uT, config_);
    const Eigen::Quaterniond& q = filter.nominal().nav.q_n_b;
    if (config_.mode == MagConfig::Mode::kHeading) {
      // The reference field (H0 and the dip direction of MagHeading; docs/gnss-ins.md,
      // "Magnetometer modes"): the mean of the samples so far rotated into NED with the
      // nominal attitudes.
      field_sum_uT_ += q * m;
      ++field_count_;
    }
    const Eigen::Vector3d mean_uT = field_count_ > 0 ? Eigen::Vector3d(field_sum_uT_ / field_count_)
                                                     : Eigen::Vector3d::Zero();
    std::unique_ptr<ceres::CostFunction> cost(Measurement(m, q, mean_uT));
    if (!cost) {
      filter.Count(kMag, false);
      return;
    }
    last_used_s_ = sample.t_s;
    filter.Update(std::move(cost), {StateBlock::Attitude()}, kMag);
  }

  void AddToBatch(BatchAccess& batch) override {
    if (config_.mode == MagConfig::Mode::kOff || samples_.empty()) return;
    const std::vector<std::pair<std::size_t, Eigen::Vector3d>> carried = CarriedToStates(batch);
    // kHeading: the reference field is the mean of the samples rotated into NED with the
    // initial attitudes (the filter's rule, with the whole record).
    Eigen::Vector3d field_sum_uT = Eigen::Vector3d::Zero();
    for (const auto& [i, m] : carried) field_sum_uT += batch.state(i).initial->nav.q_n_b * m;
    const Eigen::Vector3d mean_uT = field_sum_uT / std::max<std::size_t>(carried.size(), 1);
    for (const auto& [i, m] : carried) {
      const BatchAccess::State& s = batch.state(i);
      ceres::CostFunction* cost = Measurement(m, s.initial->nav.q_n_b, mean_uT);
      if (cost == nullptr) {
        batch.Count(kMag, false);
        continue;
      }
      batch.Add(cost, false, {s.q}, kMag);
    }
  }

 private:
  /// The cost function of calibrated body-axes sample m for the mode, linearisation
  /// attitude q; null when the mode's rule rejects the sample.
  ceres::CostFunction* Measurement(const Eigen::Vector3d& m, const Eigen::Quaterniond& q,
                                   const Eigen::Vector3d& mean_field_uT) const {
    switch (config_.mode) {
      case MagConfig::Mode::kVector:
        return MagVector::Create(m, config_.field_ned_uT, config_.noise_uT);
      case MagConfig::Mode::kHeading: {
        const double h0_uT = mean_field_uT.head<2>().norm();
        if (!(h0_uT > 0.0)) return nullptr;  // a vertical mean field: no heading
        return MagHeading::Create(MagHeading::RemoveDipNoise(m, q, mean_field_uT), config_.declination_rad,
                                  config_.heading_std_rad, h0_uT);
      }
      case MagConfig::Mode::kHeading2Axis: {
        const Eigen::Vector3d rpy = EulerFromQuat<double>(q);
        if (!(std::abs(rpy[0]) < config_.max_tilt_rad && std::abs(rpy[1]) < config_.max_tilt_rad)) {
          return nullptr;  // tilted: the 2-axis compass is not used
        }
        return MagHeading2Axis::Create(m.x(), m.y(), config_.declination_rad, config_.heading_std_rad);
      }
      case MagConfig::Mode::kOff:
        break;
    }
    return nullptr;
  }

  /// For each state with a sample (nearest, at most one per min_interval_s): the
  /// calibrated sample rotated into the body axes at the state's epoch.
  std::vector<std::pair<std::size_t, Eigen::Vector3d>> CarriedToStates(BatchAccess& batch) const {
    std::vector<double> times(batch.num_states());
    for (std::size_t i = 0; i < times.size(); ++i) times[i] = batch.state(i).t_s;
    const std::vector<long> nearest = AssociateNearest(samples_, times);
    std::vector<std::pair<std::size_t, Eigen::Vector3d>> carried;
    double last_used_s = -INFINITY;
    for (std::size_t i = 0; i < times.size(); ++i) {
      if (nearest[i] < 0) continue;
      const BatchAccess::State& s = batch.state(i);
      const MagSample& sample = samples_[static_cast<std::size_t>(nearest[i])];
      if (sample.t_s - last_used_s < config_.min_interval_s - kSameEpoch_s) continue;
      const Eigen::Vector3d m_sample = CalibrateMag(sample.m_b_uT, config_);
      Eigen::Vector3d m = m_sample;
      if (sample.t_s > s.t_s) {
        m = batch.BodyRotation(s.t_s, sample.t_s, s.initial->imu) * m_sample;
      } else if (sample.t_s < s.t_s) {
        m = batch.BodyRotation(sample.t_s, s.t_s, s.initial->imu).conjugate() * m_sample;
      }
      if (!m.allFinite()) {
        batch.Count(kMag, false);
        continue;
      }
      carried.emplace_back(i, m);
      last_used_s = sample.t_s;
    }
    return carried;
  }

  const std::vector<MagSample>& samples_;
  MagConfig config_;
  std::vector<double> times_;
  double last_used_s_ = -INFINITY;
  Eigen::Vector3d field_sum_uT_ = Eigen::Vector3d::Zero();
  double field_count_ = 0.0;
};

}  // namespace

Eigen::Vector3d CalibrateMag(const Eigen::Vector3d& m_raw_uT, const MagConfig& mag) {
  return mag.iron.Remove(m_raw_uT);
}

std::unique_ptr<AidingSource> MakeMagSource(const std::vector<MagSample>& samples, const MagConfig& config) {
  return std::make_unique<MagSource>(samples, config);
}

}  // namespace navtwin::ins
