// The transfer-alignment filters' shared model (filter_model.h).
#include "problems/transfer_alignment/filter_model.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/earth.h"
#include "core/imu_error_model.h"
#include "core/imu_split.h"
#include "problems/ins/ins_state.h"

namespace navtwin::transfer {
namespace {

// Memory over which an unestimated slave bias is covered by process noise (header
// comment): the attitude matching observes phi at 50 Hz, so the filter's memory of phi is
// seconds; 10 s makes the bias term about equal to the tactical ARW term.
constexpr double kBiasMemory_s = 10.0;
// Random walks of the misalignment (structural flexure) and of the delay (clock wander):
// 1 urad/sqrt(s) gives 14 urad over 200 s, 10 us/sqrt(s) 0.14 ms, both far below what the
// filter resolves, so they only keep the gains from vanishing.
constexpr double kMisalignmentWalk_rad_sqrt_s = 1e-6;
constexpr double kDelayWalk_s_sqrt_s = 1e-5;
constexpr double kTimeEpsilon_s = 1e-9;

}  // namespace

void CheckTransferFilterConfig(const TransferConfig& c, const char* who) {
  const auto require = [who](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string(who) + ": configuration: " + what);
  };
  auto non_negative = [](double x) { return std::isfinite(x) && x >= 0.0; };
  auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  require(non_negative(c.gyro_bias_radps), "gyro_bias_radps must be >= 0");
  require(non_negative(c.gyro_arw_rad_per_sqrt_s), "gyro_arw_rad_per_sqrt_s must be >= 0");
  require(non_negative(c.accel_bias_mps2), "accel_bias_mps2 must be >= 0");
  require(non_negative(c.accel_vrw_mps_per_sqrt_s), "accel_vrw_mps_per_sqrt_s must be >= 0");
  require(positive(c.initial_velocity_mps), "initial_velocity_mps must be > 0");
  require(positive(c.initial_attitude_rad), "initial_attitude_rad must be > 0");
  require(positive(c.misalignment_rad), "misalignment_rad must be > 0");
  require(positive(c.delay_s), "delay_s must be > 0");
  require(std::isfinite(c.delay_initial_s), "delay_initial_s must be finite");
  require(positive(c.master_attitude_rad), "master_attitude_rad must be > 0");
  require(positive(c.master_velocity_mps), "master_velocity_mps must be > 0");
  require(c.lever_arm_b_m.allFinite(), "lever_arm_b_m must be finite");
  require(positive(c.history_window_s), "history_window_s must be > 0");
}

int MasterFitRecords(const std::vector<NavState>& master, double window_s) {
  if (!(window_s > 0.0) || master.size() < 3) return 0;
  std::vector<double> dts;
  for (std::size_t k = 1; k < master.size(); ++k) dts.push_back(master[k].t_s - master[k - 1].t_s);
  std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
  const double dt = dts[dts.size() / 2];
  if (!(dt > 0.0)) return 0;
  return std::max(3, static_cast<int>(std::lround(window_s / dt)) + 1);
}

TransferVector TransferInitialSigma(const TransferConfig& c) {
  TransferVector sd;
  sd.segment<3>(tstate::kVel).setConstant(c.initial_velocity_mps);
  sd.segment<3>(tstate::kAtt).setConstant(c.initial_attitude_rad);
  sd.segment<3>(tstate::kMis).setConstant(c.misalignment_rad);
  sd(tstate::kTau) = c.delay_s;
  return sd;
}

TransferVector TransferProcessNoise(const TransferConfig& c, SlaveBiases biases) {
  TransferVector q;
  const bool as_noise = biases == SlaveBiases::kAsNoise;
  const double bg = as_noise ? c.gyro_bias_radps : 0.0, ba = as_noise ? c.accel_bias_mps2 : 0.0;
  q.segment<3>(tstate::kVel).setConstant(std::pow(c.accel_vrw_mps_per_sqrt_s, 2) + ba * ba * kBiasMemory_s);
  q.segment<3>(tstate::kAtt).setConstant(std::pow(c.gyro_arw_rad_per_sqrt_s, 2) + bg * bg * kBiasMemory_s);
  q.segment<3>(tstate::kMis).setConstant(kMisalignmentWalk_rad_sqrt_s * kMisalignmentWalk_rad_sqrt_s);
  q(tstate::kTau) = kDelayWalk_s_sqrt_s * kDelayWalk_s_sqrt_s;
  return q;
}

InstrumentPrior InstrumentPriorSigma(const TransferConfig& c) {
  InstrumentPrior sd;
  sd.segment<3>(istate::kSg).setConstant(c.gyro_scale_factor);
  sd.segment<6>(istate::kMg).setConstant(c.gyro_axis_misalignment_rad);
  sd.segment<3>(istate::kSa).setConstant(c.accel_scale_factor);
  sd.segment<6>(istate::kMa).setConstant(c.accel_axis_misalignment_rad);
  sd.segment<3>(istate::kBg).setConstant(c.gyro_bias_radps);
  sd.segment<3>(istate::kBa).setConstant(c.accel_bias_mps2);
  return sd;
}

void TransferErrorDynamics(const NavState& nav, const ImuSample& s, TransferMatrix* F,
                           InstrumentColumns* F_instrument) {
  using tstate::kAtt;
  using tstate::kVel;
  const double dt = s.dt_s;
  ins::InsState x;
  x.nav = nav;
  const Eigen::Vector3d f_s = s.dv_b_mps / dt, w_s = s.dtheta_b_rad / dt;
  // The noise does not enter F.
  const Eigen::MatrixXd F15 = ins::ErrorDynamicsF(x, f_s, w_s, ins::ImuNoise{}, ins::err::kSize15);
  F->setZero();
  F->block<3, 3>(kVel, kVel) = F15.block<3, 3>(ins::err::kVel, ins::err::kVel);
  F->block<3, 3>(kVel, kAtt) = F15.block<3, 3>(ins::err::kVel, ins::err::kAtt);
  F->block<3, 3>(kAtt, kVel) = F15.block<3, 3>(ins::err::kAtt, ins::err::kVel);
  F->block<3, 3>(kAtt, kAtt) = F15.block<3, 3>(ins::err::kAtt, ins::err::kAtt);
  if (F_instrument == nullptr) return;
  const Eigen::Matrix3d F_att_bg = F15.block<3, 3>(ins::err::kAtt, ins::err::kBg);
  const Eigen::Matrix3d F_vel_ba = F15.block<3, 3>(ins::err::kVel, ins::err::kBa);
  F_instrument->setZero();
  F_instrument->block<3, 3>(kAtt, istate::kSg) = F_att_bg * w_s.asDiagonal();
  F_instrument->block<3, 6>(kAtt, istate::kMg) = F_att_bg * MisalignmentColumns(w_s);
  F_instrument->block<3, 3>(kVel, istate::kSa) = F_vel_ba * f_s.asDiagonal();
  F_instrument->block<3, 6>(kVel, istate::kMa) = F_vel_ba * MisalignmentColumns(f_s);
  F_instrument->block<3, 3>(kAtt, istate::kBg) = F_att_bg;
  F_instrument->block<3, 3>(kVel, istate::kBa) = F_vel_ba;
}

TransferMatrix TransferTransition(const NavState& nav, const ImuSample& s, InstrumentColumns* phi_instrument) {
  TransferMatrix F;
  InstrumentColumns Fi;
  TransferErrorDynamics(nav, s, &F, phi_instrument != nullptr ? &Fi : nullptr);
  const double dt = s.dt_s;
  const TransferMatrix Fdt = F * dt;
  if (phi_instrument != nullptr) *phi_instrument = Fi * dt + 0.5 * Fdt * Fi * dt;
  return TransferMatrix::Identity() + Fdt + 0.5 * Fdt * Fdt;
}

void ResetSlavePosition(const NavState& record, double tau_s, NavState* slave) {
  const double lat = record.lat_rad, h = record.h_m;
  const Eigen::Vector3d d_n_m = record.v_n_mps * tau_s;
  slave->lat_rad = lat + d_n_m.x() / (wgs84::MeridianRadius(lat) + h);
  slave->lon_rad = record.lon_rad + d_n_m.y() / ((wgs84::PrimeVerticalRadius(lat) + h) * std::cos(lat));
  slave->h_m = h - d_n_m.z();
}

void ThrowNonFinite(const char* who, double t_s, const char* what) {
  std::ostringstream m;
  m << who << ": " << what << " became non-finite at t = " << t_s << " s";
  throw std::runtime_error(m.str());
}

void WalkSlaveImu(const std::vector<ImuSample>& slave_imu, const MasterStream& master, double t0_s,
                  const std::function<void(const ImuSample&)>& propagate,
                  const std::function<void(std::size_t)>& update) {
  if (slave_imu.empty()) return;
  const double t_end = slave_imu.back().t_s;
  double t = t0_s;        // the slave's time
  std::size_t next = 0;   // next master record to use
  // Records before the slave's start are outside its span.
  while (next < master.size() && master.record(next).t_s < t - kTimeEpsilon_s) ++next;
  const auto update_due = [&](double t_s) {
    return next < master.size() && master.record(next).t_s <= t_s + kTimeEpsilon_s &&
           master.record(next).t_s <= t_end + kTimeEpsilon_s;
  };
  while (update_due(t)) update(next++);  // records at the initial time
  for (const ImuSample& raw : slave_imu) {
    if (raw.t_s <= t + kTimeEpsilon_s) continue;  // before the start
    ImuSample cur = raw;
    if (cur.t_s - cur.dt_s < t - kTimeEpsilon_s) cur = SplitImuSample(cur, t).second;
    // Records tagged inside the sample: split at the tag.
    while (update_due(cur.t_s) && master.record(next).t_s < cur.t_s - kTimeEpsilon_s) {
      const double tag = master.record(next).t_s;
      if (tag > t + kTimeEpsilon_s) {
        const auto parts = SplitImuSample(cur, tag);
        propagate(parts.first);
        t = parts.first.t_s;
        cur = parts.second;
      }
      update(next++);
    }
    propagate(cur);
    t = cur.t_s;
    while (update_due(cur.t_s)) update(next++);
  }
}

}  // namespace navtwin::transfer
