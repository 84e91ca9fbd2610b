#include "core/io/file_summary.h"

#include <algorithm>

namespace navtwin {

void TimeTagStats::Add(double t_s) {
  if (count_ == 0) {
    first_s_ = t_s;
  } else {
    dt_s_.push_back(static_cast<float>(t_s - last_s_));
  }
  last_s_ = t_s;
  ++count_;
}

double TimeTagStats::median_dt_s() const {
  if (dt_s_.empty()) return 0.0;
  std::vector<float> v = dt_s_;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

double TimeTagStats::rate_hz() const {
  const double dt = median_dt_s();
  return dt > 0.0 ? 1.0 / dt : 0.0;
}

double TimeTagStats::mean_rate_hz() const {
  return span_s() > 0.0 ? static_cast<double>(count_ - 1) / span_s() : 0.0;
}

std::size_t TimeTagStats::gap_count(double gap_factor) const {
  const double limit = gap_factor * median_dt_s();
  return static_cast<std::size_t>(
      std::count_if(dt_s_.begin(), dt_s_.end(), [limit](float dt) { return dt > limit; }));
}

double TimeTagStats::max_dt_s() const {
  return dt_s_.empty() ? 0.0 : *std::max_element(dt_s_.begin(), dt_s_.end());
}

StreamSummary StreamSummary::FromStats(const std::string& name, const TimeTagStats& stats,
                                       std::vector<std::string> fields) {
  StreamSummary s;
  s.name = name;
  s.count = stats.count();
  s.t_first_s = stats.first_s();
  s.t_last_s = stats.last_s();
  s.rate_hz = stats.rate_hz();
  s.mean_rate_hz = stats.mean_rate_hz();
  s.gaps = stats.gap_count();
  s.max_gap_s = stats.max_dt_s();
  s.fields = std::move(fields);
  return s;
}

}  // namespace navtwin
