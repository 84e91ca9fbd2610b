// Adaptive smoother of GPS positions for the in-flight alignment of seed 003: the seed
// passes GPS fixes, "which jump by a few to tens of metres", through an adaptive smoothing
// filter before their difference from the INS position feeds the 10-state Kalman filter.
// The seed gives no details; this is the design chosen here (docs/inflight-alignment-gps-
// smoother.md gives the reasons and the measured performance):
//
//  - Frame: a curvilinear local NED frame about the first fix, metres along the meridian
//    and the parallel with the origin's radii (core/earth.h):
//      n = (lat - lat0)(R_M0 + h0),  e = (lon - lon0)(R_N0 + h0) cos lat0,  d = h0 - h.
//    The map is linear, so it inverts exactly, and a straight flight at constant height
//    stays a straight line at constant d (a tangent plane would bend it by s^2 / 2R,
//    785 m after 100 km, a fictitious acceleration the model would have to follow).
//  - Motion: constant velocity per axis with white acceleration noise, in two modes mixed
//    by an Interacting Multiple Model (IMM, Blom and Bar-Shalom 1988): a quiet mode for
//    straight flight (strong smoothing) and a manoeuvre mode (pull-ups, accelerations)
//    whose large process noise follows the vehicle (lag < 50 m through the preset's
//    pull-up, gone 3 s after the level-off). Mode switches are a Markov chain with the mean sojourn
//    times of the options. Constant velocity rather than constant acceleration: the
//    seed's vehicle flies straight, where a CA model smooths less; sustained
//    accelerations are the manoeuvre mode's job (a CA manoeuvre mode is a possible
//    refinement, see the doc).
//  - Measurement noise R (diagonal, per axis) is estimated from the data, from the third
//    differences of the positions over a sliding window,
//      d_k = z_k - 3 z_k-1 + 3 z_k-2 - z_k-3,   E d^2 = 20 sigma^2 for white noise,
//    sigma = RMS(d) / sqrt(20): blind to any motion of constant acceleration, unlike an
//    innovation-based estimate, which a manoeuvre's lag would inflate (and which depends
//    on the process noise). Only fixes the gate accepted enter (a rejected fix leaves a
//    gap, and differences across a gap are skipped), so outliers and jumps stay out;
//    clamped to the bounds. The gate (below) includes the manoeuvre process noise, so a
//    far too small initial sigma does not lock the estimate out by rejecting every fix.
//  - Outliers: a fix is rejected when its NIS exceeds the chi-square gate (3 dof) under
//    the combined estimate predicted with the manoeuvre mode's process noise (what a
//    manoeuvre starting now could explain: 4.6 sigma = 115 m per axis for 17 m noise),
//    once the noise estimate comes from the data (before, every fix is accepted). A run
//    of reset_after_rejections consecutive rejections is taken for a real jump (or a lost
//    track) and re-initialises the smoother at the fix that completes the run (counted
//    as rejected, flagged reset); the origin of the local frame stays.
//  - No velocity input: INS velocity would tie the smoothed GPS to the INS errors that
//    the alignment filter estimates from the GPS - INS difference; GPS velocity is what
//    the seed distrusts. Manoeuvres are handled by the IMM's manoeuvre mode.
// The receiver's own position sigmas (GnssSample::pos_std_ned_m) are not used.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <deque>
#include <utility>

#include <Eigen/Core>

#include "core/earth.h"
#include "core/types.h"

namespace navtwin::inflight {

/// Third differences z_k - 3 z_k-1 + 3 z_k-2 - z_k-3 of white noise of standard deviation
/// sigma have standard deviation sqrt(1 + 9 + 9 + 1) sigma: sigma = sd(third difference) / this.
inline const double kThirdDifferenceGain = std::sqrt(20.0);

struct GpsSmootherOptions {
  /// Quiet mode (straight flight): white acceleration noise per axis, as the square root
  /// of its power spectral density (m/s^2/sqrt(Hz); q = value^2 in m^2/s^3).
  double quiet_accel_noise_mps2_sqrt_hz = 0.1;
  /// Manoeuvre mode (pull-ups, speed changes): the same, large enough to follow the
  /// vehicle's accelerations within one GPS interval.
  double maneuver_accel_noise_mps2_sqrt_hz = 30.0;
  /// Mean time spent in the quiet mode before a manoeuvre, and in a manoeuvre (s): the
  /// Markov switching probabilities over dt are 1 - exp(-dt / mean time). A long quiet
  /// time keeps the manoeuvre mode's weight, mixed into the quiet mode at every step,
  /// small in straight flight (RMS error per axis at 17 m noise, 10 seeds: 100 s 7.5 m,
  /// 10000 s 4.9 m, quiet mode alone 4.7 m); the price is a slower switch into a
  /// manoeuvre that builds up gradually (doc: sustained acceleration).
  double maneuver_mean_interval_s = 10000.0;
  double maneuver_mean_duration_s = 20.0;

  /// Measurement noise (1 sigma, per NED axis) used until noise_min_fixes third
  /// differences exist (m).
  Eigen::Vector3d initial_position_sigma_ned_m = Eigen::Vector3d(10.0, 10.0, 15.0);
  /// Velocity uncertainty at (re)initialisation (m/s): the first fix carries no velocity.
  double initial_speed_sigma_mps = 300.0;
  /// Sliding window of the noise estimate (third differences of consecutive, equally
  /// spaced, accepted fixes) and the number needed before it replaces the initial sigma
  /// (and before the gate is applied: 20 differences give sigma to ~20 %).
  int noise_window_fixes = 120;
  int noise_min_fixes = 20;
  /// Bounds of the estimated measurement sigma (m).
  double min_position_sigma_m = 0.5;
  double max_position_sigma_m = 100.0;

  /// Chi-square gate probability on the 3-dof position innovation (1: no gate).
  double gate_probability = 0.9999;
  /// This many consecutive rejected fixes re-initialise the smoother at the last one.
  int reset_after_rejections = 3;
};

/// The smoother's output for one fix.
struct SmoothedFix {
  double t_s = 0.0;
  double lat_rad = 0.0;  ///< smoothed position, geodetic
  double lon_rad = 0.0;
  double h_m = 0.0;
  Eigen::Vector3d pos_ned_m = Eigen::Vector3d::Zero();    ///< in the local frame (header)
  Eigen::Vector3d vel_ned_mps = Eigen::Vector3d::Zero();  ///< rate of pos_ned_m
  Eigen::Vector3d sigma_ned_m = Eigen::Vector3d::Zero();  ///< 1 sigma of pos_ned_m
  /// The measurement sigma in use at this fix (estimated, or the initial value).
  Eigen::Vector3d measurement_sigma_ned_m = Eigen::Vector3d::Zero();
  double maneuver_probability = 0.0;  ///< IMM probability of the manoeuvre mode
  double nis = 0.0;       ///< NIS of the gate (header)
  bool rejected = false;  ///< the fix failed the gate and was not used
  bool reset = false;     ///< the smoother (re)started at this fix
};

class GpsSmoother {
 public:
  /// Throws std::invalid_argument for options out of range (message names the option).
  explicit GpsSmoother(const GpsSmootherOptions& options = {});

  /// Processes one fix. Throws std::invalid_argument (message names the field and value)
  /// for a non-finite time or position, a latitude at or beyond a pole, or a time not after
  /// the previous fix's; the smoother is then unchanged.
  SmoothedFix Update(const GnssSample& fix);

  std::size_t fix_count() const { return fixes_; }        ///< fixes processed
  std::size_t rejected_count() const { return rejected_; }  ///< rejected by the gate
  std::size_t reset_count() const { return resets_; }     ///< re-initialisations (not the first)
  /// The origin of the local frame (the first fix); valid after the first Update.
  const wgs84::Geodetic& origin() const { return origin_; }

  /// One IMM mode's estimate (public only for the implementation's helpers).
  struct ModeState {
    Eigen::Matrix<double, 6, 1> x;  ///< [pos_ned_m, vel_ned_mps]
    Eigen::Matrix<double, 6, 6> P;
    double probability = 0.0;
  };

 private:
  void Validate(const GnssSample& fix) const;
  Eigen::Vector3d ToLocal(const GnssSample& fix) const;
  wgs84::Geodetic ToGeodetic(const Eigen::Vector3d& pos_ned_m) const;
  void Initialise(const Eigen::Vector3d& z_ned_m, const Eigen::Vector3d& sigma_ned_m);
  void PushNoiseSample(double t_s, const Eigen::Vector3d& z_ned_m);
  Eigen::Vector3d MeasurementSigma() const;
  /// A fix the gate rejected: the modes keep their predictions; the run completes a
  /// reset when it reaches reset_after_rejections.
  SmoothedFix Reject(double t_s, const Eigen::Vector3d& z_ned_m, const Eigen::Vector3d& sigma_ned_m,
                     const std::array<ModeState, 2>& predicted);
  SmoothedFix Output(double t_s, const Eigen::Vector3d& measurement_sigma_ned_m) const;

  GpsSmootherOptions options_;
  double gate_nis_;  ///< chi-square threshold (3 dof), infinity without a gate
  double rad_to_north_m_ = 0.0, rad_to_east_m_ = 0.0;  ///< local frame scales
  wgs84::Geodetic origin_;
  bool started_ = false;
  double last_t_s_ = 0.0;
  std::array<ModeState, 2> modes_;  ///< [quiet, manoeuvre]
  std::deque<std::pair<double, Eigen::Vector3d>> recent_;  ///< last 4 accepted fixes (t, local)
  std::deque<Eigen::Vector3d> third_diff_sq_m2_;           ///< the noise window (d^2 per axis)
  std::size_t fixes_ = 0, rejected_ = 0, resets_ = 0;
  int rejection_run_ = 0;
};

}  // namespace navtwin::inflight
