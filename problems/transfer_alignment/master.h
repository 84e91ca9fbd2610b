// The master INS stream of transfer alignment: records as received (time tag = arrival),
// each carrying the master's attitude and velocity at (tag - delay), and the derivatives
// the delay compensation needs (problems/transfer_alignment/delay_model.h): body rate omega_nb^b and its rate, and
// dv_n/dt and its rate. A master navigation file holds attitude and velocity only (the
// simulator's master.nav, the DJI solution of the ANSFL flights), so the derivatives are
// estimated from the records (docs/transfer-alignment.md, "Derivatives of the master
// stream": the differentiators, their lag and noise gain).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/types.h"
#include "problems/transfer_alignment/delay_model.h"

namespace navtwin::transfer {

enum class DerivativeMode {
  /// Only records up to k (what a filter has when record k arrives): backward
  /// differences, omega at k from records k-1, k (lag half a record interval), omega_dot
  /// from the last two omegas (a further half interval), likewise a and a_dot.
  kCausal,
  /// Centred differences over k-1, k, k+1 (no lag; the batch, which has every record).
  kCentral,
};

class MasterStream {
 public:
  /// records: the master's NavState with t_s = the time tag; at least 3, tags strictly
  /// increasing, finite. Throws InputError (file `path`, "record N", field) otherwise.
  ///
  /// fit_records >= 3 (kCausal only): instead of differences, omega, omega_dot, a, a_dot at
  /// record k come from a least-squares quadratic over the last fit_records records
  /// (attitude: the rotation vectors Log(R_k^T R_j); velocity: v_j; against t_j - t_k),
  /// evaluated at t_k: no lag for motion quadratic over the window, and the noise of the
  /// second derivative falls as the window grows (docs/transfer-alignment.md). Records
  /// before the window is full use the differences. 0: differences only.
  MasterStream(std::vector<NavState> records, DerivativeMode mode, const std::string& path = "master",
               int fit_records = 0);

  /// Gain of the order-2 (or order-1) velocity compensation v_k + a tau + a_dot tau^2 / 2
  /// on white velocity noise of the records: sqrt(sum of the squared weights of the v_j),
  /// for uniformly spaced records at the stream's median spacing.
  double VelocityNoiseGain(double tau_s, DelayOrder order) const;

  std::size_t size() const { return records_.size(); }
  const NavState& record(std::size_t k) const { return records_[k]; }
  /// Attitude, velocity and derivatives at record k (data time tag_k - delay).
  const MasterKinematics& kinematics(std::size_t k) const { return kinematics_[k]; }
  /// The last record whose tag is <= t_s (npos if none).
  std::size_t LastAtOrBefore(double t_s) const;
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);

 private:
  std::vector<NavState> records_;
  std::vector<MasterKinematics> kinematics_;
  int fit_records_ = 0;
  double median_dt_s_ = 0.0;
};

}  // namespace navtwin::transfer
