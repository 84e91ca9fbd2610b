// PX4's own estimate (EKF2 output topics) as navigation states: OpenULogPx4Estimate in
// core/io/ulog.h. Three cursors walk the file side by side, one per topic, so the log
// is streamed, never held in memory.
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <utility>

#include <Eigen/Geometry>

#include "core/io/input_error.h"
#include "core/io/ulog.h"
#include "core/io/ulog_time.h"
#include "core/io/ulog_topic.h"
#include "core/units.h"

namespace navtwin {
namespace {

using ulog::SampleTime;
using ulog::TimeOrderedTopic;

/// Longest interval between the two samples an epoch is interpolated from (velocity is
/// logged at 10 Hz, attitude at 20-50 Hz: 0.5 s is several missing samples).
constexpr std::int64_t kMaxBracket_us = 500000;
/// A logged quaternion further than this from unit norm is an input error, not rounding
/// (float q has a norm error of a few 1e-7).
constexpr double kQuaternionNormTolerance = 1e-3;

/// One sample of a topic that is interpolated to the position epochs.
struct EstimateSample {
  std::int64_t t_us = 0;
  Eigen::Vector4d value = Eigen::Vector4d::Zero();  ///< velocity (x, y, z, 0) or q (w, x, y, z)
  int reset = 0;                                    ///< reset counter(s) of the quantity
  bool valid = true;                                ///< the topic's validity flags
};

enum class EstimateLookup { kOk, kOutside, kGap, kInvalid };

/// 1 when a boolean field is absent (older formats) or true.
bool FlagOrTrue(const TimeOrderedTopic& topic, const char* field) {
  return !topic.log().HasField(field) || topic.Finite(field) != 0.0;
}

/// A counter field, 0 when absent.
int CounterOrZero(const TimeOrderedTopic& topic, const char* field) {
  return topic.log().HasField(field) ? static_cast<int>(topic.Finite(field)) : 0;
}

/// A topic read one sample ahead, so that the two samples around an epoch are at hand.
class EstimateBracket {
 public:
  using Decode = std::function<EstimateSample(const TimeOrderedTopic&)>;
  EstimateBracket(TimeOrderedTopic topic, Decode decode, bool spherical)
      : topic_(std::move(topic)), decode_(std::move(decode)), spherical_(spherical) {}

  /// The value at t_us (epochs must come in increasing time); *across_reset is set when
  /// the nearer sample was taken because a reset lies between the two.
  EstimateLookup At(std::int64_t t_us, Eigen::Vector4d* value, bool* across_reset) {
    *across_reset = false;
    if (!primed_) {
      primed_ = true;
      has_upper_ = Read(&upper_);
    }
    while (has_upper_ && upper_.t_us < t_us) {
      lower_ = upper_;
      has_lower_ = true;
      has_upper_ = Read(&upper_);
    }
    if (!has_upper_) return EstimateLookup::kOutside;
    if (upper_.t_us == t_us) return Take(upper_, value);
    if (!has_lower_) return EstimateLookup::kOutside;
    if (upper_.t_us - lower_.t_us > kMaxBracket_us) return EstimateLookup::kGap;
    if (lower_.reset != upper_.reset) {
      *across_reset = true;
      return Take(t_us - lower_.t_us <= upper_.t_us - t_us ? lower_ : upper_, value);
    }
    if (!lower_.valid || !upper_.valid) return EstimateLookup::kInvalid;
    const double w = static_cast<double>(t_us - lower_.t_us) /
                     static_cast<double>(upper_.t_us - lower_.t_us);
    *value = spherical_ ? Slerp(lower_.value, upper_.value, w)
                        : Eigen::Vector4d((1.0 - w) * lower_.value + w * upper_.value);
    return EstimateLookup::kOk;
  }

 private:
  bool Read(EstimateSample* sample) {
    if (!topic_.Next()) return false;
    *sample = decode_(topic_);
    sample->t_us = topic_.time_us();
    return true;
  }
  static EstimateLookup Take(const EstimateSample& s, Eigen::Vector4d* value) {
    if (!s.valid) return EstimateLookup::kInvalid;
    *value = s.value;
    return EstimateLookup::kOk;
  }
  static Eigen::Vector4d Slerp(const Eigen::Vector4d& a, const Eigen::Vector4d& b, double w) {
    const Eigen::Quaterniond qa(a[0], a[1], a[2], a[3]);
    const Eigen::Quaterniond qb(b[0], b[1], b[2], b[3]);
    const Eigen::Quaterniond q = qa.slerp(w, qb);  // the shorter arc
    return {q.w(), q.x(), q.y(), q.z()};
  }

  TimeOrderedTopic topic_;
  Decode decode_;
  bool spherical_;
  bool primed_ = false;
  bool has_lower_ = false;
  bool has_upper_ = false;
  EstimateSample lower_;
  EstimateSample upper_;
};

EstimateSample DecodeLocalVelocity(const TimeOrderedTopic& t) {
  EstimateSample s;
  s.value = {t.Finite("vx"), t.Finite("vy"), t.Finite("vz"), 0.0};
  // Both counters in one number: a reset of either is a discontinuity.
  s.reset = 256 * CounterOrZero(t, "vxy_reset_counter") + CounterOrZero(t, "vz_reset_counter");
  s.valid = FlagOrTrue(t, "v_xy_valid") && FlagOrTrue(t, "v_z_valid");
  return s;
}

EstimateSample DecodeAttitude(const TimeOrderedTopic& t) {
  EstimateSample s;
  s.value = {t.Finite("q", 0), t.Finite("q", 1), t.Finite("q", 2), t.Finite("q", 3)};
  const double norm = s.value.norm();
  if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
    throw t.ErrorAt("q", "not a unit quaternion (norm " + ulog::FormatNumber(norm) + ")");
  }
  s.value /= norm;
  s.reset = CounterOrZero(t, "quat_reset_counter");
  return s;
}

class ULogPx4EstimateReader final : public Px4EstimateReader {
 public:
  ULogPx4EstimateReader(const std::string& path, const ULogClock& clock)
      : path_(path),
        global_(path, ulog::ChooseTopic(path, {{"vehicle_global_position", "lat", ""}}, "position"),
                clock, SampleTime::kTimestampSample),
        velocity_(TimeOrderedTopic(path,
                                   ulog::ChooseTopic(path, {{"vehicle_local_position", "vx", ""}},
                                                     "velocity"),
                                   clock, SampleTime::kTimestampSample),
                  DecodeLocalVelocity, false),
        attitude_(TimeOrderedTopic(path,
                                   ulog::ChooseTopic(path, {{"vehicle_attitude", "q", ""}},
                                                     "attitude"),
                                   clock, SampleTime::kTimestampSample),
                  DecodeAttitude, true) {
    const std::vector<ULogSubscription> subs = ListULogSubscriptions(path);
    const ULogSubscription* sub =
        ulog::FindSubscription(subs, {"vehicle_global_position", "lat", ""});
    stats_.ellipsoid = sub != nullptr && ulog::SubscriptionHasField(*sub, "alt_ellipsoid");
    stats_.height_field = stats_.ellipsoid ? "alt_ellipsoid" : "alt";
  }

  bool Next(NavState* s) override {
    while (global_.Next()) {
      if (!FlagOrTrue(global_, "lat_lon_valid") || !FlagOrTrue(global_, "alt_valid")) {
        ++stats_.invalid;
        continue;
      }
      Eigen::Vector4d v = Eigen::Vector4d::Zero();
      Eigen::Vector4d q = Eigen::Vector4d::Zero();
      bool v_reset = false, q_reset = false;
      const EstimateLookup lv = velocity_.At(global_.time_us(), &v, &v_reset);
      const EstimateLookup lq = attitude_.At(global_.time_us(), &q, &q_reset);
      if (!Count(lv, lq)) continue;
      if (v_reset || q_reset) ++stats_.across_reset;
      FillPosition(s);
      s->v_n_mps = v.head<3>();
      s->q_n_b = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
      ++stats_.epochs;
      return true;
    }
    return false;
  }
  const std::string& path() const override { return path_; }
  const Px4EstimateStats& stats() const override { return stats_; }

 private:
  // Counts a skipped epoch by its first reason; true when both lookups succeeded.
  bool Count(EstimateLookup a, EstimateLookup b) {
    for (const EstimateLookup reason :
         {EstimateLookup::kOutside, EstimateLookup::kGap, EstimateLookup::kInvalid}) {
      if (a != reason && b != reason) continue;
      ++(reason == EstimateLookup::kOutside ? stats_.outside
         : reason == EstimateLookup::kGap   ? stats_.gaps
                                            : stats_.invalid);
      return false;
    }
    return true;
  }

  void FillPosition(NavState* s) const {
    const double lat_deg = global_.Finite("lat");
    const double lon_deg = global_.Finite("lon");
    if (std::abs(lat_deg) > 90.0 || std::abs(lon_deg) > 180.0) {
      throw global_.ErrorAt("lat", "latitude/longitude out of range (" +
                                       ulog::FormatNumber(lat_deg) + ", " +
                                       ulog::FormatNumber(lon_deg) + " deg)");
    }
    s->t_s = global_.t_s();
    s->gps_week = global_.clock().gps_week;
    s->lat_rad = lat_deg * kDegToRad;
    s->lon_rad = lon_deg * kDegToRad;
    s->h_m = global_.Finite(stats_.height_field);
  }

  std::string path_;
  TimeOrderedTopic global_;
  EstimateBracket velocity_;
  EstimateBracket attitude_;
  Px4EstimateStats stats_;
};

}  // namespace

std::unique_ptr<Px4EstimateReader> OpenULogPx4Estimate(const std::string& path) {
  return std::make_unique<ULogPx4EstimateReader>(path, FindULogClock(path));
}

}  // namespace navtwin
