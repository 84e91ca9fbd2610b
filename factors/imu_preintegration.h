// IMU preintegration between two states i and j (Lupton & Sukkarieh 2012; Forster et al.
// 2017, "On-Manifold Preintegration for Real-Time Visual-Inertial Odometry", IEEE T-RO),
// with the rotating NED frame (Earth rate and transport rate) handled in the factor.
// Derivation, the neglected terms and their sizes: docs/imu-preintegration.md.
//
// From the corrected increments (core/imu_errors.h, at the linearisation point's errors)
//   a_k = (dtheta_k - bg_lin dt_k) / (1 + sg_lin),  u_k = (dv_k - ba_lin dt_k) / (1 + sa_lin)
// of the samples between t_i and t_j (body axes), in body frame i:
//   dR_k = dR_{k-1} Exp(a_k)                                           (R_bi_bk)
//   dv_k = dv_{k-1} + dR_{k-1} (u_k + 1/2 a_k x u_k)
//   dp_k = dp_{k-1} + dv_{k-1} dt_k + dR_{k-1} (1/2 u_k + 1/6 a_k x u_k) dt_k
// (constant angular rate and specific force within each sample, to first order in a_k).
// Biases and scale factors at i other than the linearisation point enter to first order:
//   dR(bg, sg) = dR Exp(J_R_bg dbg + J_R_sg dsg),
//   dv(bg, ba, sg, sa) = dv + J_v_bg dbg + J_v_ba dba + J_v_sg dsg + J_v_sa dsa,
//   dp likewise (dbg = bg - bg_lin, ...).
// Optionally (TrackAxisMisalignment) also the triads' axis misalignments, linearised at zero:
// omega_meas = (I + S_g + M_g) omega_true + bg with M_g's six off-diagonal entries
// mg = (M01, M02, M10, M12, M20, M21) (M_ij: axis i's sensitivity to axis j; the order of
// core/imu_error_model.h's triad block, as the simulator's model), likewise M_a; they add J_R_mg mg to the
// rotation's exponent, J_v_mg mg + J_v_ma ma to dv and the same to dp.
// Covariance of (dphi, dv, dp), dR_meas = dR_true Exp(dphi) (dphi in body axes at j; dv,
// dp in body axes at i), from white gyro and accelerometer noise: ARW^2 and VRW^2 per
// second, propagated per sample (the noise inside a sample is integrated in continuous
// time, so that even one sample gives a positive definite covariance).
//
// The factor (CreateImuFactor) links the states
//   pos[3] (lat_rad, lon_rad, h_m; PositionManifold), vel[3] (v_n_mps),
//   q[4] (q_n_b as x, y, z, w; AttitudeManifold), bg_i[3] (rad/s), ba_i[3] (m/s^2),
//   and with the scale factors as unknowns (CreateImuScaleFactor) sg_i[3], sa_i[3] (-),
// with 9 residuals, prediction minus state at j (unwhitened units rad, m/s, m, NED):
//   r_phi = Log(R_pred R_j^T),  R_pred = Exp(-omega_in dt) R_i dR(bg)   (R_pred = Exp(r_phi) R_j)
//   r_v   = v_pred - v_j,       r_p = D_pred - D(p_i, p_j)
// (D: NED displacement from i to j with the radii at the midpoint; the full model is in
// imu_preintegration.cc), whitened by the Cholesky factor of the covariance rotated into
// the residual's axes.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/imu_errors.h"
#include "core/types.h"

namespace ceres {
class CostFunction;
}  // namespace ceres

namespace navtwin {

class ImuPreintegration {
 public:
  using Matrix9d = Eigen::Matrix<double, 9, 9>;
  using Vector9d = Eigen::Matrix<double, 9, 1>;

  /// Linearisation-point biases (body axes) and the white-noise densities:
  /// gyro ARW in rad/sqrt(s), accelerometer VRW in m/s/sqrt(s). Throws
  /// std::invalid_argument for non-finite biases or a non-positive or non-finite density.
  ImuPreintegration(const Eigen::Vector3d& bg_lin_radps, const Eigen::Vector3d& ba_lin_mps2,
                    double gyro_arw_rad_per_sqrt_s, double accel_vrw_mps_per_sqrt_s);
  /// Linearised at biases and scale factors `lin`; also throws for scale factors not
  /// finite or not above -1.
  ImuPreintegration(const ImuErrors& lin, double gyro_arw_rad_per_sqrt_s, double accel_vrw_mps_per_sqrt_s);

  /// Adds one raw sample (body-axis increments over (t_s - dt_s, t_s], biases not removed).
  /// Throws std::invalid_argument for a non-positive or non-finite dt_s, non-finite
  /// increments, or a sample that does not start where the previous one ended (gap or
  /// overlap larger than max(1e-6 s, 1e-3 dt_s)).
  void Integrate(const ImuSample& s);

  /// Re-runs the integration from the stored samples at a new linearisation point (the
  /// first form keeps the scale factors'). std::logic_error after DropSamples.
  void Reintegrate(const Eigen::Vector3d& bg_lin_radps, const Eigen::Vector3d& ba_lin_mps2);
  void Reintegrate(const ImuErrors& lin);

  /// Integrated time t_j - t_i, s (0 before the first sample).
  double dt_s() const { return dt_s_; }
  /// Start and end time of the integrated samples (NaN before the first sample).
  double t_start_s() const;
  double t_end_s() const;
  std::size_t num_samples() const { return num_samples_; }
  /// Computes the axis-misalignment Jacobians J_mg, J_ma too (header comment); before the
  /// first sample (std::logic_error after one). Costs two 9x9 by 9x6 products per sample.
  void TrackAxisMisalignment();
  bool tracks_axis_misalignment() const { return track_misalignment_; }

  /// The samples integrated (empty after DropSamples).
  const std::vector<ImuSample>& samples() const { return samples_; }
  /// Releases the stored samples, and stores none of those integrated later, when no
  /// Reintegrate will follow (a caller that can give the samples again integrates them
  /// into a new preintegration instead).
  void DropSamples();

  /// Preintegrated rotation R_bi_bj (as a matrix and as a unit quaternion), velocity and
  /// position increments in body frame i (m/s, m) at the linearisation point.
  const Eigen::Matrix3d& delta_R() const { return delta_R_; }
  const Eigen::Quaterniond& delta_q() const { return delta_q_; }
  const Eigen::Vector3d& delta_v_mps() const { return delta_v_; }
  const Eigen::Vector3d& delta_p_m() const { return delta_p_; }

  /// Covariance of (dphi rad, dv m/s, dp m), 9x9, see the header comment.
  const Matrix9d& covariance() const { return covariance_; }
  /// S = L^-1 with covariance = L L^T (L lower-triangular Cholesky factor), so that
  /// S^T S = covariance^-1 and S x has unit covariance. Throws std::domain_error when the
  /// covariance is not positive definite (no sample integrated).
  Matrix9d SqrtInformation() const;

  /// First-order bias and scale-factor Jacobians at the linearisation point (see the header
  /// comment), the exact derivatives of the discrete recursion. Units: J_R_bg s (rad per
  /// rad/s), J_v_bg m/rad, J_v_ba s, J_p_bg m s/rad, J_p_ba s^2; per unit scale factor
  /// J_R_sg rad, J_v_sg m/s, J_p_sg m, J_v_sa m/s, J_p_sa m. d(delta_R)/d(ba, sa) is zero.
  Eigen::Matrix3d J_R_bg() const { return J_bg_.block<3, 3>(0, 0); }
  Eigen::Matrix3d J_v_bg() const { return J_bg_.block<3, 3>(3, 0); }
  Eigen::Matrix3d J_v_ba() const { return J_ba_.block<3, 3>(3, 0); }
  Eigen::Matrix3d J_p_bg() const { return J_bg_.block<3, 3>(6, 0); }
  Eigen::Matrix3d J_p_ba() const { return J_ba_.block<3, 3>(6, 0); }
  Eigen::Matrix3d J_R_sg() const { return J_sg_.block<3, 3>(0, 0); }
  Eigen::Matrix3d J_v_sg() const { return J_sg_.block<3, 3>(3, 0); }
  Eigen::Matrix3d J_p_sg() const { return J_sg_.block<3, 3>(6, 0); }
  Eigen::Matrix3d J_v_sa() const { return J_sa_.block<3, 3>(3, 0); }
  Eigen::Matrix3d J_p_sa() const { return J_sa_.block<3, 3>(6, 0); }
  /// Per unit axis misalignment (rad), columns mg = (M01, M02, M10, M12, M20, M21), rows
  /// (dphi, dv, dp); zero unless TrackAxisMisalignment. d(delta_R)/d(ma) is zero.
  const Eigen::Matrix<double, 9, 6>& J_mg() const { return J_mg_; }
  const Eigen::Matrix<double, 9, 6>& J_ma() const { return J_ma_; }

  /// The linearisation point: biases and scale factors.
  const ImuErrors& lin() const { return lin_; }
  const Eigen::Vector3d& bg_lin_radps() const { return lin_.bg_radps; }
  const Eigen::Vector3d& ba_lin_mps2() const { return lin_.ba_mps2; }
  double gyro_arw_rad_per_sqrt_s() const { return gyro_arw_; }
  double accel_vrw_mps_per_sqrt_s() const { return accel_vrw_; }

  /// The increments at biases (bg, ba) (scale factors at the linearisation point), or at
  /// errors e, by the first-order correction above (no reintegration). Worth a Reintegrate
  /// when the attitude correction |J_R_bg dbg + J_R_sg dsg| grows past ~1e-3 rad.
  struct Deltas {
    Eigen::Quaterniond delta_q;
    Eigen::Vector3d delta_v_mps;
    Eigen::Vector3d delta_p_m;
  };
  Deltas Corrected(const Eigen::Vector3d& bg_radps, const Eigen::Vector3d& ba_mps2) const;
  Deltas Corrected(const ImuErrors& e) const;

 private:
  void Reset();
  void Propagate(const ImuSample& s);

  ImuErrors lin_;
  double gyro_arw_, accel_vrw_;
  std::vector<ImuSample> samples_;
  std::size_t num_samples_ = 0;
  bool samples_dropped_ = false;
  double t_start_s_ = 0.0, t_end_s_ = 0.0;  ///< of the samples integrated
  double dt_s_ = 0.0;
  Eigen::Quaterniond delta_q_;
  Eigen::Matrix3d delta_R_;
  Eigen::Vector3d delta_v_, delta_p_;
  Matrix9d covariance_;
  Eigen::Matrix<double, 9, 3> J_bg_, J_ba_, J_sg_, J_sa_;  // rows: dphi, dv, dp
  bool track_misalignment_ = false;
  Eigen::Matrix<double, 9, 6> J_mg_, J_ma_;
};

/// The IMU factor between states i and j: 9 whitened residuals (attitude, velocity,
/// position) with parameter blocks
///   (pos_i[3], vel_i[3], q_i[4], bg_i[3], ba_i[3], pos_j[3], vel_j[3], q_j[4]).
/// The factor copies what it needs from `pre` when it is created (a later Reintegrate of
/// `pre` does not change it: create a new factor). Throws std::invalid_argument when
/// `pre` is null or has no sample, std::domain_error when its covariance is not positive
/// definite. The caller owns the returned cost function.
ceres::CostFunction* CreateImuFactor(std::shared_ptr<const ImuPreintegration> pre);

/// The IMU factor with the scale factors as unknowns: parameter blocks
///   (pos_i[3], vel_i[3], q_i[4], bg_i[3], ba_i[3], sg_i[3], sa_i[3], pos_j[3], vel_j[3], q_j[4]),
/// the same 9 residuals; otherwise as CreateImuFactor.
ceres::CostFunction* CreateImuScaleFactor(std::shared_ptr<const ImuPreintegration> pre);

/// The IMU factor with scale factors and axis misalignments as unknowns (the preintegration
/// must track them, TrackAxisMisalignment): parameter blocks
///   (pos_i[3], vel_i[3], q_i[4], bg_i[3], ba_i[3], sg_i[3], sa_i[3], mg_i[6], ma_i[6],
///    pos_j[3], vel_j[3], q_j[4]);
/// the same 9 residuals. Throws std::invalid_argument otherwise.
ceres::CostFunction* CreateImuInstrumentFactor(std::shared_ptr<const ImuPreintegration> pre);

/// The same model evaluated in double: the 9 residuals, whitened or not (rad, m/s, m,
/// NED; see the header comment). For tests, diagnostics and initial-guess checks.
Eigen::Matrix<double, 9, 1> ImuFactorResidual(const ImuPreintegration& pre, const double* pos_i,
                                              const double* vel_i, const double* q_i,
                                              const double* bg_i, const double* ba_i,
                                              const double* pos_j, const double* vel_j,
                                              const double* q_j, bool whitened);
/// The same with the scale-factor blocks sg_i, sa_i (CreateImuScaleFactor's model).
Eigen::Matrix<double, 9, 1> ImuScaleFactorResidual(const ImuPreintegration& pre, const double* pos_i,
                                                   const double* vel_i, const double* q_i, const double* bg_i,
                                                   const double* ba_i, const double* sg_i, const double* sa_i,
                                                   const double* pos_j, const double* vel_j, const double* q_j,
                                                   bool whitened);
/// The same with the axis-misalignment blocks mg_i, ma_i (CreateImuInstrumentFactor's model).
Eigen::Matrix<double, 9, 1> ImuInstrumentFactorResidual(const ImuPreintegration& pre, const double* pos_i,
                                                        const double* vel_i, const double* q_i, const double* bg_i,
                                                        const double* ba_i, const double* sg_i, const double* sa_i,
                                                        const double* mg_i, const double* ma_i, const double* pos_j,
                                                        const double* vel_j, const double* q_j, bool whitened);

}  // namespace navtwin
