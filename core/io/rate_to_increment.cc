#include "core/io/rate_to_increment.h"

#include <stdexcept>

namespace navtwin {

bool RateToIncrement::Add(const RateSample& sample, ImuSample* out) {
  if (!has_previous_) {
    previous_ = sample;
    has_previous_ = true;
    return false;
  }
  const double dt_s = sample.t_s - previous_.t_s;
  if (!(dt_s > 0.0)) {
    throw std::invalid_argument("RateToIncrement: time does not increase");
  }
  out->t_s = sample.t_s;
  out->dt_s = dt_s;
  out->dtheta_b_rad = 0.5 * (previous_.gyro_radps + sample.gyro_radps) * dt_s;
  out->dv_b_mps = 0.5 * (previous_.acc_mps2 + sample.acc_mps2) * dt_s;
  previous_ = sample;
  return true;
}

bool IncrementIntervals::Add(const ImuSample& row, ImuSample* out) {
  ++rows_;
  if (!has_pending_) {
    pending_ = row;
    has_pending_ = true;
    return false;
  }
  if (rows_ == 2) previous_t_s_ = pending_.t_s - (row.t_s - pending_.t_s);
  *out = pending_;
  out->dt_s = pending_.t_s - previous_t_s_;
  previous_t_s_ = pending_.t_s;
  pending_ = row;
  return true;
}

bool IncrementIntervals::Flush(ImuSample* out) {
  if (!has_pending_) return false;
  if (rows_ < 2) throw std::logic_error("IncrementIntervals: one row gives no interval");
  *out = pending_;
  out->dt_s = pending_.t_s - previous_t_s_;
  has_pending_ = false;
  return true;
}

}  // namespace navtwin
