// GNSS antenna position and velocity with the installation as unknowns: the antenna lever
// arm l_b (body FRD, m) and the receiver's time offset tau (s). tau is a latency: the fix
// stamped t describes the antenna at t - tau. The models are those of gnss_position.h and
// gnss_velocity.h carried back by tau with the antenna's velocity and acceleration at t:
//
//   v_ant_n = v_n + R_n_b (omega x l_b)
//   a_ant_n = a_n + R_n_b (alpha x l_b + omega x (omega x l_b))
//   position  r = (PositionMinus(pos, p_meas) + R_n_b l_b
//                  - tau v_ant_n + tau^2/2 a_ant_n - tau^3/6 j_n) / sigma_ned
//   velocity  r = (v_ant_n - tau a_ant_n + tau^2/2 j_n - v_meas_n) / sigma_ned
//
// omega = omega_ib_b (bias-corrected gyro rate), alpha (the body's angular acceleration), a_n
// and j_n (the IMU's NED acceleration and jerk) are known inputs held fixed (BodyMotion), as
// omega is in gnss_velocity.h; problems/ins/measurement_rules.h (MotionWindow) takes them
// from the mechanization over the last 0.2 s, shrinking what its noise and the
// mechanization's tilt errors could fake. (a_n = R_n_b f_b + g_n with the estimated attitude
// was tried: the batch then traded tau against the tilt that the accelerometer bias hides.)
// Approximations:
//  - Taylor series in tau: the IMU's part to third order in position and second in
//    velocity; the lever arm's to second and first, its rate of change of the angular
//    acceleration left out: the velocity is off by tau^2/2 |R_n_b (dalpha/dt x l_b)| and
//    smaller terms. A rotation that starts or stops within a fraction of a second
//    (20 rad/s^3 at 0.4 m, 0.15 s: 9 cm/s) biases the lever arm (docs/gnss-ins.md). alpha is
//    taken about 0.1 s before t, near the mean over [t - tau, t] for tau near 0.2 s, which
//    removes part of that term for smooth motion;
//  - the inputs are estimated from a window of IMU samples: their noise and their lag
//    (docs in measurement_rules.h) enter the velocity times tau;
//  - the rotation of the navigation frame is left out: the Earth-rate term of the lever-arm
//    velocity as in gnss_velocity.h, and in a_ant the part of a_n's Coriolis and transport
//    terms that a_n may leave out, tau |(2 omega_ie + omega_en) x v| (0.15 s at 30 m/s:
//    7e-4 m/s).
// Keep |tau| well below a second (the configuration allows 1 s).
//
// Parameter blocks (DynamicAutoDiffCostFunction), in this order:
//   position: pos {lat_rad, lon_rad, h_m} (3, PositionManifold), q_n_b (4, x y z w,
//             AttitudeManifold), v_n (3), then the unknowns below;
//   velocity: v_n (3), q_n_b (4), then the unknowns below;
//   unknowns: with lever_arm three 1-double blocks l_x, l_y, l_z (m); with time_offset one
//             1-double block tau (s). A parameter that is not a block takes its fixed value.
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

#include <ceres/dynamic_autodiff_cost_function.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rotation.h"
#include "factors/position_manifold.h"

namespace navtwin {

/// Which installation parameters are parameter blocks, and the fixed values of the others.
struct GnssInstallation {
  bool lever_arm = false;    ///< l_b as three 1-double blocks (x, y, z)
  bool time_offset = false;  ///< tau as one 1-double block
  Eigen::Vector3d lever_arm_b_m = Eigen::Vector3d::Zero();  ///< fixed l_b (lever_arm false)
  double time_offset_s = 0.0;                               ///< fixed tau (time_offset false)

  int NumUnknownBlocks() const { return (lever_arm ? 3 : 0) + (time_offset ? 1 : 0); }

  /// l_b and tau from the blocks after the first `first` ones, or the fixed values.
  template <typename T>
  void Unknowns(T const* const* blocks, int first, Vector3<T>* l_b, T* tau) const {
    int k = first;
    if (lever_arm) {
      *l_b = Vector3<T>(blocks[k][0], blocks[k + 1][0], blocks[k + 2][0]);
      k += 3;
    } else {
      *l_b = lever_arm_b_m.cast<T>();
    }
    *tau = time_offset ? blocks[k][0] : T(time_offset_s);
  }

  void Check(const char* who) const {
    if (!lever_arm_b_m.allFinite() || !std::isfinite(time_offset_s)) {
      throw std::invalid_argument(std::string(who) + ": the fixed lever arm and time offset must be finite");
    }
  }
};

/// The body's motion at the fix: known inputs of the models, held fixed.
struct BodyMotion {
  Eigen::Vector3d omega_ib_b_radps = Eigen::Vector3d::Zero();   ///< bias-corrected gyro rate
  Eigen::Vector3d alpha_ib_b_radps2 = Eigen::Vector3d::Zero();  ///< angular acceleration, body axes
  Eigen::Vector3d a_n_mps2 = Eigen::Vector3d::Zero();           ///< the IMU's NED acceleration
  Eigen::Vector3d j_n_mps3 = Eigen::Vector3d::Zero();           ///< its rate of change

  bool allFinite() const {
    return omega_ib_b_radps.allFinite() && alpha_ib_b_radps2.allFinite() && a_n_mps2.allFinite() &&
           j_n_mps3.allFinite();
  }

  /// v_ant_n and a_ant_n of the antenna at l_b for the IMU velocity v_n and attitude R_n_b.
  template <typename T>
  void Antenna(const Matrix3<T>& R_n_b, const Vector3<T>& v_n, const Vector3<T>& l_b, Vector3<T>* v_ant_n,
               Vector3<T>* a_ant_n) const {
    const Vector3<T> omega = omega_ib_b_radps.cast<T>();
    const Vector3<T> omega_x_l = omega.cross(l_b);
    *v_ant_n = v_n + R_n_b * omega_x_l;
    *a_ant_n = a_n_mps2.cast<T>() + R_n_b * (alpha_ib_b_radps2.cast<T>().cross(l_b) + omega.cross(omega_x_l));
  }
};

namespace gnss_installation_detail {

inline Eigen::Vector3d InverseSigma(const Eigen::Vector3d& std, const char* who) {
  for (int i = 0; i < 3; ++i) {
    if (!(std[i] > 0.0) || !std::isfinite(std[i])) {
      throw std::invalid_argument(std::string(who) + ": the standard deviations must be positive and finite");
    }
  }
  return std.cwiseInverse();
}

/// Stride 8: the position residual's 14 parameters (lever arm and tau on) in two passes.
constexpr int kStride = 8;

}  // namespace gnss_installation_detail

class GnssAntennaPosition {
 public:
  static constexpr int kResiduals = 3;

  /// p_meas: {lat_rad, lon_rad, h_m} of the antenna; std_ned_m: 1-sigma per NED axis, each
  /// > 0 and finite (else std::invalid_argument).
  GnssAntennaPosition(const Eigen::Vector3d& p_meas, const GnssInstallation& installation, const BodyMotion& motion,
                      const Eigen::Vector3d& std_ned_m)
      : p_meas_(p_meas), installation_(installation), motion_(motion) {
    inv_sigma_ = gnss_installation_detail::InverseSigma(std_ned_m, "GnssAntennaPosition");
    installation.Check("GnssAntennaPosition");
    if (!p_meas.allFinite() || !motion.allFinite()) {
      throw std::invalid_argument("GnssAntennaPosition: p_meas and the motion must be finite");
    }
  }

  template <typename T>
  bool operator()(T const* const* blocks, T* residual_ptr) const {
    const T* pos = blocks[0];
    const Eigen::Map<const Quaternion<T>> q_n_b(blocks[1]);
    const Eigen::Map<const Vector3<T>> v_n(blocks[2]);
    Vector3<T> l_b;
    T tau;
    installation_.Unknowns(blocks, 3, &l_b, &tau);
    const T p_meas[3] = {T(p_meas_[0]), T(p_meas_[1]), T(p_meas_[2])};
    Vector3<T> dp_ned;
    PositionMinus(pos, p_meas, dp_ned.data());
    const Matrix3<T> R_n_b = DcmFromQuat<T>(q_n_b);
    Vector3<T> v_ant_n, a_ant_n;
    motion_.Antenna(R_n_b, Vector3<T>(v_n), l_b, &v_ant_n, &a_ant_n);
    Eigen::Map<Vector3<T>> residual(residual_ptr);
    const Vector3<T> carried_back_n =
        -tau * v_ant_n + (T(0.5) * tau * tau) * a_ant_n - (tau * tau * tau / T(6.0)) * motion_.j_n_mps3.cast<T>();
    residual = (dp_ned + R_n_b * l_b + carried_back_n).cwiseProduct(inv_sigma_.cast<T>());
    return true;
  }

  /// 3 residuals; blocks pos (3), q_n_b (4), v_n (3), then the installation's unknowns (1 each).
  static ceres::CostFunction* Create(const Eigen::Vector3d& p_meas, const GnssInstallation& installation,
                                     const BodyMotion& motion, const Eigen::Vector3d& std_ned_m) {
    auto* cost = new ceres::DynamicAutoDiffCostFunction<GnssAntennaPosition, gnss_installation_detail::kStride>(
        new GnssAntennaPosition(p_meas, installation, motion, std_ned_m));
    cost->AddParameterBlock(3);
    cost->AddParameterBlock(4);
    cost->AddParameterBlock(3);
    for (int i = 0; i < installation.NumUnknownBlocks(); ++i) cost->AddParameterBlock(1);
    cost->SetNumResiduals(kResiduals);
    return cost;
  }

 private:
  Eigen::Vector3d p_meas_;
  GnssInstallation installation_;
  BodyMotion motion_;
  Eigen::Vector3d inv_sigma_;
};

class GnssAntennaVelocity {
 public:
  static constexpr int kResiduals = 3;

  /// v_meas_n_mps: the antenna's NED velocity; std_ned_mps: 1-sigma per NED axis, each > 0
  /// and finite (else std::invalid_argument).
  GnssAntennaVelocity(const Eigen::Vector3d& v_meas_n_mps, const GnssInstallation& installation,
                      const BodyMotion& motion, const Eigen::Vector3d& std_ned_mps)
      : v_meas_n_mps_(v_meas_n_mps), installation_(installation), motion_(motion) {
    inv_sigma_ = gnss_installation_detail::InverseSigma(std_ned_mps, "GnssAntennaVelocity");
    installation.Check("GnssAntennaVelocity");
    if (!v_meas_n_mps.allFinite() || !motion.allFinite()) {
      throw std::invalid_argument("GnssAntennaVelocity: v_meas and the motion must be finite");
    }
  }

  template <typename T>
  bool operator()(T const* const* blocks, T* residual_ptr) const {
    const Eigen::Map<const Vector3<T>> v_n(blocks[0]);
    const Eigen::Map<const Quaternion<T>> q_n_b(blocks[1]);
    Vector3<T> l_b;
    T tau;
    installation_.Unknowns(blocks, 2, &l_b, &tau);
    Vector3<T> v_ant_n, a_ant_n;
    motion_.Antenna(DcmFromQuat<T>(q_n_b), Vector3<T>(v_n), l_b, &v_ant_n, &a_ant_n);
    Eigen::Map<Vector3<T>> residual(residual_ptr);
    const Vector3<T> carried_back_n = -tau * a_ant_n + (T(0.5) * tau * tau) * motion_.j_n_mps3.cast<T>();
    residual = (v_ant_n + carried_back_n - v_meas_n_mps_.cast<T>()).cwiseProduct(inv_sigma_.cast<T>());
    return true;
  }

  /// 3 residuals; blocks v_n (3), q_n_b (4), then the installation's unknowns (1 each).
  static ceres::CostFunction* Create(const Eigen::Vector3d& v_meas_n_mps, const GnssInstallation& installation,
                                     const BodyMotion& motion, const Eigen::Vector3d& std_ned_mps) {
    auto* cost = new ceres::DynamicAutoDiffCostFunction<GnssAntennaVelocity, gnss_installation_detail::kStride>(
        new GnssAntennaVelocity(v_meas_n_mps, installation, motion, std_ned_mps));
    cost->AddParameterBlock(3);
    cost->AddParameterBlock(4);
    for (int i = 0; i < installation.NumUnknownBlocks(); ++i) cost->AddParameterBlock(1);
    cost->SetNumResiduals(kResiduals);
    return cost;
  }

 private:
  Eigen::Vector3d v_meas_n_mps_;
  GnssInstallation installation_;
  BodyMotion motion_;
  Eigen::Vector3d inv_sigma_;
};

}  // namespace navtwin
