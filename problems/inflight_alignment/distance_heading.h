// Heading error from the distance flown (seed 003, equations 6-14): the distance flown
// since alignment started, the heading error of equation 8 with its standard deviation,
// and the separation of the heading error from the Schuler-periodic position errors that
// sensor biases and initial errors cause. docs/inflight-alignment.md gives the
// derivations; the filter, the Kalman-only baseline and the batch build on these.
//
// SIGN CONVENTION. Distance errors are INS minus reference (err = p_ins - p_ref, as in
// the seed), and the heading error is
//     dH = yaw_ins - yaw_true = -phi_D,
// where phi_n is the project's attitude error R_n_b_true = Exp(phi_n) R_n_b_est
// (core/rotation.h): a rotation phi_D about the down axis adds phi_D to the yaw, so the
// INS yaw is the true yaw minus phi_D. An INS whose heading is dH too large (clockwise
// seen from above) integrates a velocity rotated by dH from north towards east, so its
// displacement is Rz(dH) times the true one and, to first order,
//     err_N = -dH dE,   err_E = dH dN.
// To correct the INS with a result: yaw_corrected = yaw_ins - dH, i.e. phi_D = -dH.
// (tests/problems/inflight_alignment/distance_heading_test.cc proves the sign on a
// simulated flight.)
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/earth.h"

namespace navtwin::inflight {

/// North-east offset (m) of p from start in the curvilinear frame of the start point
/// (the frame of gps_smoother.h): N = (lat - lat0)(R_M(lat0) + h0),
/// E = (lon - lon0)(R_N(lat0) + h0) cos lat0, longitude difference wrapped to (-pi, pi].
Eigen::Vector2d NorthEastFromStart(const wgs84::Geodetic& start, const wgs84::Geodetic& p);

/// Distance flown north and east (m) since alignment started, in one of two forms fixed
/// by the first call:
///  - velocity form, Add(t, v_n): trapezoidal integral of the NED velocity (the vertical
///    component is ignored). Exact for velocity linear between samples.
///  - position form, AddPosition(t, p): current minus initial position mapped by
///    NorthEastFromStart. It differs from the path integral of the velocity by the
///    convergence of the meridians, about |E| tan(lat0) |N| / R after flying N north and
///    E east (and by (h - h0) / R relative if the height changes), which changes the
///    direction of the distance by less than 1e-3 rad at 10 km and so the heading error
///    of equation 8 by less than 1e-3 of itself.
/// Equation 8 needs the displacement that the heading error rotates: the velocity gained
/// since the INS velocity was set. An INS started at rest uses the distance itself; one
/// initialised in flight with velocity v0 should feed Add(t, v_n - v0) (see the docs).
class DistanceFlown {
 public:
  enum class Form { kNone, kVelocity, kPosition };

  /// Velocity form. The first call sets the start (distance zero). Throws
  /// std::invalid_argument for non-finite input or time going backwards, and
  /// std::logic_error after AddPosition.
  void Add(double t_s, const Eigen::Vector3d& v_n_mps);
  /// Position form. The first call sets the start position. Same errors as Add.
  void AddPosition(double t_s, const wgs84::Geodetic& p);

  Form form() const { return form_; }
  bool started() const { return form_ != Form::kNone; }
  double start_time_s() const { return t0_s_; }
  double time_s() const { return t_s_; }
  double north_m() const { return ne_m_.x(); }
  double east_m() const { return ne_m_.y(); }
  Eigen::Vector2d north_east_m() const { return ne_m_; }
  double horizontal_m() const { return ne_m_.norm(); }

 private:
  void CheckTime(double t_s, Form form) const;

  Form form_ = Form::kNone;
  double t0_s_ = 0.0;
  double t_s_ = 0.0;
  Eigen::Vector2d ne_m_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d last_v_ne_mps_ = Eigen::Vector2d::Zero();  // velocity form
  wgs84::Geodetic start_;                                    // position form
};

/// Equation 8 as an angle, templated so that a Ceres residual can use it:
///     tan dH = (dN err_E - dE err_N) / (dN^2 + dE^2).
/// dN, dE: distance flown (m); err_N, err_E: distance error, INS minus reference (m).
/// The exact relation with (dN, dE) the INS displacement has dN err_N + dE err_E
/// subtracted from the denominator (the seed's equation 5 for distances); dropping it
/// makes this atan(sin dH) = dH - dH^3/2 + ..., 3e-4 arcmin at 20 arcmin.
template <typename T>
T DistanceHeadingError(const T& dn_m, const T& de_m, const T& err_n_m, const T& err_e_m) {
  using std::atan2;
  return atan2(dn_m * err_e_m - de_m * err_n_m, dn_m * dn_m + de_m * de_m);
}

/// d dH / d(dN, dE, err_N, err_E) of DistanceHeadingError. With D2 = dN^2 + dE^2,
/// u = (dN err_E - dE err_N) / D2 and c = 1 / (1 + u^2):
///     d/d dN  = c (err_E - 2 u dN) / D2      d/d err_N = -c dE / D2
///     d/d dE  = c (-err_N - 2 u dE) / D2     d/d err_E =  c dN / D2
Eigen::Matrix<double, 1, 4> DistanceHeadingJacobian(double dn_m, double de_m, double err_n_m,
                                                    double err_e_m);

struct DistanceHeading {
  double dh_rad = 0.0;     ///< yaw_ins - yaw_true (header comment)
  double sigma_rad = 0.0;  ///< 1 sigma from the covariance of (err_N, err_E); 0 if none given
  double distance_m = 0.0; ///< sqrt(dN^2 + dE^2)
};

/// Equation 8 with first-order propagation of the 2x2 covariance of (err_N, err_E) (m^2):
/// sigma^2 = J P J^T with J the last two columns of DistanceHeadingJacobian. The distance
/// flown is taken as exact (its errors scale dH, which is small). Throws
/// std::invalid_argument when an input is not finite, the distance is zero, or the
/// covariance is not symmetric with non-negative variances.
DistanceHeading HeadingErrorFromDistance(double dn_m, double de_m, double err_n_m, double err_e_m,
                                         const Eigen::Matrix2d& cov_err_ne_m2 = Eigen::Matrix2d::Zero());

// ---------------------------------------------------------------------------------------
// Separating the heading error from the Schuler part (equations 9-14).
//
// Integrating equation 14 from the start of alignment (x = w t, w the Schuler rate) gives
// the position error of each horizontal axis as
//     err(t) = c0 + c1 sin(x)/w + c2 (1 - cos x)/w^2 + c3 (x - sin x)/w^3
// with, for east (north in brackets):
//     c0 = dE(0)                 [dN(0)]                 m       position error at start
//     c1 = dV_E(0)               [dV_N(0)]               m/s     velocity error at start
//     c2 = df_E - g eps_N(0)     [df_N + g eps_E(0)]     m/s^2   accelerometer bias and tilt
//     c3 = -g dw_N               [g dw_E]                m/s^3   gyro bias (and heading x Earth rate)
// (docs/inflight-alignment.md). The heading term adds err_E = dH dN, err_N = -dH dE.

enum class SchulerTerm { kOffset = 0, kVelocity = 1, kTilt = 2, kGyro = 3 };
constexpr int kSchulerTerms = 4;

/// Schuler rate sqrt(g / R) at a latitude and height (R the Gaussian mean radius
/// sqrt(R_M R_N) + h), rad/s; about 1.24e-3 rad/s, a period of 84 minutes.
double SchulerRate(double lat_rad, double h_m);

/// The four basis functions of the comment above at time t since alignment started (m
/// per unit coefficient), evaluated without cancellation for small w t.
std::array<double, kSchulerTerms> SchulerBasis(double t_s, double schuler_rate_radps);

/// One epoch: time since alignment started, distance flown, distance error (INS minus
/// reference), in metres.
struct DistanceErrorSample {
  double t_s = 0.0;
  double dn_m = 0.0;
  double de_m = 0.0;
  double err_n_m = 0.0;
  double err_e_m = 0.0;
};

struct SeparationOptions {
  double schuler_rate_radps = 1.2407e-3;  ///< sqrt(9.80665 / 6371000); see SchulerRate
  /// Terms fitted on both axes, index SchulerTerm. The velocity term is off by default:
  /// on a straight flight at constant speed dH dN(t) is linear in t, and so is an initial
  /// velocity error with the gyro term that holds it constant, so the two cannot be told
  /// apart (docs/inflight-alignment.md); the distance must then start where the velocity
  /// error is known (at rest, or where the INS velocity was set).
  std::array<bool, kSchulerTerms> terms{{true, false, true, true}};
  /// Position error 1 sigma per axis (m); <= 0: estimated from the fit residual.
  double position_sigma_m = 0.0;
  /// Prior 1 sigma of each term's coefficient (units of the table above, both axes;
  /// 0: no prior, the coefficient is free), e.g. from the sensor specification:
  /// tilt sqrt(df^2 + (g eps0)^2), gyro g dw (plus Earth rate x heading error, see the
  /// docs). With priors the fit is the maximum a posteriori estimate: a term that the
  /// flight cannot yet separate from the heading stays near zero and its uncertainty
  /// goes into the heading sigma, which is what a short flight needs (the docs show
  /// why a condition number cannot tell a short flight from a long one). Needs
  /// position_sigma_m > 0.
  std::array<double, kSchulerTerms> prior_sigma{};
  /// Where > 0, the prior sigma of a term on the NORTH axis instead of prior_sigma (the
  /// east axis keeps prior_sigma). E.g. the Earth-rate coupling of the heading error,
  /// Omega cos L dH, acts like an east gyro bias, so it widens only the north axis's gyro
  /// term: g sqrt(dw^2 + (Omega cos L sigma_dH0)^2) north, g dw east.
  std::array<double, kSchulerTerms> prior_sigma_north{};
  /// Largest condition number of the column-scaled design matrix accepted; above it
  /// terms are dropped in the order velocity, offset, gyro, tilt, until it is met.
  double max_condition = 1e6;
};

struct SchulerCoefficients {
  std::array<bool, kSchulerTerms> used{};  ///< fitted (false: held at zero)
  std::array<double, kSchulerTerms> north{};  ///< c0..c3 of the north axis (units above)
  std::array<double, kSchulerTerms> east{};
  std::array<double, kSchulerTerms> north_sigma{};
  std::array<double, kSchulerTerms> east_sigma{};
};

struct HeadingSeparation {
  double dh_rad = 0.0;     ///< yaw_ins - yaw_true
  double sigma_rad = 0.0;  ///< 1 sigma
  /// The sigma dH would have if the Schuler part were known (heading column alone, same
  /// position sigma): sigma_rad / this is what removing the Schuler part costs.
  double sigma_heading_only_rad = 0.0;
  SchulerCoefficients schuler;
  double position_sigma_m = 0.0;  ///< the sigma used (given, or from the residual)
  double residual_rms_m = 0.0;
  double condition_number = 0.0;  ///< of the column-scaled design matrix finally used
  int samples = 0;
  /// Empty when the requested terms were fitted; otherwise which terms were dropped and why.
  std::string note;
};

/// Linear least squares over all samples of
///     err_E = dH dN + sum_k c_k^E b_k(t),   err_N = -dH dE + sum_k c_k^N b_k(t)
/// (equation 8 to first order per sample, plus the basis above). Columns are scaled to
/// unit norm and time enters as w t, so the fit is solved (SVD) at unit scale. sigma
/// comes from options.position_sigma_m or, when that is <= 0, from the residual with
/// 2 samples - unknowns degrees of freedom. Throws std::invalid_argument for non-finite
/// samples, too few samples for the unknowns (a residual sigma needs one more), a
/// heading column that is zero (no distance flown), or priors without a position sigma.
/// With priors each prior adds the pseudo-measurement c_k = 0 +- prior_sigma_k.
HeadingSeparation SeparateHeadingError(const std::vector<DistanceErrorSample>& samples,
                                       const SeparationOptions& options = SeparationOptions());

}  // namespace navtwin::inflight
