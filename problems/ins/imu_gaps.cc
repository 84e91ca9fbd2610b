#include "problems/ins/imu_gaps.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "core/io/input_error.h"

namespace navtwin::ins {
namespace {

std::string Num(double x) {
  std::ostringstream s;
  s.precision(12);
  s << x;
  return s.str();
}

/// Streams the samples of another reader through an ImuGapBridge.
class GapBridgingReader final : public ImuReader {
 public:
  GapBridgingReader(std::unique_ptr<ImuReader> reader, double max_gap_s, std::string limit_name,
                    double time_offset_s, std::size_t* bridged)
      : reader_(std::move(reader)),
        max_gap_s_(max_gap_s),
        limit_name_(std::move(limit_name)),
        time_offset_s_(time_offset_s),
        bridged_(bridged) {}

  bool Next(ImuSample* sample) override {
    if (!bridge_) Start();
    while (next_ == ready_.size()) {
      ready_.clear();
      next_ = 0;
      ImuSample s;
      if (!reader_->Next(&s)) return false;
      bridge_->Add(s, &ready_);
      if (bridged_) *bridged_ = bridge_->bridged();
    }
    *sample = ready_[next_++];
    return true;
  }
  const std::string& path() const override { return reader_->path(); }

 private:
  /// Reads the first samples to find the nominal interval; they are served first.
  void Start() {
    std::vector<ImuSample> head;
    ImuSample s;
    while (head.size() < kGapLookahead && reader_->Next(&s)) head.push_back(s);
    const double nominal = head.empty() ? 0.0 : MedianInterval(head);
    bridge_ = std::make_unique<ImuGapBridge>(reader_->path(), nominal, max_gap_s_, time_offset_s_, limit_name_);
    for (const ImuSample& h : head) bridge_->Add(h, &ready_);
    if (bridged_) *bridged_ = bridge_->bridged();
  }

  std::unique_ptr<ImuReader> reader_;
  double max_gap_s_;
  std::string limit_name_;
  double time_offset_s_;
  std::size_t* bridged_;
  std::unique_ptr<ImuGapBridge> bridge_;
  std::vector<ImuSample> ready_;
  std::size_t next_ = 0;
};

}  // namespace

double MedianInterval(const std::vector<ImuSample>& imu) {
  std::vector<double> dt;
  dt.reserve(imu.size());
  for (const ImuSample& s : imu) dt.push_back(s.dt_s);
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  return dt[dt.size() / 2];
}

ImuGapBridge::ImuGapBridge(std::string path, double nominal_s, double max_gap_s, double time_offset_s,
                           std::string limit_name)
    : path_(std::move(path)),
      nominal_s_(nominal_s),
      max_gap_s_(max_gap_s),
      time_offset_s_(time_offset_s),
      limit_name_(std::move(limit_name)) {}

void ImuGapBridge::Add(const ImuSample& s, std::vector<ImuSample>* out) {
  if (s.dt_s <= kGapFactor * nominal_s_) {
    out->push_back(s);
    return;
  }
  const double t0 = s.t_s - s.dt_s;
  if (s.dt_s > max_gap_s_) {
    throw InputError(path_, 0, "time",
                     "IMU gap of " + Num(s.dt_s) + " s between t = " + Num(t0 - time_offset_s_) +
                         " s and t = " + Num(s.t_s - time_offset_s_) + " s (file time), longer than " +
                         limit_name_ + " = " + Num(max_gap_s_) + " s (nominal interval " + Num(nominal_s_) +
                         " s)");
  }
  const int n = std::max(2, static_cast<int>(std::lround(s.dt_s / nominal_s_)));
  for (int k = 1; k <= n; ++k) {
    ImuSample piece = s;
    piece.t_s = k == n ? s.t_s : t0 + s.dt_s * k / n;
    piece.dt_s = piece.t_s - (t0 + s.dt_s * (k - 1) / n);
    piece.dtheta_b_rad = s.dtheta_b_rad / n;
    piece.dv_b_mps = s.dv_b_mps / n;
    out->push_back(piece);
  }
  ++bridged_;
}

std::unique_ptr<ImuReader> GapBridgingImuReader(std::unique_ptr<ImuReader> reader, double max_gap_s,
                                                const std::string& limit_name, double time_offset_s,
                                                std::size_t* bridged) {
  return std::make_unique<GapBridgingReader>(std::move(reader), max_gap_s, limit_name, time_offset_s, bridged);
}

}  // namespace navtwin::ins
