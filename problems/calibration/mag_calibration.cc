// Magnetometer calibration: the methods of mag_calibration.h. The equations are in
// docs/calibration-magnetometer.md; the comments below say what each step computes.
#include "problems/calibration/mag_calibration.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <ceres/ceres.h>
#include <ceres/manifold.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "core/linalg.h"
#include "core/rotation.h"
#include "problems/calibration/mag_ellipsoid.h"

namespace navtwin::calibration {
namespace {

using Vector9d = Eigen::Matrix<double, 9, 1>;
using Matrix9d = Eigen::Matrix<double, 9, 9>;

/// 9 unknowns (h and the 6 entries of A); a few more so that the fit is overdetermined.
constexpr int kMinEllipsoidSamples = 12;
/// The recursive fit's quadric is in units of m / s with s this scale (uT) unless a field
/// magnitude is given: it keeps the monomials near 1 for Earth-like fields.
constexpr double kRecursiveScale_uT = 50.0;
/// Initial covariance of the recursive fit's quadric parameters (scaled units): large
/// against the information of one sample (~1), so the recursive estimate equals the batch
/// algebraic least squares after a few samples.
constexpr double kRecursiveP0 = 1e6;
/// 5 unknowns of the planar fit (centre 2, symmetric 2x2 correction 3), overdetermined.
constexpr int kMinPlanarSamples = 12;
/// The bidirectional phase is read from the samples within this angle of each x extreme.
constexpr double kPhaseWindowRad = 15.0 * kDegToRad;
/// Largest accepted heading gap of the 2-axis turn (both extremes of both axes must be seen).
constexpr double kMaxHeadingGapRad = 45.0 * kDegToRad;
constexpr int kMinBidirectionalSamples = 8;
/// Plausibility of a 3-axis fit: magnetometer soft iron distorts the axes by percents, rarely
/// 20 %; a fitted correction whose axes differ by more than this factor is a small patch of
/// the sphere fitted by a distorted ellipsoid, not iron.
constexpr double kMaxCorrectionAxisRatio = 2.0;
/// ... and a hard iron whose sigma exceeds this fraction of the field is not determined.
constexpr double kMaxHardIronSigmaFraction = 0.05;
/// The 2-axis limits that follow from the same axis ratio k = 2 (the x/y plane of a
/// symmetric soft iron): the y/x scale lies in [1/k, k]; the x/y phase is largest with the
/// principal axes at 45 deg, where sin(phase) = (k^2 - 1) / (k^2 + 1) = 0.6 (36.9 deg).
constexpr double kMaxBidirectionalSinPhase =
    (kMaxCorrectionAxisRatio * kMaxCorrectionAxisRatio - 1.0) / (kMaxCorrectionAxisRatio * kMaxCorrectionAxisRatio + 1.0);
/// Largest angle between the data's plane normal and sensor z for the 2-axis method: the
/// soft iron it accepts tilts the plane of the readings by a few degrees; a plane 20 deg
/// off is a sensor (or mounting) tilt, worth ~28 deg of heading error at 57 deg
/// inclination (TiltErrorBound), or a different sensor plane altogether (FitPlanar).
constexpr double kMaxBidirectionalPlaneTiltRad = 20.0 * kDegToRad;

std::string Vec(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s.precision(3);
  s << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return s.str();
}

void CheckSamplesFinite(const std::vector<MagSample>& samples, const char* what) {
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!samples[i].m_b_uT.allFinite()) {
      throw std::invalid_argument(std::string(what) + ": sample " + std::to_string(i) + " (t = " +
                                  std::to_string(samples[i].t_s) + " s) is not finite (NaN or inf)");
    }
  }
}

/// Mean and standard deviation of values.
std::pair<double, double> MeanStd(const std::vector<double>& values) {
  if (values.empty()) return {0.0, 0.0};
  double sum = 0.0;
  for (double v : values) sum += v;
  const double mean = sum / static_cast<double>(values.size());
  double ss = 0.0;
  for (double v : values) ss += (v - mean) * (v - mean);
  return {mean, std::sqrt(ss / static_cast<double>(values.size()))};
}

/// Quadric regressor of a (scaled, centred) point x: the quadric
///   x^T M x + 2 v^T x = 1,  M = [[t0, t3, t4], [t3, t1, t5], [t4, t5, t2]],  v = (t6, t7, t8)
/// is phi(x)^T theta = 1 with phi = [x^2, y^2, z^2, 2xy, 2xz, 2yz, 2x, 2y, 2z].
Vector9d QuadricRegressor(const Eigen::Vector3d& x) {
  Vector9d phi;
  phi << x.x() * x.x(), x.y() * x.y(), x.z() * x.z(), 2.0 * x.x() * x.y(), 2.0 * x.x() * x.z(),
      2.0 * x.y() * x.z(), 2.0 * x.x(), 2.0 * x.y(), 2.0 * x.z();
  return phi;
}

/// Smallest / largest eigenvalue of the covariance of points (and the eigenvector of the
/// smallest): near 0 when all lie near one plane (that plane's normal).
struct Spread {
  double ratio = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};
Spread SpreadOfCovariance(const Eigen::Matrix3d& covariance) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(covariance);
  Spread s;
  const double largest = eig.eigenvalues()(2);
  s.ratio = largest > 0.0 ? std::max(0.0, eig.eigenvalues()(0)) / largest : 0.0;
  s.normal = eig.eigenvectors().col(0);
  return s;
}

/// The coverage message shared by the batch and recursive fits.
[[noreturn]] void ThrowPlanar(const char* what, const Spread& s, double min_coverage) {
  std::ostringstream msg;
  msg.precision(3);
  msg << what << ": all samples near one plane (smallest/largest spread " << s.ratio << " < " << min_coverage
      << ", plane normal " << Vec(s.normal)
      << " in sensor axes): the axis normal to it is not calibrated; rotate the sensor about another axis";
  throw std::runtime_error(msg.str());
}

/// h, A and B from the quadric theta in units x = (m - offset) / scale:
///   centre c = -M^-1 v, k = 1 + c^T M c, Q = M / k (positive definite for an ellipsoid),
///   (x - c)^T Q (x - c) = 1,  so A_unit = Q^(1/2) / scale maps m - h to the unit sphere;
///   h = offset + scale c;  B = field_uT if given, else det(A_unit)^(-1/3) (the geometric
///   mean of the semi-axes), and A = B A_unit.
/// Returns false (with the reason) when the quadric is not an ellipsoid.
bool EllipsoidFromQuadric(const Vector9d& t, const Eigen::Vector3d& offset_uT, double scale_uT, double field_uT,
                          MagCalibration* c, std::string* why) {
  Eigen::Matrix3d M;
  M << t(0), t(3), t(4), t(3), t(1), t(5), t(4), t(5), t(2);
  const Eigen::Vector3d v = t.tail<3>();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig_m(M);
  const Eigen::Vector3d lm = eig_m.eigenvalues();
  if (!(std::abs(lm(0)) > 1e-9 * std::abs(lm(2)))) {
    *why = "the quadric is singular (a cylinder or plane, not an ellipsoid)";
    return false;
  }
  const Eigen::Vector3d centre = -eig_m.eigenvectors() * (lm.cwiseInverse().asDiagonal() *
                                                           (eig_m.eigenvectors().transpose() * v));
  const double k = 1.0 + centre.dot(M * centre);
  const Eigen::Vector3d lq = lm / k;
  if (!(k != 0.0) || !(lq.minCoeff() > 0.0) || !lq.allFinite()) {
    *why = "the quadric is not an ellipsoid (its matrix is not positive definite)";
    return false;
  }
  const Eigen::Matrix3d A_unit = eig_m.eigenvectors() * lq.cwiseSqrt().asDiagonal() *
                                 eig_m.eigenvectors().transpose() / scale_uT;
  const double B = field_uT > 0.0 ? field_uT : std::cbrt(1.0 / A_unit.determinant());
  c->hard_iron_uT = offset_uT + scale_uT * centre;
  c->correction = B * A_unit;
  c->field_uT = B;
  if (!c->hard_iron_uT.allFinite() || !c->correction.allFinite() || !std::isfinite(B)) {
    *why = "the ellipsoid is not finite";
    return false;
  }
  return true;
}

void CheckEllipsoidOptions(const EllipsoidFitOptions& o) {
  if (o.loss != MagLoss::kNone && (!(o.loss_scale_uT > 0.0) || !std::isfinite(o.loss_scale_uT))) {
    throw std::invalid_argument("FitEllipsoid: loss_scale_uT must be positive and finite");
  }
  if (!std::isfinite(o.field_uT)) throw std::invalid_argument("FitEllipsoid: field_uT must be finite");
  if (o.max_iterations < 1) throw std::invalid_argument("FitEllipsoid: max_iterations must be >= 1");
  if (!(o.min_coverage >= 0.0 && o.min_coverage < 1.0)) {
    throw std::invalid_argument("FitEllipsoid: min_coverage must be in [0, 1)");
  }
}

std::unique_ptr<ceres::LossFunction> MakeLoss(MagLoss loss, double scale_uT) {
  switch (loss) {
    case MagLoss::kHuber:
      return std::make_unique<ceres::HuberLoss>(scale_uT);
    case MagLoss::kCauchy:
      return std::make_unique<ceres::CauchyLoss>(scale_uT);
    case MagLoss::kNone:
      break;
  }
  return nullptr;
}

/// Largest gap (rad) between angles on the circle; 2 pi for fewer than 2 angles.
double LargestGap(std::vector<double> angles_rad) {
  if (angles_rad.size() < 2) return 2.0 * M_PI;
  std::sort(angles_rad.begin(), angles_rad.end());
  double gap = angles_rad.front() + 2.0 * M_PI - angles_rad.back();
  for (std::size_t i = 1; i < angles_rad.size(); ++i) gap = std::max(gap, angles_rad[i] - angles_rad[i - 1]);
  return gap;
}

/// Sample mean and covariance of the readings.
std::pair<Eigen::Vector3d, Eigen::Matrix3d> MeanCovariance(const std::vector<MagSample>& samples) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const MagSample& s : samples) mean += s.m_b_uT;
  mean /= static_cast<double>(samples.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const MagSample& s : samples) cov += (s.m_b_uT - mean) * (s.m_b_uT - mean).transpose();
  return {mean, cov / static_cast<double>(samples.size())};
}

std::vector<double> Magnitudes(const std::vector<MagSample>& samples) {
  std::vector<double> out;
  out.reserve(samples.size());
  for (const MagSample& s : samples) out.push_back(s.m_b_uT.norm());
  return out;
}

/// Dense, single-threaded, silent solve of a small fit; throws std::runtime_error (prefixed
/// with `who`) when Ceres gives no usable solution.
void Solve(int max_iterations, const std::string& who, ceres::Problem* problem) {
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = max_iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, problem, &summary);
  if (!summary.IsSolutionUsable()) {
    throw std::runtime_error(who + ": the least-squares solve failed: " + summary.message);
  }
}

/// The M-estimator (sandwich) covariance of a robust least-squares fit with one scalar
/// residual per sample: Cov = H^-1 G H^-1 N / (N - P), H = sum psi'_i J_i^T J_i,
/// G = sum (rho'_i r_i)^2 J_i^T J_i, psi' = rho' + 2 s rho'' (s = r^2; the robust second
/// derivative, clamped at 0). Also counts the samples the loss down-weights below 0.5.
template <int P>
class RobustSandwich {
 public:
  using Vector = Eigen::Matrix<double, P, 1>;
  using Matrix = Eigen::Matrix<double, P, P>;

  explicit RobustSandwich(const ceres::LossFunction* loss) : loss_(loss) {}

  void Add(const Vector& j, double r) {
    double rho[3] = {r * r, 1.0, 0.0};
    if (loss_ != nullptr) loss_->Evaluate(r * r, rho);
    if (rho[1] < 0.5) ++downweighted_;
    H_.template selfadjointView<Eigen::Lower>().rankUpdate(j, std::max(0.0, rho[1] + 2.0 * r * r * rho[2]));
    G_.template selfadjointView<Eigen::Lower>().rankUpdate(j, (rho[1] * r) * (rho[1] * r));
    ++count_;
  }

  /// Throws std::runtime_error (prefixed with `who`) when H is singular.
  Matrix Covariance(const std::string& who) const {
    const Matrix H = H_.template selfadjointView<Eigen::Lower>();
    const Matrix G = G_.template selfadjointView<Eigen::Lower>();
    const Eigen::LDLT<Matrix> ldlt(H);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) {
      throw std::runtime_error(who + ": the parameters are not observable from these samples "
                               "(information matrix singular)");
    }
    const Matrix H_inv = ldlt.solve(Matrix::Identity());
    return H_inv * G * H_inv * (static_cast<double>(count_) / (count_ - P));
  }
  int downweighted() const { return downweighted_; }

 private:
  const ceres::LossFunction* loss_;
  Matrix H_ = Matrix::Zero();
  Matrix G_ = Matrix::Zero();
  int count_ = 0;
  int downweighted_ = 0;
};

}  // namespace

double FieldMagnitudeSpread_uT(const std::vector<MagSample>& samples) {
  return MeanStd(Magnitudes(samples)).second;
}

Eigen::Vector3d ApplyMagCalibration(const MagCalibration& c, const Eigen::Vector3d& m_uT) {
  return RemoveIron(m_uT, c.hard_iron_uT, c.correction);
}

FieldMagnitude FieldMagnitudeOf(const MagCalibration& c, const Eigen::Vector3d& m_uT) {
  const Eigen::Vector3d calibrated = ApplyMagCalibration(c, m_uT);
  const Eigen::Vector3d& n = c.uncalibrated_axis;
  if (n.squaredNorm() == 0.0) return {m_uT.norm(), calibrated.norm()};
  const Eigen::Matrix3d in_plane = Eigen::Matrix3d::Identity() - n * n.transpose() / n.squaredNorm();
  return {(in_plane * m_uT).norm(), (in_plane * calibrated).norm()};
}

void WriteMagResidualsCsv(std::ostream& out, const MagCalibration& c, const std::vector<MagSample>& samples) {
  out << "t_s,field_before_uT,field_after_uT\n";
  for (const MagSample& s : samples) {
    const FieldMagnitude f = FieldMagnitudeOf(c, s.m_b_uT);
    out << s.t_s << "," << f.before_uT << "," << f.after_uT << "\n";
  }
}

// ------------------------------------------------------------------------ batch ellipsoid

MagCalibration FitEllipsoid(const std::vector<MagSample>& samples, const EllipsoidFitOptions& options) {
  CheckEllipsoidOptions(options);
  const int n = static_cast<int>(samples.size());
  if (n < kMinEllipsoidSamples) {
    throw std::invalid_argument("FitEllipsoid: too few samples: " + std::to_string(n) + " (need at least " +
                                std::to_string(kMinEllipsoidSamples) + " for 9 unknowns)");
  }
  CheckSamplesFinite(samples, "FitEllipsoid");

  // 1. Spread of the raw samples about their mean (one plane -> no calibration of its normal).
  const auto [mean, cov] = MeanCovariance(samples);
  const Spread spread = SpreadOfCovariance(cov);
  if (spread.ratio < options.min_coverage) ThrowPlanar("FitEllipsoid", spread, options.min_coverage);
  const double scale_uT = std::sqrt(cov.trace());  // ~ the radius: monomials of x near 1
  if (!(scale_uT > 0.0)) throw std::runtime_error("FitEllipsoid: all samples are equal");

  // 2. Algebraic start: linear least squares phi(x_i)^T theta = 1, x_i = (m_i - mean) / s.
  Matrix9d normal = Matrix9d::Zero();
  Vector9d rhs = Vector9d::Zero();
  for (const MagSample& s : samples) {
    const Vector9d phi = QuadricRegressor((s.m_b_uT - mean) / scale_uT);
    normal.selfadjointView<Eigen::Lower>().rankUpdate(phi);
    rhs += phi;
  }
  normal = normal.selfadjointView<Eigen::Lower>();
  const SymmetricEigen eig_n = SymmetricEigenDecomposition(normal);
  if (!(eig_n.values(0) > 1e-12 * eig_n.values(8))) {
    throw std::runtime_error("FitEllipsoid: the samples do not determine an ellipsoid (normal equations singular): "
                             "rotate the sensor through more attitudes");
  }
  const Vector9d theta = eig_n.vectors * (eig_n.values.cwiseInverse().asDiagonal() * (eig_n.vectors.transpose() * rhs));
  MagCalibration c;
  std::string why;
  if (!EllipsoidFromQuadric(theta, mean, scale_uT, options.field_uT, &c, &why)) {
    throw std::runtime_error("FitEllipsoid: algebraic start failed: " + why +
                             "; the samples cover too little of the sphere or are too noisy");
  }

  // 3. Directions from the centre must cover the sphere (not only one side of it).
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const MagSample& s : samples) {
    const Eigen::Vector3d d = s.m_b_uT - c.hard_iron_uT;
    const double norm = d.norm();
    if (norm > 0.0) scatter += d * d.transpose() / (norm * norm);
  }
  const Spread directions = SpreadOfCovariance(scatter / n);
  if (directions.ratio < options.min_coverage) {
    std::ostringstream msg;
    msg.precision(3);
    msg << "FitEllipsoid: the field directions cover too little of the sphere (smallest/largest direction scatter "
        << directions.ratio << " < " << options.min_coverage << "; least seen direction " << Vec(directions.normal)
        << " in sensor axes): rotate the sensor so that this axis points up and down";
    throw std::runtime_error(msg.str());
  }

  // 4. Geometric fit: min sum rho(r_i^2), r_i = |A (m_i - h)| - B (uT), B held constant.
  double h[3] = {c.hard_iron_uT.x(), c.hard_iron_uT.y(), c.hard_iron_uT.z()};
  double a[6] = {c.correction(0, 0), c.correction(0, 1), c.correction(0, 2),
                 c.correction(1, 1), c.correction(1, 2), c.correction(2, 2)};
  double B = c.field_uT;
  std::unique_ptr<ceres::LossFunction> loss = MakeLoss(options.loss, options.loss_scale_uT);
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::vector<ceres::ResidualBlockId> blocks;
  blocks.reserve(samples.size());
  for (const MagSample& s : samples) {
    blocks.push_back(problem.AddResidualBlock(MagEllipsoid::Create(s.m_b_uT, 1.0), loss.get(), h, a, &B));
  }
  problem.SetParameterBlockConstant(&B);
  Solve(options.max_iterations, "FitEllipsoid", &problem);
  c.hard_iron_uT = Eigen::Vector3d(h[0], h[1], h[2]);
  c.correction = MagEllipsoid::SymmetricFromUpper(a);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig_a(c.correction);
  if (!c.hard_iron_uT.allFinite() || !c.correction.allFinite() || !(eig_a.eigenvalues()(0) > 0.0)) {
    throw std::runtime_error("FitEllipsoid: the fit did not give a positive-definite correction: the samples cover "
                             "too little of the sphere (or too many are outliers)");
  }
  const double axis_ratio = eig_a.eigenvalues()(2) / eig_a.eigenvalues()(0);
  if (axis_ratio > kMaxCorrectionAxisRatio) {
    throw std::runtime_error("FitEllipsoid: implausible soft iron (the correction's axes differ by a factor " +
                             std::to_string(axis_ratio) + " > " + std::to_string(kMaxCorrectionAxisRatio) +
                             "): a patch of the sphere fitted by a distorted ellipsoid; cover more attitudes");
  }

  // 5. Residuals, robust weights and the M-estimator (sandwich) covariance of (h, A).
  RobustSandwich<9> sandwich(loss.get());
  double ss = 0.0;
  std::vector<double> after;
  after.reserve(samples.size());
  const double* parameters[] = {h, a, &B};
  for (std::size_t i = 0; i < samples.size(); ++i) {
    double r = 0.0;
    Eigen::Matrix<double, 1, 3, Eigen::RowMajor> jh;
    Eigen::Matrix<double, 1, 6, Eigen::RowMajor> ja;
    double* jacobians[] = {jh.data(), ja.data(), nullptr};
    problem.GetCostFunctionForResidualBlock(blocks[i])->Evaluate(parameters, &r, jacobians);
    Vector9d j;
    j << jh.transpose(), ja.transpose();
    sandwich.Add(j, r);
    ss += r * r;
    after.push_back(r + B);
  }
  const Matrix9d covariance = sandwich.Covariance("FitEllipsoid");
  const Vector9d sigma = covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  if (sigma.head<3>().maxCoeff() > kMaxHardIronSigmaFraction * c.field_uT) {
    throw std::runtime_error("FitEllipsoid: the hard iron is not determined by these samples (sigma " +
                             std::to_string(sigma.head<3>().maxCoeff()) + " uT > " +
                             std::to_string(kMaxHardIronSigmaFraction) + " of the field): cover more attitudes");
  }
  c.hard_iron_sigma_uT = sigma.head<3>();
  c.correction_sigma = sigma.tail<6>();
  c.residual_rms_uT = std::sqrt(ss / n);
  c.field_spread_before_uT = FieldMagnitudeSpread_uT(samples);
  c.field_spread_after_uT = MeanStd(after).second;
  c.samples = n;
  c.downweighted = sandwich.downweighted();
  c.method = "ellipsoid";
  return c;
}

// ------------------------------------------------------------------------ recursive ellipsoid

RecursiveEllipsoidFit::RecursiveEllipsoidFit(double field_uT) : field_uT_(field_uT) {
  if (!std::isfinite(field_uT)) throw std::invalid_argument("RecursiveEllipsoidFit: field_uT must be finite");
  P_ = kRecursiveP0 * Eigen::Matrix<double, 9, 9>::Identity();
  theta_.setZero();
}

// Recursive least squares on phi(x)^T theta = 1, x = m / s (s = field_uT if given, else
// 50 uT), theta_0 = 0, P_0 = kRecursiveP0 I:
//   k = P phi / (1 + phi^T P phi),  theta += k (1 - phi^T theta),  P -= k phi^T P.
// Then P^-1 = I / P_0 + sum phi phi^T and P^-1 theta = sum phi exactly, which Current() uses
// to recover the sample moments (sum x, sum x x^T) for its coverage check.
void RecursiveEllipsoidFit::Add(const Eigen::Vector3d& m_uT) {
  if (!m_uT.allFinite()) throw std::invalid_argument("RecursiveEllipsoidFit::Add: sample is not finite (NaN or inf)");
  const double scale_uT = field_uT_ > 0.0 ? field_uT_ : kRecursiveScale_uT;
  const Vector9d phi = QuadricRegressor(m_uT / scale_uT);
  const Vector9d P_phi = P_ * phi;
  const Vector9d k = P_phi / (1.0 + phi.dot(P_phi));
  theta_ += k * (1.0 - phi.dot(theta_));
  P_ -= k * P_phi.transpose();
  P_ = 0.5 * (P_ + P_.transpose()).eval();
  ++count_;
}

MagCalibration RecursiveEllipsoidFit::Current() const {
  if (count_ < 9) {
    throw std::runtime_error("RecursiveEllipsoidFit: too few samples: " + std::to_string(count_) +
                             " (need at least 9 for 9 unknowns)");
  }
  const double scale_uT = field_uT_ > 0.0 ? field_uT_ : kRecursiveScale_uT;
  // Sample moments from the information form (see Add): g = P^-1 theta = sum phi.
  const Eigen::LDLT<Matrix9d> ldlt(P_);
  const Vector9d g = ldlt.solve(theta_);
  const double n = count_;
  const Eigen::Vector3d mean = g.tail<3>() / (2.0 * n);
  Eigen::Matrix3d second;
  second << g(0), g(3) / 2.0, g(4) / 2.0, g(3) / 2.0, g(1), g(5) / 2.0, g(4) / 2.0, g(5) / 2.0, g(2);
  const Eigen::Matrix3d cov = second / n - mean * mean.transpose();
  const Spread spread = SpreadOfCovariance(cov);
  const double min_coverage = EllipsoidFitOptions{}.min_coverage;
  if (spread.ratio < min_coverage) ThrowPlanar("RecursiveEllipsoidFit", spread, min_coverage);
  MagCalibration c;
  std::string why;
  if (!EllipsoidFromQuadric(theta_, Eigen::Vector3d::Zero(), scale_uT, field_uT_, &c, &why)) {
    throw std::runtime_error("RecursiveEllipsoidFit: " + why + " after " + std::to_string(count_) +
                             " samples; the samples cover too little of the sphere or are too noisy");
  }
  c.hard_iron_sigma_uT.setConstant(std::numeric_limits<double>::quiet_NaN());  // not estimated
  c.correction_sigma.setConstant(std::numeric_limits<double>::quiet_NaN());
  c.samples = count_;
  c.method = "recursive";
  return c;
}

MagCalibration FitRecursive(const std::vector<MagSample>& samples, double field_uT, std::size_t block,
                            const std::function<void(const RecursiveMagStep&)>& on_step) {
  if (samples.empty()) throw std::runtime_error("FitRecursive: no samples");
  RecursiveEllipsoidFit fit(field_uT);
  RecursiveMagStep step;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    fit.Add(samples[i].m_b_uT);
    if ((i + 1) % std::max<std::size_t>(block, 1) != 0 && i + 1 != samples.size()) continue;
    step = RecursiveMagStep{i + 1, samples[i].t_s, std::nullopt, ""};
    try {
      step.estimate = fit.Current();
    } catch (const std::runtime_error& e) {
      step.why_not = e.what();
    }
    if (on_step) on_step(step);
  }
  if (!step.estimate) throw std::runtime_error(step.why_not);
  MagCalibration c = *step.estimate;
  std::vector<double> before, after;
  double ss = 0.0;
  for (const MagSample& s : samples) {
    const FieldMagnitude f = FieldMagnitudeOf(c, s.m_b_uT);
    before.push_back(f.before_uT);
    after.push_back(f.after_uT);
    ss += (f.after_uT - c.field_uT) * (f.after_uT - c.field_uT);
  }
  c.residual_rms_uT = std::sqrt(ss / static_cast<double>(samples.size()));
  c.field_spread_before_uT = MeanStd(before).second;
  c.field_spread_after_uT = MeanStd(after).second;
  return c;
}

void WriteMagConvergenceCsv(std::ostream& out, const std::vector<RecursiveMagStep>& steps) {
  out << "samples,t_s,hard_iron_x_uT,hard_iron_y_uT,hard_iron_z_uT,field_uT\n";
  for (const RecursiveMagStep& s : steps) {
    out << s.samples << "," << s.t_s;
    for (int i = 0; i < 3; ++i) out << "," << (s.estimate ? s.estimate->hard_iron_uT[i] : NAN);
    out << "," << (s.estimate ? s.estimate->field_uT : NAN) << "\n";
  }
}

// ------------------------------------------------------------------------ planar (3-axis, one plane)

// Data near one plane (a level turn of a 3-axis sensor, in whatever sensor plane):
// 1. plane: mean m_bar and scatter C of the samples; n = the eigenvector of C's smallest
//    eigenvalue (sign: n . m_bar >= 0, for a level turn the vertical field's direction),
//    in-plane basis U = [u, v] with u the largest eigenvector and v = n x u (u x v = n);
//    p_i = U^T (m_i - m_bar).
// 2. algebraic start in x = p / s (s = RMS in-plane distance): the conic
//    x^T M x + 2 w^T x = 1 by linear least squares, centre c = -M^-1 w, Q = M / (1 + c^T M c)
//    positive definite, A_unit = Q^(1/2) / s; the radius R = det(A_unit)^(-1/2) (geometric
//    mean of the semi-axes) and A2 = R A_unit, centre s c.
// 3. geometric least squares r_i = |A2 (p_i - c)| - R with R held (MagEllipsoid on (p, 0)
//    with h_z and A's third row/column held: the same residual in 2-D), robust loss.
// 4. checks: A2 positive definite; the directions A2 (p_i - c) cover >= min_coverage_rad;
//    the axis ratio of A2 <= kMaxCorrectionAxisRatio; sigma(c) <= kMaxHardIronSigmaFraction R.
// 5. lift to sensor axes: h = U (U^T m_bar + c) (no component along n),
//    A = U A2 U^T + n n^T (identity along n); sigmas propagated from the 5x5 sandwich
//    covariance (as FitEllipsoid's): Cov(h) = U Cov(c) U^T, Cov(A) = J Cov(A2) J^T.
MagCalibration FitPlanar(const std::vector<MagSample>& samples, const PlanarFitOptions& options) {
  if (options.loss != MagLoss::kNone && (!(options.loss_scale_uT > 0.0) || !std::isfinite(options.loss_scale_uT))) {
    throw std::invalid_argument("FitPlanar: loss_scale_uT must be positive and finite");
  }
  if (options.max_iterations < 1) throw std::invalid_argument("FitPlanar: max_iterations must be >= 1");
  if (!(options.min_coverage_rad > 0.0 && options.min_coverage_rad <= kTwoPi)) {
    throw std::invalid_argument("FitPlanar: min_coverage_rad must be in (0, 2 pi]");
  }
  if (!(options.max_out_of_plane > 0.0) || !std::isfinite(options.max_out_of_plane)) {
    throw std::invalid_argument("FitPlanar: max_out_of_plane must be positive and finite");
  }
  const int n = static_cast<int>(samples.size());
  if (n < kMinPlanarSamples) {
    throw std::invalid_argument("FitPlanar: too few samples: " + std::to_string(n) + " (need at least " +
                                std::to_string(kMinPlanarSamples) + " for 5 unknowns)");
  }
  CheckSamplesFinite(samples, "FitPlanar");

  // 1. The plane.
  const auto [mean, cov] = MeanCovariance(samples);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const double in_plane_var = eig.eigenvalues()(1) + eig.eigenvalues()(2);
  if (!(eig.eigenvalues()(1) > 0.0)) throw std::runtime_error("FitPlanar: the samples lie on a line or a point");
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  if (normal.dot(mean) < 0.0) normal = -normal;
  Eigen::Matrix<double, 3, 2> U;
  U.col(0) = eig.eigenvectors().col(2);
  U.col(1) = normal.cross(U.col(0));
  std::vector<Eigen::Vector2d> p(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) p[i] = U.transpose() * (samples[i].m_b_uT - mean);
  const double scale_uT = std::sqrt(in_plane_var);

  // 2. Algebraic conic.
  Eigen::Matrix<double, 5, 5> normal_eq = Eigen::Matrix<double, 5, 5>::Zero();
  Eigen::Matrix<double, 5, 1> rhs = Eigen::Matrix<double, 5, 1>::Zero();
  for (const Eigen::Vector2d& pi : p) {
    const Eigen::Vector2d x = pi / scale_uT;
    Eigen::Matrix<double, 5, 1> phi;
    phi << x.x() * x.x(), x.y() * x.y(), 2.0 * x.x() * x.y(), 2.0 * x.x(), 2.0 * x.y();
    normal_eq.selfadjointView<Eigen::Lower>().rankUpdate(phi);
    rhs += phi;
  }
  normal_eq = normal_eq.selfadjointView<Eigen::Lower>();
  const Eigen::Matrix<double, 5, 1> t = normal_eq.ldlt().solve(rhs);
  Eigen::Matrix2d M;
  M << t(0), t(2), t(2), t(1);
  const Eigen::Vector2d w = t.tail<2>();
  const double det_m = M.determinant();
  const Eigen::Vector2d centre_unit = det_m != 0.0 ? Eigen::Vector2d(-M.inverse() * w) : Eigen::Vector2d::Zero();
  const double k = 1.0 + centre_unit.dot(M * centre_unit);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig_q(M / k);
  if (!(det_m > 0.0) || !(k > 0.0) || !(eig_q.eigenvalues()(0) > 0.0) || !t.allFinite()) {
    throw std::runtime_error("FitPlanar: the in-plane readings do not lie on an ellipse: they cover too little of "
                             "the circle (turn through a full 360 deg in the plane)");
  }
  const Eigen::Matrix2d A_unit = eig_q.eigenvectors() * eig_q.eigenvalues().cwiseSqrt().asDiagonal() *
                                 eig_q.eigenvectors().transpose() / scale_uT;
  const double R = 1.0 / std::sqrt(A_unit.determinant());
  const double out_of_plane_rms_uT = std::sqrt(std::max(0.0, eig.eigenvalues()(0)));
  if (out_of_plane_rms_uT > options.max_out_of_plane * R) {
    std::ostringstream msg;
    msg.precision(3);
    msg << "FitPlanar: the samples are not near one plane (RMS " << out_of_plane_rms_uT << " uT off the plane > "
        << options.max_out_of_plane << " of the in-plane radius " << R
        << " uT): the sensor tilts too much for a planar calibration; use the ellipsoid fit";
    throw std::runtime_error(msg.str());
  }

  // 3. Geometric least squares on (p, 0) with the z parts held.
  double h[3] = {scale_uT * centre_unit.x(), scale_uT * centre_unit.y(), 0.0};
  const Eigen::Matrix2d A2_start = R * A_unit;
  double a[6] = {A2_start(0, 0), A2_start(0, 1), 0.0, A2_start(1, 1), 0.0, 1.0};
  double B = R;
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // loss is used after the solve
  ceres::Problem problem(problem_options);
  const std::unique_ptr<ceres::LossFunction> loss = MakeLoss(options.loss, options.loss_scale_uT);
  std::vector<ceres::ResidualBlockId> blocks;
  blocks.reserve(samples.size());
  for (const Eigen::Vector2d& pi : p) {
    blocks.push_back(problem.AddResidualBlock(MagEllipsoid::Create(Eigen::Vector3d(pi.x(), pi.y(), 0.0), 1.0),
                                              loss.get(), h, a, &B));
  }
  problem.SetManifold(h, new ceres::SubsetManifold(3, {2}));
  problem.SetManifold(a, new ceres::SubsetManifold(6, {2, 4, 5}));
  problem.SetParameterBlockConstant(&B);
  Solve(options.max_iterations, "FitPlanar", &problem);
  const Eigen::Vector2d centre(h[0], h[1]);
  Eigen::Matrix2d A2;
  A2 << a[0], a[1], a[1], a[3];
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig_a(A2);
  if (!centre.allFinite() || !A2.allFinite() || !(eig_a.eigenvalues()(0) > 0.0)) {
    throw std::runtime_error("FitPlanar: the fit did not give a positive-definite correction: the samples cover "
                             "too little of the circle (or too many are outliers)");
  }

  // 4. Coverage (first: an arc is the usual cause of an implausible ellipse) and plausibility.
  std::vector<double> angles;
  angles.reserve(p.size());
  for (const Eigen::Vector2d& pi : p) {
    const Eigen::Vector2d d = A2 * (pi - centre);
    angles.push_back(std::atan2(d.y(), d.x()));
  }
  const double coverage_deg = 360.0 - LargestGap(angles) * kRadToDeg;
  if (coverage_deg * kDegToRad < options.min_coverage_rad) {
    throw std::runtime_error("FitPlanar: the in-plane field directions cover only " + std::to_string(coverage_deg) +
                             " deg of the circle (need " + std::to_string(options.min_coverage_rad * kRadToDeg) +
                             "): turn through a full 360 deg in the plane");
  }

  const double axis_ratio = eig_a.eigenvalues()(1) / eig_a.eigenvalues()(0);
  if (axis_ratio > kMaxCorrectionAxisRatio) {
    throw std::runtime_error("FitPlanar: implausible soft iron (the in-plane correction's axes differ by a factor " +
                             std::to_string(axis_ratio) + " > " + std::to_string(kMaxCorrectionAxisRatio) +
                             "): an arc of the circle fitted by a distorted ellipse; turn through a full 360 deg");
  }

  // Sandwich covariance of (c, A2) as in FitEllipsoid: columns h0, h1, a0, a1, a3.
  using Vector5d = Eigen::Matrix<double, 5, 1>;
  using Matrix5d = Eigen::Matrix<double, 5, 5>;
  RobustSandwich<5> sandwich(loss.get());
  double ss = 0.0;
  std::vector<double> before, after;
  before.reserve(p.size());
  after.reserve(p.size());
  const double* parameters[] = {h, a, &B};
  const Eigen::Vector2d mean_in_plane = U.transpose() * mean;
  for (std::size_t i = 0; i < p.size(); ++i) {
    double r = 0.0;
    Eigen::Matrix<double, 1, 3, Eigen::RowMajor> jh;
    Eigen::Matrix<double, 1, 6, Eigen::RowMajor> ja;
    double* jacobians[] = {jh.data(), ja.data(), nullptr};
    problem.GetCostFunctionForResidualBlock(blocks[i])->Evaluate(parameters, &r, jacobians);
    Vector5d j;
    j << jh(0), jh(1), ja(0), ja(1), ja(3);
    sandwich.Add(j, r);
    ss += r * r;
    before.push_back((mean_in_plane + p[i]).norm());
    after.push_back(r + B);
  }
  const Matrix5d covariance = sandwich.Covariance("FitPlanar");
  const double centre_sigma = std::sqrt(std::max(covariance(0, 0), covariance(1, 1)));
  if (centre_sigma > kMaxHardIronSigmaFraction * R) {
    throw std::runtime_error("FitPlanar: the in-plane hard iron is not determined by these samples (sigma " +
                             std::to_string(centre_sigma) + " uT > " + std::to_string(kMaxHardIronSigmaFraction) +
                             " of the in-plane field)");
  }

  // 5. Lift to sensor axes.
  MagCalibration c;
  c.hard_iron_uT = U * (mean_in_plane + centre);
  c.correction = U * A2 * U.transpose() + normal * normal.transpose();
  c.field_uT = R;
  c.hard_iron_sigma_uT = (U * covariance.topLeftCorner<2, 2>() * U.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  // d(U A2 U^T)/d(a0, a1, a3) in the order A00 A01 A02 A11 A12 A22.
  const std::array<Eigen::Matrix3d, 3> dA = {U.col(0) * U.col(0).transpose(),
                                             U.col(0) * U.col(1).transpose() + U.col(1) * U.col(0).transpose(),
                                             U.col(1) * U.col(1).transpose()};
  Eigen::Matrix<double, 6, 3> J;
  for (int q = 0; q < 3; ++q) {
    J.col(q) << dA[q](0, 0), dA[q](0, 1), dA[q](0, 2), dA[q](1, 1), dA[q](1, 2), dA[q](2, 2);
  }
  c.correction_sigma =
      (J * covariance.bottomRightCorner<3, 3>() * J.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  c.uncalibrated_axis = normal;
  c.residual_rms_uT = std::sqrt(ss / n);
  c.field_spread_before_uT = MeanStd(before).second;
  c.field_spread_after_uT = MeanStd(after).second;
  c.samples = n;
  c.downweighted = sandwich.downweighted();
  c.method = "planar";
  c.coverage_deg = coverage_deg;
  c.out_of_plane_rms_uT = out_of_plane_rms_uT;
  return c;
}

// ------------------------------------------------------------------------ bidirectional (2-axis)

// Level turn of a 2-axis sensor (body x forward, y right), heading psi from magnetic north:
// the true horizontal field is H (cos psi, -sin psi). With hard iron and a 2x2 soft iron the
// readings are (up to a constant heading offset, the sensor's alignment, and noise)
//   x = hx + X cos t,   y = hy - Y sin(t + phi),   t = psi + const.
// Hard iron (the seed's bidirectional measurement): readings 180 deg apart average to the
// offset, taken at the extremes of each axis: hx = (x_max + x_min) / 2, X = (x_max - x_min) / 2
// (likewise y). Phase: at the x extremes (t = 0, pi), y - hy = -+Y sin phi, so
//   sin phi = (ybar(x min) - ybar(x max)) / (2 Y) / [(xbar(x max) - xbar(x min)) / (2 X)]
// with bars the means over the samples within kPhaseWindowRad of each extreme (the bracket
// corrects the window's mean cos t; the seed reads the headings of the x and y maxima, whose
// separation is 90 deg + phi). Correction (soft iron), from sin t = (-(y - hy) / Y - cos t sin phi) / cos phi:
//   [x_c]   [1       0              ] [x - hx]
//   [y_c] = [tan phi  (X / Y) / cos phi] [y - hy],   then |(x_c, y_c)| = X = field_uT (horizontal).
MagCalibration FitBidirectional(const std::vector<MagSample>& samples, const std::vector<Eigen::Vector2d>& roll_pitch_rad,
                                const BidirectionalOptions& options) {
  if (samples.size() != roll_pitch_rad.size()) {
    throw std::invalid_argument("FitBidirectional: " + std::to_string(samples.size()) + " samples but " +
                                std::to_string(roll_pitch_rad.size()) + " roll/pitch pairs");
  }
  if (!(options.max_tilt_rad > 0.0) || !std::isfinite(options.max_tilt_rad)) {
    throw std::invalid_argument("FitBidirectional: max_tilt_rad must be positive and finite");
  }
  CheckSamplesFinite(samples, "FitBidirectional");
  const double max_tilt_rad = options.max_tilt_rad;
  std::vector<Eigen::Vector2d> xy;
  std::vector<MagSample> used;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!roll_pitch_rad[i].allFinite()) {
      throw std::invalid_argument("FitBidirectional: roll/pitch of sample " + std::to_string(i) + " is not finite");
    }
    if (std::abs(roll_pitch_rad[i].x()) <= max_tilt_rad && std::abs(roll_pitch_rad[i].y()) <= max_tilt_rad) {
      xy.push_back(samples[i].m_b_uT.head<2>());
      used.push_back(samples[i]);
    }
  }
  if (static_cast<int>(xy.size()) < kMinBidirectionalSamples) {
    throw std::runtime_error("FitBidirectional: too few samples within the tilt limit of " +
                             std::to_string(options.max_tilt_rad * kRadToDeg) + " deg: " + std::to_string(xy.size()) + " of " +
                             std::to_string(samples.size()) + " (need at least " +
                             std::to_string(kMinBidirectionalSamples) + ")");
  }
  // The data's plane must be the sensor's x/y plane (a 2-axis sensor reads z = 0: normal z).
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(MeanCovariance(used).second);
  const Eigen::Vector3d normal = eig.eigenvectors().col(0);
  const double plane_tilt_rad = std::acos(std::min(1.0, std::abs(normal.z())));
  if (plane_tilt_rad > kMaxBidirectionalPlaneTiltRad) {
    throw std::runtime_error("FitBidirectional: the readings' plane is not the sensor's x/y plane (its normal " +
                             Vec(normal) + " is " + std::to_string(plane_tilt_rad * kRadToDeg) + " deg from z, limit " +
                             std::to_string(kMaxBidirectionalPlaneTiltRad * kRadToDeg) +
                             "): the turn is in another sensor plane; use --method planar (FitPlanar)");
  }
  Eigen::Vector2d lo = xy.front(), hi = xy.front();
  for (const Eigen::Vector2d& p : xy) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector2d offset = 0.5 * (hi + lo);
  const Eigen::Vector2d amplitude = 0.5 * (hi - lo);
  if (!(amplitude.minCoeff() > 0.0)) throw std::runtime_error("FitBidirectional: an axis reads a constant");
  const double y_over_x = amplitude.y() / amplitude.x();
  if (y_over_x > kMaxCorrectionAxisRatio || y_over_x < 1.0 / kMaxCorrectionAxisRatio) {
    throw std::runtime_error("FitBidirectional: implausible y/x scale " + std::to_string(y_over_x) +
                             " (soft iron within an axis ratio of " + std::to_string(kMaxCorrectionAxisRatio) +
                             " gives [" + std::to_string(1.0 / kMaxCorrectionAxisRatio) + ", " +
                             std::to_string(kMaxCorrectionAxisRatio) + "]): not a level turn in the x/y plane");
  }
  // Coverage: the angles of the normalised readings must leave no gap above kMaxHeadingGapRad.
  std::vector<double> angles;
  angles.reserve(xy.size());
  for (const Eigen::Vector2d& p : xy) {
    angles.push_back(std::atan2(-(p.y() - offset.y()) / amplitude.y(), (p.x() - offset.x()) / amplitude.x()));
  }
  const double gap = LargestGap(angles);
  if (gap > kMaxHeadingGapRad) {
    throw std::runtime_error("FitBidirectional: the turn does not cover both extremes of both axes (a heading gap of " +
                             std::to_string(gap / kDegToRad) + " deg; turn through a full 360 deg, level)");
  }
  // Phase from the samples near the x extremes.
  const double window = amplitude.x() * std::cos(kPhaseWindowRad);
  double x_max_sum = 0.0, y_max_sum = 0.0, x_min_sum = 0.0, y_min_sum = 0.0;
  int n_max = 0, n_min = 0;
  for (const Eigen::Vector2d& p : xy) {
    const Eigen::Vector2d d = p - offset;
    if (d.x() >= window) {
      x_max_sum += d.x();
      y_max_sum += d.y();
      ++n_max;
    } else if (d.x() <= -window) {
      x_min_sum += d.x();
      y_min_sum += d.y();
      ++n_min;
    }
  }
  if (n_max == 0 || n_min == 0) throw std::runtime_error("FitBidirectional: no samples near an x extreme");
  const double cos_t = (x_max_sum / n_max - x_min_sum / n_min) / (2.0 * amplitude.x());
  const double sin_phase = (y_min_sum / n_min - y_max_sum / n_max) / (2.0 * amplitude.y()) / cos_t;
  if (!(std::abs(sin_phase) <= kMaxBidirectionalSinPhase)) {
    throw std::runtime_error("FitBidirectional: implausible x/y phase (sin = " + std::to_string(sin_phase) +
                             ", |phase| > " + std::to_string(std::asin(kMaxBidirectionalSinPhase) * kRadToDeg) +
                             " deg, the most a soft-iron axis ratio of " + std::to_string(kMaxCorrectionAxisRatio) +
                             " gives): the axes are nearly parallel or the samples too noisy");
  }
  const double phase = std::asin(sin_phase);

  MagCalibration c;
  c.hard_iron_uT = Eigen::Vector3d(offset.x(), offset.y(), 0.0);
  c.correction.setIdentity();
  c.correction(1, 0) = std::tan(phase);
  c.correction(1, 1) = amplitude.x() / amplitude.y() / std::cos(phase);
  c.field_uT = amplitude.x();
  c.hard_iron_sigma_uT.setConstant(std::numeric_limits<double>::quiet_NaN());  // not estimated
  c.correction_sigma.setConstant(std::numeric_limits<double>::quiet_NaN());
  c.uncalibrated_axis = Eigen::Vector3d::UnitZ();
  c.coverage_deg = 360.0 - gap * kRadToDeg;
  std::vector<double> before, after;
  double ss = 0.0;
  for (const Eigen::Vector2d& p : xy) {
    before.push_back(p.norm());
    const double m = (c.correction.topLeftCorner<2, 2>() * (p - offset)).norm();
    after.push_back(m);
    ss += (m - c.field_uT) * (m - c.field_uT);
  }
  c.residual_rms_uT = std::sqrt(ss / static_cast<double>(xy.size()));
  c.field_spread_before_uT = MeanStd(before).second;
  c.field_spread_after_uT = MeanStd(after).second;
  c.samples = static_cast<int>(xy.size());
  c.method = "bidirectional";
  return c;
}

// ------------------------------------------------------------------------ heading

// Level the field with roll and pitch (R_n_b = Rz(yaw) Ry(pitch) Rx(roll), so
// m_l = Ry(pitch) Rx(roll) m_b = Rz(-yaw) m_n = (H cos yaw, -H sin yaw, V) for a magnetic-
// north azimuth yaw), then heading = atan2(-m_l,y, m_l,x) + D, wrapped to (-pi, pi].
double TiltCompensatedHeading(const Eigen::Vector3d& m_b_uT, double roll_rad, double pitch_rad,
                              double declination_rad) {
  const Eigen::Vector3d m_l = DcmFromEuler(roll_rad, pitch_rad, 0.0) * m_b_uT;
  return WrapPi(std::atan2(-m_l.y(), m_l.x()) + declination_rad);
}

double LevelHeading(const Eigen::Vector3d& m_b_uT, double declination_rad) {
  return WrapPi(std::atan2(-m_b_uT.y(), m_b_uT.x()) + declination_rad);
}

// A 2-axis sensor pitched by t (about body y; a tilt about any horizontal axis is the same
// up to the heading) at heading psi reads x = H cos psi cos t - V sin t, y = -H sin psi, so
// its heading is atan2(sin psi, cos psi cos t - k), k = tan I sin t. The error is largest
// near psi = +-90 deg (east/west), where it is ~atan(k) ~ t tan I; the exact maximum over psi
// (slightly above atan(k), by the cos t factor) is found on a 0.5 deg grid refined by golden
// section.
double TiltErrorBound(double tilt_rad, double inclination_rad) {
  if (!std::isfinite(tilt_rad) || !std::isfinite(inclination_rad)) {
    throw std::invalid_argument("TiltErrorBound: tilt_rad and inclination_rad must be finite");
  }
  const double c = std::cos(tilt_rad), k = std::tan(inclination_rad) * std::sin(tilt_rad);
  const auto error = [c, k](double psi) {
    return std::abs(WrapPi(std::atan2(std::sin(psi), std::cos(psi) * c - k) - psi));
  };
  const double step = 0.5 * kDegToRad;
  double best_psi = 0.0, best = 0.0;
  for (double psi = -M_PI; psi < M_PI; psi += step) {
    if (error(psi) > best) {
      best = error(psi);
      best_psi = psi;
    }
  }
  double lo = best_psi - step, hi = best_psi + step;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int i = 0; i < 60; ++i) {
    const double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
    if (error(a) > error(b)) {
      hi = b;
    } else {
      lo = a;
    }
  }
  return std::max(best, error(0.5 * (lo + hi)));
}

}  // namespace navtwin::calibration
