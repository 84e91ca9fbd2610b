#include "factors/imu_preintegration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include <ceres/autodiff_cost_function.h>
#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "core/earth.h"
#include "core/imu_error_model.h"
#include "core/rotation.h"
#include "factors/position_manifold.h"

namespace navtwin {
namespace {

using Matrix9d = ImuPreintegration::Matrix9d;

/// What the factor needs from a preintegration (copied when the factor is made).
struct ImuFactorData {
  double dt_s = 0.0;
  Eigen::Quaterniond delta_q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d delta_v = Eigen::Vector3d::Zero(), delta_p = Eigen::Vector3d::Zero();
  Eigen::Matrix3d J_R_bg, J_v_bg, J_v_ba, J_p_bg, J_p_ba;
  Eigen::Matrix3d J_R_sg, J_v_sg, J_p_sg, J_v_sa, J_p_sa;
  Eigen::Matrix<double, 9, 6> J_mg = Eigen::Matrix<double, 9, 6>::Zero(), J_ma = Eigen::Matrix<double, 9, 6>::Zero();
  ImuErrors lin;
  Matrix9d sqrt_information = Matrix9d::Identity();  // S = L^-1
  bool whiten = true;
};

ImuFactorData MakeData(const ImuPreintegration& pre, bool whiten) {
  if (!(pre.dt_s() > 0.0) || pre.num_samples() == 0) {
    throw std::invalid_argument("ImuFactor: the preintegration has no sample");
  }
  ImuFactorData d;
  d.dt_s = pre.dt_s();
  d.delta_q = pre.delta_q();
  d.delta_v = pre.delta_v_mps();
  d.delta_p = pre.delta_p_m();
  d.J_R_bg = pre.J_R_bg();
  d.J_v_bg = pre.J_v_bg();
  d.J_v_ba = pre.J_v_ba();
  d.J_p_bg = pre.J_p_bg();
  d.J_p_ba = pre.J_p_ba();
  d.J_R_sg = pre.J_R_sg();
  d.J_v_sg = pre.J_v_sg();
  d.J_p_sg = pre.J_p_sg();
  d.J_v_sa = pre.J_v_sa();
  d.J_p_sa = pre.J_p_sa();
  d.J_mg = pre.J_mg();
  d.J_ma = pre.J_ma();
  d.lin = pre.lin();
  d.whiten = whiten;
  if (whiten) d.sqrt_information = pre.SqrtInformation();
  return d;
}

// The IMU residual (docs/imu-preintegration.md). With dt = t_j - t_i, dbg = bg_i - bg_lin,
// dba = ba_i - ba_lin (and dsg = sg_i - sg_lin, dsa = sa_i - sa_lin when the scale factors
// are unknowns, else zero), the corrected increments
//   dR = dR_lin Exp(J_R_bg dbg + J_R_sg dsg),
//   dv = dv_lin + J_v_bg dbg + J_v_ba dba + J_v_sg dsg + J_v_sa dsa,  dp likewise,
// the midpoint lat_m = (lat_i + lat_j)/2, h_m = (h_i + h_j)/2, the displacement
//   D = NED displacement i -> j with the radii at (lat_m, h_m)   (= integral of v_n dt),
// the mean velocity v_m = D / dt, and
//   w_ie = EarthRateNed(lat_m),  w_en = TransportRateNed(lat_m, h_m, v_m),
//   w_in = w_ie + w_en,  c = 2 w_ie + w_en,  g = GravityNed(lat_m, h_m),
// the prediction, to first order in w_in dt:
//   R_pred  = Exp(-w_in dt) R_i dR
//   v_pred  = v_i + R_i dv - w_in x R_i (dv dt - dp) + g dt - c x D
//   D_pred  = v_i dt + R_i dp - w_in x R_i dv dt^2/6 + g dt^2/2
//             - c x (D dt/2 + (v_i - v_j) dt^2/12)
// and the residuals (prediction minus state, NED):
//   r_phi = Log(R_pred R_j^T),  r_v = v_pred - v_j,  r_p = D_pred - D.
// Whitening: the preintegration noise (dphi in body j, dv and dp in body i) appears in the
// residuals as (R_pred dphi, R_i dv, R_i dp) up to O(w_in dt) ~ 1e-4, so
//   r_w = S [R_pred^T r_phi; R_i^T r_v; R_i^T r_p],  R_pred^T r_phi = Log(R_j^T R_pred),
// with S = L^-1, L L^T the preintegration covariance.
class ImuFactor {
 public:
  explicit ImuFactor(ImuFactorData data) : d_(std::move(data)) {}

  template <typename T>
  bool operator()(const T* pos_i, const T* vel_i, const T* q_i, const T* bg_i, const T* ba_i, const T* pos_j,
                  const T* vel_j, const T* q_j, T* residual) const {
    return Evaluate<T>(pos_i, vel_i, q_i, bg_i, ba_i, nullptr, nullptr, nullptr, nullptr, pos_j, vel_j, q_j,
                       residual);
  }

  /// sg_i, sa_i null: the scale factors at the linearisation point; mg_i, ma_i null: no
  /// axis misalignment.
  template <typename T>
  bool Evaluate(const T* pos_i, const T* vel_i, const T* q_i_ptr, const T* bg_i, const T* ba_i, const T* sg_i,
                const T* sa_i, const T* mg_i, const T* ma_i, const T* pos_j, const T* vel_j, const T* q_j_ptr,
                T* residual_ptr) const {
    const T dt(d_.dt_s);
    const Eigen::Map<const Vector3<T>> v_i(vel_i), v_j(vel_j);
    const Quaternion<T> q_i = Eigen::Map<const Quaternion<T>>(q_i_ptr).normalized();
    const Quaternion<T> q_j = Eigen::Map<const Quaternion<T>>(q_j_ptr).normalized();
    const Vector3<T> dbg = Eigen::Map<const Vector3<T>>(bg_i) - d_.lin.bg_radps.cast<T>();
    const Vector3<T> dba = Eigen::Map<const Vector3<T>>(ba_i) - d_.lin.ba_mps2.cast<T>();

    // Corrected increments (first order).
    Vector3<T> dphi = d_.J_R_bg.cast<T>() * dbg;
    Vector3<T> dv = d_.delta_v.cast<T>() + d_.J_v_bg.cast<T>() * dbg + d_.J_v_ba.cast<T>() * dba;
    Vector3<T> dp = d_.delta_p.cast<T>() + d_.J_p_bg.cast<T>() * dbg + d_.J_p_ba.cast<T>() * dba;
    if (sg_i != nullptr) {
      const Vector3<T> dsg = Eigen::Map<const Vector3<T>>(sg_i) - d_.lin.sg.cast<T>();
      const Vector3<T> dsa = Eigen::Map<const Vector3<T>>(sa_i) - d_.lin.sa.cast<T>();
      dphi += d_.J_R_sg.cast<T>() * dsg;
      dv += d_.J_v_sg.cast<T>() * dsg + d_.J_v_sa.cast<T>() * dsa;
      dp += d_.J_p_sg.cast<T>() * dsg + d_.J_p_sa.cast<T>() * dsa;
    }
    if (mg_i != nullptr) {
      const Eigen::Map<const Eigen::Matrix<T, 6, 1>> mg(mg_i), ma(ma_i);
      const Eigen::Matrix<T, 9, 1> d_mis = d_.J_mg.cast<T>() * mg + d_.J_ma.cast<T>() * ma;
      dphi += d_mis.template segment<3>(0);
      dv += d_mis.template segment<3>(3);
      dp += d_mis.template segment<3>(6);
    }
    const Quaternion<T> dq = d_.delta_q.cast<T>() * QuatFromRotVec<T>(dphi);

    // Earth model at the interval midpoint, with the mean velocity over the interval.
    const T lat_m = (pos_i[0] + pos_j[0]) * T(0.5);
    const T h_m = (pos_i[2] + pos_j[2]) * T(0.5);
    // Displacement i -> j in NED metres with the radii at the midpoint: the difference of
    // the two positions' offsets from a point at (lat_m, lon_i, h_m).
    const T p_mid[3] = {lat_m, pos_i[1], h_m};
    Vector3<T> off_j, off_i;
    PositionMinus(pos_j, p_mid, off_j.data());
    PositionMinus(pos_i, p_mid, off_i.data());
    const Vector3<T> D = off_j - off_i;

    const Vector3<T> v_m = D / dt;
    const Vector3<T> w_ie = wgs84::EarthRateNed(lat_m);
    const Vector3<T> w_en = wgs84::TransportRateNed(lat_m, h_m, v_m);
    const Vector3<T> w_in = w_ie + w_en;
    const Vector3<T> c = T(2) * w_ie + w_en;
    const Vector3<T> g = wgs84::GravityNed(lat_m, h_m);

    const Matrix3<T> R_i = q_i.toRotationMatrix();
    const Vector3<T> Rdv = R_i * dv;
    const Vector3<T> Rdp = R_i * dp;

    const Quaternion<T> q_pred = QuatFromRotVec<T>(-w_in * dt) * q_i * dq;
    const Vector3<T> v_pred = v_i + Rdv - w_in.cross(Rdv * dt - Rdp) + g * dt - c.cross(D);
    const Vector3<T> D_pred = v_i * dt + Rdp - w_in.cross(Rdv) * (dt * dt / T(6)) +
                              g * (dt * dt * T(0.5)) -
                              c.cross(D * (dt * T(0.5)) + (v_i - v_j) * (dt * dt / T(12)));

    Eigen::Map<Eigen::Matrix<T, 9, 1>> residual(residual_ptr);
    if (!d_.whiten) {
      residual.template segment<3>(0) = AttitudeError<T>(q_pred, q_j);  // Log(R_pred R_j^T)
      residual.template segment<3>(3) = v_pred - v_j;
      residual.template segment<3>(6) = D_pred - D;
      return true;
    }
    Eigen::Matrix<T, 9, 1> r_body;
    r_body.template segment<3>(0) = RotVecFromQuat<T>(Quaternion<T>(q_j.conjugate() * q_pred));
    r_body.template segment<3>(3) = R_i.transpose() * (v_pred - v_j);
    r_body.template segment<3>(6) = R_i.transpose() * (D_pred - D);
    residual = d_.sqrt_information.cast<T>() * r_body;
    return true;
  }

 private:
  ImuFactorData d_;
};

/// The factor with the scale-factor blocks (CreateImuScaleFactor).
class ImuScaleFactor {
 public:
  explicit ImuScaleFactor(ImuFactorData data) : factor_(std::move(data)) {}

  template <typename T>
  bool operator()(const T* pos_i, const T* vel_i, const T* q_i, const T* bg_i, const T* ba_i, const T* sg_i,
                  const T* sa_i, const T* pos_j, const T* vel_j, const T* q_j, T* residual) const {
    return factor_.Evaluate<T>(pos_i, vel_i, q_i, bg_i, ba_i, sg_i, sa_i, nullptr, nullptr, pos_j, vel_j, q_j,
                               residual);
  }

 private:
  ImuFactor factor_;
};

/// The factor with the scale-factor and axis-misalignment blocks (CreateImuInstrumentFactor).
class ImuInstrumentFactor {
 public:
  explicit ImuInstrumentFactor(ImuFactorData data) : factor_(std::move(data)) {}

  template <typename T>
  bool operator()(const T* pos_i, const T* vel_i, const T* q_i, const T* bg_i, const T* ba_i, const T* sg_i,
                  const T* sa_i, const T* mg_i, const T* ma_i, const T* pos_j, const T* vel_j, const T* q_j,
                  T* residual) const {
    return factor_.Evaluate<T>(pos_i, vel_i, q_i, bg_i, ba_i, sg_i, sa_i, mg_i, ma_i, pos_j, vel_j, q_j, residual);
  }

 private:
  ImuFactor factor_;
};


}  // namespace

namespace {

/// Biases and scale factors a preintegration can be linearised at: finite, 1 + s > 0.
void CheckLinearisation(const ImuErrors& lin, const char* where) {
  if (!lin.bg_radps.allFinite() || !lin.ba_mps2.allFinite()) {
    throw std::invalid_argument(std::string(where) + ": the linearisation biases must be finite");
  }
  if (!lin.sg.allFinite() || !lin.sa.allFinite() || (lin.sg.array() <= -1.0).any() ||
      (lin.sa.array() <= -1.0).any()) {
    throw std::invalid_argument(std::string(where) + ": the linearisation scale factors must be finite and above -1");
  }
}

ImuErrors BiasesOnly(const Eigen::Vector3d& bg_radps, const Eigen::Vector3d& ba_mps2) {
  ImuErrors e;
  e.bg_radps = bg_radps;
  e.ba_mps2 = ba_mps2;
  return e;
}

}  // namespace

ImuPreintegration::ImuPreintegration(const Eigen::Vector3d& bg_lin_radps,
                                     const Eigen::Vector3d& ba_lin_mps2,
                                     double gyro_arw_rad_per_sqrt_s,
                                     double accel_vrw_mps_per_sqrt_s)
    : ImuPreintegration(BiasesOnly(bg_lin_radps, ba_lin_mps2), gyro_arw_rad_per_sqrt_s, accel_vrw_mps_per_sqrt_s) {}

ImuPreintegration::ImuPreintegration(const ImuErrors& lin, double gyro_arw_rad_per_sqrt_s,
                                     double accel_vrw_mps_per_sqrt_s)
    : lin_(lin), gyro_arw_(gyro_arw_rad_per_sqrt_s), accel_vrw_(accel_vrw_mps_per_sqrt_s) {
  CheckLinearisation(lin, "ImuPreintegration");
  if (!(gyro_arw_ > 0.0) || !std::isfinite(gyro_arw_)) {
    throw std::invalid_argument("ImuPreintegration: gyro ARW must be positive and finite");
  }
  if (!(accel_vrw_ > 0.0) || !std::isfinite(accel_vrw_)) {
    throw std::invalid_argument("ImuPreintegration: accelerometer VRW must be positive and finite");
  }
  Reset();
}

void ImuPreintegration::Reset() {
  dt_s_ = 0.0;
  delta_q_ = Eigen::Quaterniond::Identity();
  delta_R_ = Eigen::Matrix3d::Identity();
  delta_v_.setZero();
  delta_p_.setZero();
  covariance_.setZero();
  J_bg_.setZero();
  J_ba_.setZero();
  J_sg_.setZero();
  J_sa_.setZero();
  J_mg_.setZero();
  J_ma_.setZero();
}

void ImuPreintegration::TrackAxisMisalignment() {
  if (num_samples_ > 0) throw std::logic_error("ImuPreintegration::TrackAxisMisalignment: after the first sample");
  track_misalignment_ = true;
}

double ImuPreintegration::t_start_s() const {
  return num_samples_ == 0 ? std::numeric_limits<double>::quiet_NaN() : t_start_s_;
}

double ImuPreintegration::t_end_s() const {
  return num_samples_ == 0 ? std::numeric_limits<double>::quiet_NaN() : t_end_s_;
}

void ImuPreintegration::DropSamples() {
  std::vector<ImuSample>().swap(samples_);
  samples_dropped_ = true;
}

void ImuPreintegration::Integrate(const ImuSample& s) {
  if (!(s.dt_s > 0.0) || !std::isfinite(s.dt_s) || !std::isfinite(s.t_s)) {
    throw std::invalid_argument("ImuPreintegration: sample at t = " + std::to_string(s.t_s) +
                                " s has a non-positive or non-finite dt_s");
  }
  if (!s.dtheta_b_rad.allFinite() || !s.dv_b_mps.allFinite()) {
    throw std::invalid_argument("ImuPreintegration: sample at t = " + std::to_string(s.t_s) +
                                " s has non-finite increments");
  }
  if (num_samples_ > 0) {
    const double gap = (s.t_s - s.dt_s) - t_end_s_;
    if (std::abs(gap) > std::max(1e-6, 1e-3 * s.dt_s)) {
      throw std::invalid_argument("ImuPreintegration: sample at t = " + std::to_string(s.t_s) +
                                  " s does not start where the previous one ended (gap " +
                                  std::to_string(gap) + " s)");
    }
  }
  if (num_samples_ == 0) t_start_s_ = s.t_s - s.dt_s;
  t_end_s_ = s.t_s;
  ++num_samples_;
  if (!samples_dropped_) samples_.push_back(s);
  Propagate(s);
}

void ImuPreintegration::Reintegrate(const Eigen::Vector3d& bg_lin_radps,
                                    const Eigen::Vector3d& ba_lin_mps2) {
  ImuErrors lin = lin_;
  lin.bg_radps = bg_lin_radps;
  lin.ba_mps2 = ba_lin_mps2;
  Reintegrate(lin);
}

void ImuPreintegration::Reintegrate(const ImuErrors& lin) {
  CheckLinearisation(lin, "ImuPreintegration::Reintegrate");
  if (samples_dropped_) throw std::logic_error("ImuPreintegration::Reintegrate: the samples were dropped");
  lin_ = lin;
  Reset();
  for (const ImuSample& s : samples_) Propagate(s);
}

// One sample, corrected a = D_g (dtheta - bg dt), u = D_a (dv - ba dt) with D_g = diag(1 / (1 + sg)),
// D_a = diag(1 / (1 + sa)) (core/imu_errors.h; docs/imu-preintegration.md).
// Error propagation, x = (dphi, dv, dp), noise n_g on a, n_a on u:
//   x_k = A x_{k-1} + B_g n_g + B_a n_a
//   A   = [ Exp(a)^T       0     0 ]      B_g = [ J_r(a)                  ]
//         [ -dR [w]x       I     0 ]            [ -1/2 dR [u]x            ]
//         [ -dR [s]x dt    I dt  I ]            [ -1/6 dR [u]x dt         ]
//   B_a = [ 0; dR (I + 1/2 [a]x); dR (1/2 I + 1/6 [a]x) dt ],
//   w = u + 1/2 a x u,  s = 1/2 u + 1/6 a x u,  dR = dR_{k-1}.
// A bias change dbg changes a by -D_g dbg dt, a scale-factor change dsg by -D_g diag(a) dsg
// (d/ds of x / (1 + s) is -x / (1 + s)^2), likewise for u, so
//   J_bg <- A J_bg - B_g D_g dt,        J_ba <- A J_ba - B_a D_a dt,
//   J_sg <- A J_sg - B_g D_g diag(a),   J_sa <- A J_sa - B_a D_a diag(u)
// and, at zero axis misalignment, a change mg by -D_g K(a) mg with K(a) the 3x6 matrix of
// MisalignmentColumns (core/imu_error_model.h) ((I + S + M)^-1 = D - D M D + O(M^2)), so
//   J_mg <- A J_mg - B_g D_g K(a),      J_ma <- A J_ma - B_a D_a K(u)
// (exact derivatives of the discrete recursion). The noise densities are taken for the
// corrected sample (the D_g^2 on the raw noise is 1 - 2 sg, 0.4 % for 2000 ppm, left out).
// The covariance uses B_g with
// var(n_g) = ARW^2 dt I, and for the accelerometer the continuous-time integral of white
// noise over the sample, rotated by dR (isotropic, so the rotation drops out):
//   cov(dv, dv) = VRW^2 dt I, cov(dv, dp) = VRW^2 dt^2/2 I, cov(dp, dp) = VRW^2 dt^3/3 I
// (the 1/2 [a]x, 1/6 [a]x terms of B_a, relative size |a| < 1e-2, are left out of the
// covariance).
void ImuPreintegration::Propagate(const ImuSample& sample) {
  const double dt = sample.dt_s;
  const ImuSample corrected = CorrectImu(sample, lin_);
  const Eigen::Vector3d& a = corrected.dtheta_b_rad;
  const Eigen::Vector3d& u = corrected.dv_b_mps;
  const Eigen::Vector3d Dg = (Eigen::Vector3d::Ones() + lin_.sg).cwiseInverse();
  const Eigen::Vector3d Da = (Eigen::Vector3d::Ones() + lin_.sa).cwiseInverse();
  const Eigen::Matrix3d& dR = delta_R_;  // dR_{k-1}
  const Eigen::Vector3d w = u + 0.5 * a.cross(u);
  const Eigen::Vector3d s = 0.5 * u + a.cross(u) / 6.0;
  const Eigen::Quaterniond q_a = QuatFromRotVec<double>(a);
  const Eigen::Matrix3d R_a = q_a.toRotationMatrix();
  const Eigen::Matrix3d I3 = Eigen::Matrix3d::Identity();

  Matrix9d A = Matrix9d::Identity();
  A.block<3, 3>(0, 0) = R_a.transpose();
  A.block<3, 3>(3, 0) = -dR * Skew<double>(w);
  A.block<3, 3>(6, 0) = -dR * Skew<double>(s) * dt;
  A.block<3, 3>(6, 3) = I3 * dt;
  Eigen::Matrix<double, 9, 3> B_g, B_a;
  B_g.block<3, 3>(0, 0) = RightJacobianSO3(a);
  B_g.block<3, 3>(3, 0) = -0.5 * dR * Skew<double>(u);
  B_g.block<3, 3>(6, 0) = -dR * Skew<double>(u) * (dt / 6.0);
  B_a.block<3, 3>(0, 0).setZero();
  B_a.block<3, 3>(3, 0) = dR * (I3 + 0.5 * Skew<double>(a));
  B_a.block<3, 3>(6, 0) = dR * (0.5 * I3 + Skew<double>(a) / 6.0) * dt;

  J_bg_ = A * J_bg_ - B_g * (Dg * dt).asDiagonal();
  J_ba_ = A * J_ba_ - B_a * (Da * dt).asDiagonal();
  J_sg_ = A * J_sg_ - B_g * Dg.cwiseProduct(a).asDiagonal();
  J_sa_ = A * J_sa_ - B_a * Da.cwiseProduct(u).asDiagonal();
  if (track_misalignment_) {
    J_mg_ = A * J_mg_ - B_g * Dg.asDiagonal() * MisalignmentColumns(a);
    J_ma_ = A * J_ma_ - B_a * Da.asDiagonal() * MisalignmentColumns(u);
  }

  Matrix9d Q = gyro_arw_ * gyro_arw_ * dt * B_g * B_g.transpose();
  const double qa = accel_vrw_ * accel_vrw_;
  Q.block<3, 3>(3, 3) += qa * dt * I3;
  Q.block<3, 3>(3, 6) += qa * dt * dt / 2.0 * I3;
  Q.block<3, 3>(6, 3) += qa * dt * dt / 2.0 * I3;
  Q.block<3, 3>(6, 6) += qa * dt * dt * dt / 3.0 * I3;
  covariance_ = A * covariance_ * A.transpose() + Q;
  covariance_ = 0.5 * (covariance_ + covariance_.transpose()).eval();

  // The state itself (after the Jacobians, which use dR_{k-1}).
  delta_p_ += delta_v_ * dt + dR * s * dt;
  delta_v_ += dR * w;
  delta_q_ = (delta_q_ * q_a).normalized();
  delta_R_ = delta_q_.toRotationMatrix();
  dt_s_ += dt;
}

ImuPreintegration::Matrix9d ImuPreintegration::SqrtInformation() const {
  const Eigen::LLT<Matrix9d> llt(covariance_);
  if (num_samples_ == 0 || llt.info() != Eigen::Success) {
    throw std::domain_error("ImuPreintegration: covariance not positive definite");
  }
  const Matrix9d L = llt.matrixL();
  return L.triangularView<Eigen::Lower>().solve(Matrix9d::Identity());
}

ImuPreintegration::Deltas ImuPreintegration::Corrected(const Eigen::Vector3d& bg_radps,
                                                       const Eigen::Vector3d& ba_mps2) const {
  ImuErrors e = lin_;
  e.bg_radps = bg_radps;
  e.ba_mps2 = ba_mps2;
  return Corrected(e);
}

ImuPreintegration::Deltas ImuPreintegration::Corrected(const ImuErrors& e) const {
  const Eigen::Vector3d dbg = e.bg_radps - lin_.bg_radps, dba = e.ba_mps2 - lin_.ba_mps2;
  const Eigen::Vector3d dsg = e.sg - lin_.sg, dsa = e.sa - lin_.sa;
  Deltas d;
  d.delta_q = (delta_q_ * QuatFromRotVec<double>(J_R_bg() * dbg + J_R_sg() * dsg)).normalized();
  d.delta_v_mps = delta_v_ + J_v_bg() * dbg + J_v_ba() * dba + J_v_sg() * dsg + J_v_sa() * dsa;
  d.delta_p_m = delta_p_ + J_p_bg() * dbg + J_p_ba() * dba + J_p_sg() * dsg + J_p_sa() * dsa;
  return d;
}

ceres::CostFunction* CreateImuFactor(std::shared_ptr<const ImuPreintegration> pre) {
  if (!pre) throw std::invalid_argument("CreateImuFactor: null preintegration");
  return new ceres::AutoDiffCostFunction<ImuFactor, 9, 3, 3, 4, 3, 3, 3, 3, 4>(
      new ImuFactor(MakeData(*pre, /*whiten=*/true)));
}

ceres::CostFunction* CreateImuScaleFactor(std::shared_ptr<const ImuPreintegration> pre) {
  if (!pre) throw std::invalid_argument("CreateImuScaleFactor: null preintegration");
  return new ceres::AutoDiffCostFunction<ImuScaleFactor, 9, 3, 3, 4, 3, 3, 3, 3, 3, 3, 4>(
      new ImuScaleFactor(MakeData(*pre, /*whiten=*/true)));
}

ceres::CostFunction* CreateImuInstrumentFactor(std::shared_ptr<const ImuPreintegration> pre) {
  if (!pre) throw std::invalid_argument("CreateImuInstrumentFactor: null preintegration");
  if (!pre->tracks_axis_misalignment()) {
    throw std::invalid_argument("CreateImuInstrumentFactor: the preintegration does not track the axis misalignments");
  }
  return new ceres::AutoDiffCostFunction<ImuInstrumentFactor, 9, 3, 3, 4, 3, 3, 3, 3, 6, 6, 3, 3, 4>(
      new ImuInstrumentFactor(MakeData(*pre, /*whiten=*/true)));
}

Eigen::Matrix<double, 9, 1> ImuFactorResidual(const ImuPreintegration& pre, const double* pos_i,
                                              const double* vel_i, const double* q_i,
                                              const double* bg_i, const double* ba_i,
                                              const double* pos_j, const double* vel_j,
                                              const double* q_j, bool whitened) {
  const ImuFactor factor(MakeData(pre, whitened));
  Eigen::Matrix<double, 9, 1> r;
  factor(pos_i, vel_i, q_i, bg_i, ba_i, pos_j, vel_j, q_j, r.data());
  return r;
}

Eigen::Matrix<double, 9, 1> ImuScaleFactorResidual(const ImuPreintegration& pre, const double* pos_i,
                                                   const double* vel_i, const double* q_i, const double* bg_i,
                                                   const double* ba_i, const double* sg_i, const double* sa_i,
                                                   const double* pos_j, const double* vel_j, const double* q_j,
                                                   bool whitened) {
  const ImuFactor factor(MakeData(pre, whitened));
  Eigen::Matrix<double, 9, 1> r;
  factor.Evaluate<double>(pos_i, vel_i, q_i, bg_i, ba_i, sg_i, sa_i, nullptr, nullptr, pos_j, vel_j, q_j, r.data());
  return r;
}

Eigen::Matrix<double, 9, 1> ImuInstrumentFactorResidual(const ImuPreintegration& pre, const double* pos_i,
                                                        const double* vel_i, const double* q_i, const double* bg_i,
                                                        const double* ba_i, const double* sg_i, const double* sa_i,
                                                        const double* mg_i, const double* ma_i, const double* pos_j,
                                                        const double* vel_j, const double* q_j, bool whitened) {
  const ImuFactor factor(MakeData(pre, whitened));
  Eigen::Matrix<double, 9, 1> r;
  factor.Evaluate(pos_i, vel_i, q_i, bg_i, ba_i, sg_i, sa_i, mg_i, ma_i, pos_j, vel_j, q_j, r.data());
  return r;
}

}  // namespace navtwin
