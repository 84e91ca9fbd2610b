#include "problems/inflight_alignment/distance_heading.h"

#include <algorithm>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/SVD>

#include "core/rotation.h"

namespace navtwin::inflight {
namespace {

bool AllFinite(std::initializer_list<double> values) {
  for (const double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

const char* TermName(int k) {
  static const char* const kNames[kSchulerTerms] = {"offset", "velocity", "tilt", "gyro"};
  return kNames[k];
}

}  // namespace

// ----------------------------------------------------------------- distance flown

Eigen::Vector2d NorthEastFromStart(const wgs84::Geodetic& start, const wgs84::Geodetic& p) {
  const double rm = wgs84::MeridianRadius(start.lat_rad) + start.h_m;
  const double rn = wgs84::PrimeVerticalRadius(start.lat_rad) + start.h_m;
  return Eigen::Vector2d((p.lat_rad - start.lat_rad) * rm,
                         WrapPi(p.lon_rad - start.lon_rad) * rn * std::cos(start.lat_rad));
}

void DistanceFlown::CheckTime(double t_s, Form form) const {
  if (form_ != Form::kNone && form_ != form) {
    throw std::logic_error("DistanceFlown: velocity and position forms cannot be mixed");
  }
  if (!std::isfinite(t_s)) throw std::invalid_argument("DistanceFlown: time is not finite");
  if (form_ != Form::kNone && t_s < t_s_) {
    std::ostringstream msg;
    msg << "DistanceFlown: time goes backwards (" << t_s << " s after " << t_s_ << " s)";
    throw std::invalid_argument(msg.str());
  }
}

void DistanceFlown::Add(double t_s, const Eigen::Vector3d& v_n_mps) {
  CheckTime(t_s, Form::kVelocity);
  if (!AllFinite({v_n_mps.x(), v_n_mps.y()})) {
    throw std::invalid_argument("DistanceFlown: velocity is not finite");
  }
  const Eigen::Vector2d v_ne = v_n_mps.head<2>();
  if (form_ == Form::kNone) {
    form_ = Form::kVelocity;
    t0_s_ = t_s;
  } else {
    ne_m_ += 0.5 * (last_v_ne_mps_ + v_ne) * (t_s - t_s_);
  }
  last_v_ne_mps_ = v_ne;
  t_s_ = t_s;
}

void DistanceFlown::AddPosition(double t_s, const wgs84::Geodetic& p) {
  CheckTime(t_s, Form::kPosition);
  if (!AllFinite({p.lat_rad, p.lon_rad, p.h_m})) {
    throw std::invalid_argument("DistanceFlown: position is not finite");
  }
  if (form_ == Form::kNone) {
    form_ = Form::kPosition;
    t0_s_ = t_s;
    start_ = p;
  }
  ne_m_ = NorthEastFromStart(start_, p);
  t_s_ = t_s;
}

// ----------------------------------------------------------------- equation 8

Eigen::Matrix<double, 1, 4> DistanceHeadingJacobian(double dn_m, double de_m, double err_n_m,
                                                    double err_e_m) {
  const double d2 = dn_m * dn_m + de_m * de_m;
  const double u = (dn_m * err_e_m - de_m * err_n_m) / d2;
  const double c = 1.0 / (1.0 + u * u) / d2;
  Eigen::Matrix<double, 1, 4> j;
  j << c * (err_e_m - 2.0 * u * dn_m), c * (-err_n_m - 2.0 * u * de_m), -c * de_m, c * dn_m;
  return j;
}

DistanceHeading HeadingErrorFromDistance(double dn_m, double de_m, double err_n_m, double err_e_m,
                                         const Eigen::Matrix2d& cov_err_ne_m2) {
  if (!AllFinite({dn_m, de_m, err_n_m, err_e_m}) || !cov_err_ne_m2.allFinite()) {
    throw std::invalid_argument("HeadingErrorFromDistance: an input is not finite");
  }
  const double distance_m = std::hypot(dn_m, de_m);
  if (!(distance_m > 0.0)) {
    throw std::invalid_argument("HeadingErrorFromDistance: the distance flown is zero");
  }
  if (cov_err_ne_m2(0, 0) < 0.0 || cov_err_ne_m2(1, 1) < 0.0 ||
      cov_err_ne_m2(0, 1) != cov_err_ne_m2(1, 0)) {
    throw std::invalid_argument(
        "HeadingErrorFromDistance: the covariance must be symmetric with non-negative variances");
  }
  const Eigen::RowVector2d j_err = DistanceHeadingJacobian(dn_m, de_m, err_n_m, err_e_m).tail<2>();
  DistanceHeading r;
  r.dh_rad = DistanceHeadingError(dn_m, de_m, err_n_m, err_e_m);
  r.sigma_rad = std::sqrt(std::max(0.0, (j_err * cov_err_ne_m2 * j_err.transpose())(0, 0)));
  r.distance_m = distance_m;
  return r;
}

// ----------------------------------------------------------------- Schuler separation

double SchulerRate(double lat_rad, double h_m) {
  const double r_m =
      std::sqrt(wgs84::MeridianRadius(lat_rad) * wgs84::PrimeVerticalRadius(lat_rad)) + h_m;
  return std::sqrt(wgs84::NormalGravity(lat_rad, h_m) / r_m);
}

std::array<double, kSchulerTerms> SchulerBasis(double t_s, double schuler_rate_radps) {
  const double w = schuler_rate_radps;
  const double x = w * t_s;
  const double half_sin = std::sin(0.5 * x);
  // x - sin x loses all its digits to cancellation for small x: series below x = 0.1
  // (the x^9 term is < 3e-15 of the sum there).
  double x_minus_sin;
  if (std::abs(x) < 0.1) {
    const double x2 = x * x;
    x_minus_sin = x * x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0)));
  } else {
    x_minus_sin = x - std::sin(x);
  }
  return {1.0, std::sin(x) / w, 2.0 * half_sin * half_sin / (w * w),  // 1 - cos x = 2 sin^2(x/2)
          x_minus_sin / (w * w * w)};
}

namespace {

// Unknowns: column 0 is dH, then (north, east) pairs of each used term. Rows 2i and
// 2i+1 are the north and east errors of sample i (m); then one pseudo-measurement row
// per prior, c = 0 with weight position_sigma / prior_sigma (so that every row is in
// metres with the data's sigma).
struct Design {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  Eigen::VectorXd scale;  // column norms (the solved unknowns are x_j * scale_j)
};

Design BuildDesign(const std::vector<DistanceErrorSample>& samples,
                   const std::array<bool, kSchulerTerms>& terms, const SeparationOptions& options) {
  // Prior sigma of term k on the north (axis 0) and east (axis 1) axis.
  const auto prior = [&options](int k, int axis) {
    return axis == 0 && options.prior_sigma_north[k] > 0.0 ? options.prior_sigma_north[k] : options.prior_sigma[k];
  };
  int cols = 1, prior_rows = 0;
  for (int k = 0; k < kSchulerTerms; ++k) {
    cols += terms[k] ? 2 : 0;
    for (int axis = 0; axis < 2; ++axis) prior_rows += terms[k] && prior(k, axis) > 0.0 ? 1 : 0;
  }
  const Eigen::Index data_rows = 2 * static_cast<Eigen::Index>(samples.size());
  Design d;
  d.a = Eigen::MatrixXd::Zero(data_rows + prior_rows, cols);
  d.b = Eigen::VectorXd::Zero(data_rows + prior_rows);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const DistanceErrorSample& s = samples[i];
    const Eigen::Index rn = 2 * static_cast<Eigen::Index>(i), re = rn + 1;
    d.a(rn, 0) = -s.de_m;
    d.a(re, 0) = s.dn_m;
    d.b(rn) = s.err_n_m;
    d.b(re) = s.err_e_m;
    const std::array<double, kSchulerTerms> basis = SchulerBasis(s.t_s, options.schuler_rate_radps);
    int c = 1;
    for (int k = 0; k < kSchulerTerms; ++k) {
      if (!terms[k]) continue;
      d.a(rn, c) = basis[k];
      d.a(re, c + 1) = basis[k];
      c += 2;
    }
  }
  Eigen::Index row = data_rows;
  int c = 1;
  for (int k = 0; k < kSchulerTerms; ++k) {
    if (!terms[k]) continue;
    for (int axis = 0; axis < 2; ++axis) {
      if (prior(k, axis) > 0.0) d.a(row++, c + axis) = options.position_sigma_m / prior(k, axis);
    }
    c += 2;
  }
  d.scale = d.a.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < d.scale.size(); ++j) {
    if (d.scale(j) > 0.0) d.a.col(j) /= d.scale(j);
  }
  return d;
}

double ConditionNumber(const Eigen::JacobiSVD<Eigen::MatrixXd>& svd) {
  const Eigen::VectorXd& s = svd.singularValues();
  return s(s.size() - 1) > 0.0 ? s(0) / s(s.size() - 1) : std::numeric_limits<double>::infinity();
}

void CheckSamples(const std::vector<DistanceErrorSample>& samples, const SeparationOptions& options) {
  for (const DistanceErrorSample& s : samples) {
    if (!AllFinite({s.t_s, s.dn_m, s.de_m, s.err_n_m, s.err_e_m})) {
      throw std::invalid_argument("SeparateHeadingError: a sample is not finite");
    }
  }
  if (!(options.schuler_rate_radps > 0.0) || !std::isfinite(options.schuler_rate_radps)) {
    throw std::invalid_argument("SeparateHeadingError: the Schuler rate must be positive");
  }
  std::array<double, 2 * kSchulerTerms> priors{};
  std::copy(options.prior_sigma.begin(), options.prior_sigma.end(), priors.begin());
  std::copy(options.prior_sigma_north.begin(), options.prior_sigma_north.end(), priors.begin() + kSchulerTerms);
  for (const double p : priors) {
    if (!std::isfinite(p) || p < 0.0) {
      throw std::invalid_argument("SeparateHeadingError: prior sigmas must be finite and >= 0");
    }
    if (p > 0.0 && !(options.position_sigma_m > 0.0)) {
      throw std::invalid_argument("SeparateHeadingError: priors need a given position sigma");
    }
  }
}

// The design actually solved: the requested terms, less those dropped for conditioning.
struct ConditionedFit {
  std::array<bool, kSchulerTerms> terms{};
  Design design;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd;
  std::string note;  // empty when nothing was dropped
};

ConditionedFit FitConditioned(const std::vector<DistanceErrorSample>& samples,
                              const SeparationOptions& options) {
  // Dropping order: the terms least separable from the heading go first.
  static constexpr std::array<SchulerTerm, kSchulerTerms> kDropOrder{
      {SchulerTerm::kVelocity, SchulerTerm::kOffset, SchulerTerm::kGyro, SchulerTerm::kTilt}};
  ConditionedFit f;
  f.terms = options.terms;
  f.design = BuildDesign(samples, f.terms, options);
  if (!(f.design.scale(0) > 0.0)) {
    throw std::invalid_argument("SeparateHeadingError: no distance flown (heading column is zero)");
  }
  f.svd.compute(f.design.a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const double first_condition = ConditionNumber(f.svd);
  std::string dropped;
  for (const SchulerTerm term : kDropOrder) {
    if (ConditionNumber(f.svd) <= options.max_condition) break;
    const int k = static_cast<int>(term);
    if (!f.terms[k]) continue;
    f.terms[k] = false;
    dropped += std::string(dropped.empty() ? "" : ", ") + TermName(k);
    f.design = BuildDesign(samples, f.terms, options);
    f.svd.compute(f.design.a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  }
  if (!dropped.empty()) {
    std::ostringstream note;
    note << "condition number " << first_condition << " above " << options.max_condition
         << ": the flight does not separate these Schuler terms from the heading; dropped "
         << dropped << " (held at zero, condition now " << ConditionNumber(f.svd) << ")";
    f.note = note.str();
  }
  return f;
}

}  // namespace

HeadingSeparation SeparateHeadingError(const std::vector<DistanceErrorSample>& samples,
                                       const SeparationOptions& options) {
  CheckSamples(samples, options);
  const ConditionedFit f = FitConditioned(samples, options);
  const Design& d = f.design;
  const Eigen::Index unknowns = d.a.cols();
  const Eigen::Index data_rows = 2 * static_cast<Eigen::Index>(samples.size());
  const bool sigma_given = options.position_sigma_m > 0.0;
  if (d.a.rows() < unknowns + (sigma_given ? 0 : 1)) {
    throw std::invalid_argument("SeparateHeadingError: too few samples for the unknowns");
  }
  const Eigen::VectorXd y = f.svd.solve(d.b);  // unknowns times column scale
  const double rss = (d.b - d.a * y).head(data_rows).squaredNorm();

  HeadingSeparation r;
  r.samples = static_cast<int>(samples.size());
  r.condition_number = ConditionNumber(f.svd);
  r.note = f.note;
  r.residual_rms_m = std::sqrt(rss / static_cast<double>(data_rows));
  r.position_sigma_m = sigma_given ? options.position_sigma_m
                                   : std::sqrt(rss / static_cast<double>(data_rows - unknowns));
  // cov(y) = s^2 (A^T A)^-1 = s^2 V S^-2 V^T; the unknowns are y / scale.
  const Eigen::MatrixXd vs = f.svd.matrixV() * f.svd.singularValues().cwiseInverse().asDiagonal();
  const Eigen::VectorXd var_y = vs.rowwise().squaredNorm() * (r.position_sigma_m * r.position_sigma_m);
  const Eigen::VectorXd x = y.cwiseQuotient(d.scale);
  const Eigen::VectorXd sigma_x = var_y.cwiseSqrt().cwiseQuotient(d.scale);
  r.dh_rad = x(0);
  r.sigma_rad = sigma_x(0);
  r.sigma_heading_only_rad = r.position_sigma_m / d.scale(0);
  r.schuler.used = f.terms;
  int c = 1;
  for (int k = 0; k < kSchulerTerms; ++k) {
    if (!f.terms[k]) continue;
    r.schuler.north[k] = x(c);
    r.schuler.east[k] = x(c + 1);
    r.schuler.north_sigma[k] = sigma_x(c);
    r.schuler.east_sigma[k] = sigma_x(c + 1);
    c += 2;
  }
  return r;
}

}  // namespace navtwin::inflight
