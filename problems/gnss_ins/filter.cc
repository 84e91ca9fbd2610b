// The navigation filter's main loop (problems/gnss_ins/filter.h); initialisation, calibration
// and stillness detection in filter_support.cc.
#include "problems/gnss_ins/filter.h"

#include <algorithm>
#include <chrono>
#include <initializer_list>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <ceres/cost_function.h>

#include "core/imu_split.h"
#include "core/io/input_error.h"
#include "core/rotation.h"
#include "core/strapdown.h"
#include "factors/attitude_manifold.h"
#include "factors/baro_height.h"
#include "factors/gnss_position.h"
#include "factors/gnss_velocity.h"
#include "factors/mag_heading.h"
#include "factors/mag_vector.h"
#include "factors/position_manifold.h"
#include "factors/zero_velocity.h"
#include "problems/gnss_ins/densify.h"
#include "problems/gnss_ins/error_dynamics.h"
#include "solvers/eskf.h"
#include "solvers/linearize.h"
#include "solvers/rts.h"

namespace navtwin::gnss_ins {
namespace {

/// Two times closer than this are the same epoch (IMU rates stay far below 1 MHz).
constexpr double kTimeEps_s = 1e-6;

const char* const kGnssPos = "gnss_position";
const char* const kGnssReset = "gnss_reset";
const char* const kGnssVel = "gnss_velocity";
const char* const kMag = "mag";
const char* const kBaro = "baro";
const char* const kZupt = "zupt";

class NavigationFilter {
 public:
  NavigationFilter(const Inputs& inputs, const GnssInsConfig& config, bool run_rts,
                   bool keep_covariances, const std::function<void(const NavEpoch&)>& output,
                   std::ostream* progress)
      : in_(inputs),
        cfg_(config),
        n_(config.filter.scale_factors ? err::kSize21 : err::kSize15),
        run_rts_(run_rts),
        keep_covariances_(keep_covariances),
        output_(output),
        progress_(progress),
        start_(InitialFilterState(inputs, config, progress)),
        strapdown_(start_.state.nav),
        imu_(start_.state.imu),
        kf_(InitialCovariance(config, n_)),
        zupt_detector_(config.zupt),
        decimator_(config.output_rate_hz),
        P_(kf_.P()) {
    if (config.mag.mode == MagConfig::Mode::kVector && config.mag.field_ned_uT.isZero(0.0)) {
      throw std::invalid_argument("RunFilter: magnetometer mode vector needs mag.field_ned_uT");
    }
    phi_acc_ = Eigen::MatrixXd::Identity(n_, n_);
    epoch_dx_ = Eigen::VectorXd::Zero(n_);
    for (const char* key : {kGnssPos, kGnssVel, kMag, kBaro, kZupt, kGnssReset}) counts_[key];
  }

  FilterResult Run();

 private:
  static Eigen::MatrixXd InitialCovariance(const GnssInsConfig& config, int n) {
    return InitialStdVector(config, n).array().square().matrix().asDiagonal();
  }

  InsState Nominal() const { return InsState{strapdown_.state(), imu_}; }

  /// Mechanizes one (piece of a) sample and adds it to the covariance group.
  void Propagate(const ImuSample& raw) {
    const ImuSample c = CorrectImu(raw, imu_);
    strapdown_.Update(c);
    group_dtheta_ += c.dtheta_b_rad;
    group_dv_ += c.dv_b_mps;
    group_dt_ += c.dt_s;
    omega_ib_b_ = c.dtheta_b_rad / c.dt_s;
  }

  /// Propagates the covariance over the samples of the current group.
  void FlushGroup() {
    if (group_dt_ <= 0.0) return;
    // P <- Phi P Phi^T + Qd (DiscreteErrorDynamics' Phi and Qd, in blocks; filter.h).
    PropagateCovariance(Nominal(), group_dv_ / group_dt_, group_dtheta_ / group_dt_, cfg_.imu_noise,
                        group_dt_, &P_, run_rts_ ? &phi_acc_ : nullptr);
    group_dtheta_.setZero();
    group_dv_.setZero();
    group_dt_ = 0.0;
  }

  void BeginEpoch() {
    if (in_epoch_) return;
    FlushGroup();
    P_prior_ = P_;
    epoch_dx_.setZero();
    in_epoch_ = true;
  }

  void EndEpoch(double t_s) {
    if (!in_epoch_) return;
    StoreKnot(t_s, true);
    in_epoch_ = false;
  }

  /// A knot at t_s (the covariance must be current): the post-update state and std, and for
  /// the RTS the transition since the previous knot, P_prior, P_post, the feedback.
  void StoreKnot(double t_s, bool after_updates) {
    const Eigen::MatrixXd& P = P_;
    NavEpoch e;
    e.state = Nominal();
    e.state.nav.t_s = t_s;
    e.std = P.diagonal().cwiseMax(0.0).cwiseSqrt();
    epochs_.push_back(std::move(e));
    if (keep_covariances_) filter_covariances_.push_back(P);
    if (run_rts_) {
      RtsKnot k;
      k.Phi = phi_acc_;
      k.P_prior = after_updates ? P_prior_ : P;
      k.P_post = P;
      if (after_updates) k.dx_fed_back = epoch_dx_;
      knots_.push_back(std::move(k));
      phi_acc_.setIdentity();
    }
    last_knot_t_s_ = t_s;
  }

  enum class Block { kPosition, kVelocity, kAttitude };

  /// Linearises `cost` at the nominal state over the given blocks, updates (gated) and
  /// feeds the correction back. With gnss_sigma_ned_m, an innovation farther than
  /// max_distance_m is an InputError (the residual times sigma is the antenna offset, m).
  bool Update(std::unique_ptr<ceres::CostFunction> cost, std::initializer_list<Block> blocks,
              const char* key, const GnssSample* gnss = nullptr,
              const Eigen::Vector3d* gnss_sigma_ned_m = nullptr) {
    const NavState& s = strapdown_.state();
    const double pos[3] = {s.lat_rad, s.lon_rad, s.h_m};
    const double vel[3] = {s.v_n_mps.x(), s.v_n_mps.y(), s.v_n_mps.z()};
    const Eigen::Vector4d q = s.q_n_b.coeffs();
    block_ptrs_.clear();
    manifolds_.clear();
    columns_.clear();
    for (const Block b : blocks) {
      switch (b) {
        case Block::kPosition:
          block_ptrs_.push_back(pos);
          manifolds_.push_back(&position_manifold_);
          columns_.push_back(err::kPos);
          break;
        case Block::kVelocity:
          block_ptrs_.push_back(vel);
          manifolds_.push_back(nullptr);
          columns_.push_back(err::kVel);
          break;
        case Block::kAttitude:
          block_ptrs_.push_back(q.data());
          manifolds_.push_back(&attitude_manifold_);
          columns_.push_back(err::kAtt);
          break;
      }
    }
    Linearize(*cost, block_ptrs_, manifolds_, &lin_);
    const int m = static_cast<int>(lin_.residual.size());
    if (gnss_sigma_ned_m != nullptr) {
      const double distance_m = lin_.residual.cwiseProduct(*gnss_sigma_ned_m).norm();
      if (!(distance_m <= cfg_.gnss.max_distance_m)) {
        std::ostringstream reason;
        reason.precision(12);
        reason << "the GNSS fix at t = " << gnss->t_s << " s is " << distance_m
               << " m from the INS prediction (gnss.max_distance_m = " << cfg_.gnss.max_distance_m << ")";
        throw InputError(in_.paths.gnss, 0, "position", reason.str());
      }
    }
    H_.setZero(m, n_);
    for (std::size_t i = 0; i < columns_.size(); ++i) H_.middleCols(columns_[i], 3) = lin_.jacobians[i];
    y_ = -lin_.residual;
    BeginEpoch();
    kf_.SetP(P_);
    const ErrorStateKalmanFilter::Update u = kf_.Correct(y_, H_, cfg_.filter.gate_probability);
    MeasurementCount& count = counts_[key];
    InnovationStats& stats = innovations_[key];
    ++stats.updates;
    stats.nis_capped += std::min(u.nis, u.gate);
    stats.log_det_s += u.log_det_s;
    if (!u.accepted) {
      ++count.rejected;
      ++stats.rejected;
      return false;
    }
    ++count.used;
    stats.nis += u.nis;
    stats.dof += m;
    P_ = kf_.P();
    const InsState corrected = ApplyCorrection(Nominal(), u.dx);
    strapdown_.SetState(corrected.nav);
    imu_ = corrected.imu;
    epoch_dx_ += u.dx;
    return true;
  }

  void ProcessGnss(const GnssSample& g) {
    const Eigen::Vector3d& lever = cfg_.installation.antenna_lever_arm_b_m;
    const Eigen::Vector3d sp =
        MeasurementSigma(g.pos_std_ned_m, cfg_.gnss.pos_std_floor_m, cfg_.gnss.default_pos_std_m);
    const bool position_used = Update(std::unique_ptr<ceres::CostFunction>(GnssPosition::Create(
                                          Eigen::Vector3d(g.lat_rad, g.lon_rad, g.h_m), lever, sp)),
                                      {Block::kPosition, Block::kAttitude}, kGnssPos, &g, &sp);
    const bool use_velocity = cfg_.gnss.use_velocity && g.has_velocity;
    const Eigen::Vector3d sv =
        MeasurementSigma(g.vel_std_ned_mps, cfg_.gnss.vel_std_floor_mps, cfg_.gnss.default_vel_std_mps);
    if (use_velocity) {
      Update(std::unique_ptr<ceres::CostFunction>(GnssVelocity::Create(g.v_n_mps, lever, omega_ib_b_, sv)),
             {Block::kVelocity, Block::kAttitude}, kGnssVel);
    }
    gnss_seen_ = true;
    gnss_rejected_in_row_ = position_used ? 0 : gnss_rejected_in_row_ + 1;
    const int reset_after = cfg_.filter.gnss_reset_rejections;
    if (reset_after > 0 && gnss_rejected_in_row_ >= reset_after) {
      ResetToGnss(g, sp, use_velocity ? &sv : nullptr);
      gnss_rejected_in_row_ = 0;
    }
  }

  /// After gnss_reset_rejections GNSS positions in a row failed the gate, the filter no
  /// longer believes the receiver (its covariance is too small for its own error): reset
  /// position (and velocity, when the fix has it) to the fix, their covariance to the fix's,
  /// with no correlation to the other states; attitude and IMU errors are kept. Counted as
  /// "gnss_reset" (used = number of resets).
  void ResetToGnss(const GnssSample& g, const Eigen::Vector3d& sigma_pos_m, const Eigen::Vector3d* sigma_vel_mps) {
    const NavState& s = strapdown_.state();
    const Eigen::Matrix3d R_n_b = s.q_n_b.toRotationMatrix();
    const Eigen::Vector3d lever_n = R_n_b * cfg_.installation.antenna_lever_arm_b_m;
    const double antenna[3] = {g.lat_rad, g.lon_rad, g.h_m};
    const double pos[3] = {s.lat_rad, s.lon_rad, s.h_m};
    Eigen::Vector3d ins_minus_fix_ned;
    PositionMinus(pos, antenna, ins_minus_fix_ned.data());
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(n_);
    dx.segment<3>(err::kPos) = -(ins_minus_fix_ned + lever_n);
    if (sigma_vel_mps != nullptr) {
      const Eigen::Vector3d v_antenna = s.v_n_mps + R_n_b * omega_ib_b_.cross(cfg_.installation.antenna_lever_arm_b_m);
      dx.segment<3>(err::kVel) = g.v_n_mps - v_antenna;
    }
    BeginEpoch();
    P_.middleRows(err::kPos, 6).setZero();
    P_.middleCols(err::kPos, 6).setZero();
    P_.diagonal().segment<3>(err::kPos) = sigma_pos_m.cwiseAbs2();
    // Without a GNSS velocity the velocity keeps its value with 1 (m/s)^2 of variance.
    const Eigen::Vector3d vel_var =
        sigma_vel_mps != nullptr ? Eigen::Vector3d(sigma_vel_mps->cwiseAbs2()) : Eigen::Vector3d::Ones();
    P_.diagonal().segment<3>(err::kVel) = vel_var;
    const InsState corrected = ApplyCorrection(Nominal(), dx);
    strapdown_.SetState(corrected.nav);
    epoch_dx_ += dx;
    ++counts_[kGnssReset].used;
  }

  void ProcessMag(const MagSample& sample) {
    const MagConfig& mc = cfg_.mag;
    if (mc.mode == MagConfig::Mode::kOff) return;
    if (sample.t_s - last_mag_t_s_ < mc.min_interval_s - kTimeEps_s) return;
    const Eigen::Vector3d m = CalibrateMag(sample.m_b_uT, mc);
    std::unique_ptr<ceres::CostFunction> cost;
    switch (mc.mode) {
      case MagConfig::Mode::kVector:
        cost.reset(MagVector::Create(m, mc.field_ned_uT, mc.noise_uT));
        break;
      case MagConfig::Mode::kHeading: {
        // The reference field (H0 and the dip direction of MagHeading; docs/gnss-ins.md,
        // "Magnetometer modes"): the mean of the samples so far rotated into NED with the
        // nominal attitudes. The reference attitude is the nominal one.
        const Eigen::Quaterniond& q = strapdown_.state().q_n_b;
        heading_field_sum_uT_ += q * m;
        ++heading_field_count_;
        const Eigen::Vector3d mean_uT = heading_field_sum_uT_ / static_cast<double>(heading_field_count_);
        const double h0_uT = mean_uT.head<2>().norm();
        if (!(h0_uT > 0.0)) {
          ++counts_[kMag].rejected;  // a vertical mean field: no heading
          return;
        }
        cost.reset(MagHeading::Create(MagHeading::RemoveDipNoise(m, q, mean_uT), mc.declination_rad,
                                      mc.heading_std_rad, h0_uT));
        break;
      }
      case MagConfig::Mode::kHeading2Axis: {
        const Eigen::Vector3d rpy = EulerFromQuat<double>(strapdown_.state().q_n_b);
        if (!(std::abs(rpy[0]) < mc.max_tilt_rad && std::abs(rpy[1]) < mc.max_tilt_rad)) {
          ++counts_[kMag].rejected;  // tilted: the 2-axis compass is not used
          return;
        }
        cost.reset(MagHeading2Axis::Create(m.x(), m.y(), mc.declination_rad, mc.heading_std_rad));
        break;
      }
      case MagConfig::Mode::kOff:
        return;
    }
    last_mag_t_s_ = sample.t_s;
    Update(std::move(cost), {Block::kAttitude}, kMag);
  }

  void ProcessBaro(const BaroSample& b) {
    if (!cfg_.baro.use) return;
    if (!std::isfinite(b.altitude_m)) {
      ++counts_[kBaro].rejected;
      return;
    }
    if (!baro_offset_m_) {
      // The offset baro - height is taken once the first GNSS epoch has corrected the height
      // (or from the initial state when there is no GNSS); earlier samples are not used.
      if (!in_.gnss.empty() && !gnss_seen_) {
        ++counts_[kBaro].rejected;
        return;
      }
      baro_offset_m_ = b.altitude_m - strapdown_.state().h_m;
    }
    Update(std::unique_ptr<ceres::CostFunction>(BaroHeight::Create(b.altitude_m - *baro_offset_m_, cfg_.baro.std_m)),
           {Block::kPosition}, kBaro);
  }

  /// Measurements at IMU epoch t_s (GNSS tagged t_s, magnetometer and barometer up to t_s).
  void ProcessEpochMeasurements(double t_s, bool imu_epoch) {
    while (gi_ < in_.gnss.size() && in_.gnss[gi_].t_s <= t_s + kTimeEps_s) ProcessGnss(in_.gnss[gi_++]);
    while (mi_ < in_.mag.size() && in_.mag[mi_].t_s <= t_s + kTimeEps_s) ProcessMag(in_.mag[mi_++]);
    while (bi_ < in_.baro.size() && in_.baro[bi_].t_s <= t_s + kTimeEps_s) ProcessBaro(in_.baro[bi_++]);
    if (imu_epoch && cfg_.zupt.enabled && zupt_detector_.Still() &&
        t_s - last_zupt_t_s_ >= cfg_.zupt.interval_s - kTimeEps_s) {
      last_zupt_t_s_ = t_s;
      Update(std::unique_ptr<ceres::CostFunction>(ZeroVelocity::Create(cfg_.zupt.std_mps)), {Block::kVelocity},
             kZupt);
    }
  }

  /// Skips measurements before the start (and at it unless the start allows them).
  void SkipMeasurementsBeforeStart(double t0_s) {
    const double limit = start_.use_measurements_at_start ? t0_s - kTimeEps_s : t0_s + kTimeEps_s;
    while (gi_ < in_.gnss.size() && in_.gnss[gi_].t_s < limit) ++gi_;
    while (mi_ < in_.mag.size() && in_.mag[mi_].t_s < limit) ++mi_;
    while (bi_ < in_.baro.size() && in_.baro[bi_].t_s < limit) ++bi_;
  }

  /// Output epochs: the rule every method shares (OutputDecimator, densify.h), so the
  /// filter's, the RTS smoother's and the batch's files have the same epochs.
  void Output(double t_s) {
    if (!output_ || !decimator_.Take(t_s)) return;
    NavEpoch e;
    e.state = Nominal();
    e.std = P_.diagonal().cwiseMax(0.0).cwiseSqrt();
    output_(e);
  }

  const Inputs& in_;
  const GnssInsConfig& cfg_;
  const int n_;
  const bool run_rts_;
  const bool keep_covariances_;
  const std::function<void(const NavEpoch&)>& output_;
  std::ostream* progress_;
  const FilterStart start_;
  Strapdown strapdown_;
  ImuErrors imu_;
  ErrorStateKalmanFilter kf_;
  StillnessDetector zupt_detector_;
  OutputDecimator decimator_;

  // Covariance group.
  Eigen::Vector3d group_dtheta_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d group_dv_ = Eigen::Vector3d::Zero();
  double group_dt_ = 0.0;
  Eigen::Vector3d omega_ib_b_ = Eigen::Vector3d::Zero();  ///< of the last (piece of a) sample
  /// The covariance, propagated here; the engine kf_ gets it for each update (Correct).
  Eigen::MatrixXd P_;
  Eigen::MatrixXd phi_acc_;  ///< transition since the previous knot (RTS)

  // Update epoch and knots.
  bool in_epoch_ = false;
  Eigen::MatrixXd P_prior_;
  Eigen::VectorXd epoch_dx_;
  double last_knot_t_s_ = -INFINITY;
  std::vector<NavEpoch> epochs_;
  std::vector<Eigen::MatrixXd> filter_covariances_;
  std::vector<RtsKnot> knots_;
  std::map<std::string, MeasurementCount> counts_;
  std::map<std::string, InnovationStats> innovations_;

  // Measurement models' scratch.
  PositionManifold position_manifold_;
  AttitudeManifold attitude_manifold_;
  Linearization lin_;
  std::vector<const double*> block_ptrs_;
  std::vector<const ceres::Manifold*> manifolds_;
  std::vector<int> columns_;
  Eigen::MatrixXd H_;
  Eigen::VectorXd y_;

  // Measurement streams.
  std::size_t gi_ = 0, mi_ = 0, bi_ = 0;
  bool gnss_seen_ = false;
  int gnss_rejected_in_row_ = 0;
  double last_mag_t_s_ = -INFINITY;
  Eigen::Vector3d heading_field_sum_uT_ = Eigen::Vector3d::Zero();  ///< kHeading: sum of R m_b
  std::size_t heading_field_count_ = 0;
  double last_zupt_t_s_ = -INFINITY;
  std::optional<double> baro_offset_m_;
};

FilterResult NavigationFilter::Run() {
  const auto wall_start = std::chrono::steady_clock::now();
  const std::vector<ImuSample>& imu = in_.imu;
  const double t0 = start_.state.nav.t_s;
  std::size_t k = std::upper_bound(imu.begin(), imu.end(), t0 + kTimeEps_s,
                                   [](double t, const ImuSample& s) { return t < s.t_s; }) -
                  imu.begin();
  if (k == imu.size()) {
    std::ostringstream reason;
    reason.precision(12);
    reason << "the filter starts at t = " << t0 << " s, at or after the end of the IMU record ("
           << imu.back().t_s << " s)";
    throw InputError(in_.paths.imu, 0, "t", reason.str());
  }

  // Knot 0: the initial state, with the measurements at the start time.
  SkipMeasurementsBeforeStart(t0);
  ProcessEpochMeasurements(t0, false);
  if (in_epoch_) {
    EndEpoch(t0);
  } else {
    StoreKnot(t0, false);
  }

  const double cov_interval = cfg_.filter.covariance_interval_s;
  const std::size_t n_imu = imu.size();
  int progress_step = 0;
  double t = t0;
  for (; k < n_imu; ++k) {
    ImuSample rest = imu[k];
    if (rest.t_s - rest.dt_s < t0 - kTimeEps_s) rest = SplitImuSample(rest, t0).second;
    // GNSS epochs inside the sample: split it there, update, continue with the rest.
    while (gi_ < in_.gnss.size() && in_.gnss[gi_].t_s < rest.t_s - kTimeEps_s) {
      const double tg = in_.gnss[gi_].t_s;
      if (tg > rest.t_s - rest.dt_s + kTimeEps_s) {
        const std::pair<ImuSample, ImuSample> parts = SplitImuSample(rest, tg);
        Propagate(parts.first);
        rest = parts.second;
      }
      ProcessGnss(in_.gnss[gi_++]);
      EndEpoch(tg);
    }
    Propagate(rest);
    t = rest.t_s;
    if (cfg_.zupt.enabled) zupt_detector_.Add(CorrectImu(imu[k], imu_));
    ProcessEpochMeasurements(t, true);
    if (in_epoch_) {
      EndEpoch(t);
    } else if (t - last_knot_t_s_ >= cfg_.filter.store_interval_s - kTimeEps_s) {
      FlushGroup();
      StoreKnot(t, false);
    } else if (k + 1 >= n_imu || group_dt_ + imu[k + 1].dt_s > cov_interval * (1.0 + 1e-9)) {
      FlushGroup();
    }
    Output(t);
    if (progress_ != nullptr) {
      const int step = static_cast<int>((k + 1) * 20 / n_imu);
      if (step > progress_step) {
        progress_step = step;
        std::ostringstream line;
        line.precision(10);
        line << "filter: " << 5 * step << " % (t = " << t << " s)\n";
        *progress_ << line.str() << std::flush;
      }
    }
  }
  FlushGroup();
  if (t > last_knot_t_s_ + kTimeEps_s) StoreKnot(t, false);

  FilterResult result;
  result.filter.method = "filter";
  result.filter.epochs = std::move(epochs_);
  result.filter.counts = counts_;
  result.filter.run_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  if (run_rts_) {
    const RtsResult smoothed = RunRts(knots_);
    knots_.clear();
    knots_.shrink_to_fit();
    Solution rts;
    rts.method = "rts";
    rts.counts = counts_;
    rts.epochs.reserve(smoothed.dx.size());
    for (std::size_t i = 0; i < smoothed.dx.size(); ++i) {
      NavEpoch e;
      e.state = ApplyCorrection(result.filter.epochs[i].state, smoothed.dx[i]);
      e.std = smoothed.P[i].diagonal().cwiseMax(0.0).cwiseSqrt();
      rts.epochs.push_back(std::move(e));
    }
    if (keep_covariances_) result.rts_covariances = smoothed.P;
    rts.run_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    result.rts = std::move(rts);
  }
  result.filter_covariances = std::move(filter_covariances_);
  result.innovations = std::move(innovations_);
  return result;
}

}  // namespace

FilterResult RunFilter(const Inputs& inputs, const GnssInsConfig& config, bool run_rts,
                       const std::function<void(const NavEpoch&)>& output, std::ostream* progress,
                       bool keep_covariances) {
  NavigationFilter filter(inputs, config, run_rts, keep_covariances, output, progress);
  return filter.Run();
}

}  // namespace navtwin::gnss_ins
