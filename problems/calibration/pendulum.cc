// Pendulum IMU calibration: swing fit, truth from the fitted swing, per-axis linear least
// squares with an honest covariance. The method and its equations are in pendulum.h and
// docs/calibration-pendulum.md.
#include "problems/calibration/pendulum.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Cholesky>

#include "core/earth.h"
#include "core/io/csv_series.h"
#include "core/io/input_error.h"
#include "core/io/open.h"
#include "core/io/text_reader.h"
#include "core/linalg.h"
#include "core/rotation.h"
#include "core/sim/calibration_rig.h"
#include "core/config/yaml_config.h"

namespace navtwin::calibration {
namespace {

// ------------------------------------------------------------ swing integration

/// RK4 step bound: at most 5 ms and 1/200 of the small-swing period. The global error,
/// ~(omega h)^4 per radian of phase, stays below 1e-8 rad over a 60 s record at 0.5 Hz
/// (TruthFromTheFittedSwingMatchesTheExactIncrements measures what it leaves).
constexpr double kMaxStep_s = 5e-3;
constexpr double kStepsPerPeriod = 200.0;
/// Fewer samples per period cannot resolve the swing (and its zero crossings).
constexpr double kMinSamplesPerPeriod = 10.0;
/// Zero crossings count when theta passes from beyond -h to beyond +h (or back), h this
/// fraction of the largest |theta|: encoder noise near zero cannot fake a crossing.
constexpr double kCrossingHysteresis = 0.05;

double StepFor(double c2_per_s2) {
  const double period_s = 2.0 * M_PI / std::sqrt(std::max(c2_per_s2, 1e-12));
  return std::min(kMaxStep_s, period_s / kStepsPerPeriod);
}

/// One RK4 step of theta'' = -c1 theta' - c2 sin(theta) over h.
template <typename T>
void SwingStep(const T& c1, const T& c2, double h, T* theta, T* rate) {
  using std::sin;
  const auto accel = [&](const T& th, const T& w) { return -c1 * w - c2 * sin(th); };
  const T k1t = *rate, k1w = accel(*theta, *rate);
  const T k2t = *rate + 0.5 * h * k1w, k2w = accel(*theta + 0.5 * h * k1t, k2t);
  const T k3t = *rate + 0.5 * h * k2w, k3w = accel(*theta + 0.5 * h * k2t, k3t);
  const T k4t = *rate + h * k3w, k4w = accel(*theta + h * k3t, k4t);
  *theta += h / 6.0 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t);
  *rate += h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
}

/// Number of equal steps of at most h_max covering dt (either sign).
int StepsFor(double dt_s, double h_max) {
  return std::max(1, static_cast<int>(std::ceil(std::fabs(dt_s) / h_max - 1e-9)));
}

/// Angle residuals of a swing (c1, c2, theta0, rate0 at t0) against the first n samples.
class SwingResidual {
 public:
  SwingResidual(const AngleRecord& angle, int n, double h_max) : angle_(angle), n_(n), h_max_(h_max) {}

  template <typename T>
  bool operator()(T const* const* p, T* residual) const {
    const T c1 = p[0][0], c2 = p[0][1];
    T theta = p[0][2], rate = p[0][3];
    double t = angle_.t_s.front();
    for (int i = 0; i < n_; ++i) {
      const double dt = angle_.t_s[i] - t;
      if (dt > 0.0) {
        const int m = StepsFor(dt, h_max_);
        for (int k = 0; k < m; ++k) SwingStep(c1, c2, dt / m, &theta, &rate);
      }
      t = angle_.t_s[i];
      residual[i] = theta - angle_.theta_rad[i];
    }
    return true;
  }

 private:
  const AngleRecord& angle_;
  int n_;
  double h_max_;
};

/// The starting point of the fit: period from the zero crossings (corrected for the
/// amplitude, T = T0 (1 + a^2/16 + 11 a^4/3072), and the damping, w_d^2 = w0^2 - c1^2/4),
/// c1 from the decay of the peaks, theta0 and rate0 from a quadratic through the first
/// samples.
struct SwingStart {
  std::array<double, 4> p{};  ///< c1, c2, theta0, rate0
  double period_s = 0.0;
};

SwingStart StartOfSwing(const AngleRecord& a) {
  const std::size_t n = a.t_s.size();
  double peak = 0.0;
  for (const double th : a.theta_rad) peak = std::max(peak, std::fabs(th));
  const double h = kCrossingHysteresis * peak;
  std::vector<double> crossings;
  int side = 0;  // sign of the last sample beyond +-h
  for (std::size_t i = 0; i < n; ++i) {
    const double th = a.theta_rad[i];
    const int s = th > h ? 1 : (th < -h ? -1 : 0);
    if (s == 0) continue;
    if (side != 0 && s != side) {
      // The last sign change before sample i: interpolate the crossing time.
      std::size_t j = i;
      while (j > 0 && (a.theta_rad[j - 1] > 0.0) == (s > 0)) --j;
      if (j == 0) j = 1;
      const double t0 = a.t_s[j - 1], t1 = a.t_s[j];
      const double y0 = a.theta_rad[j - 1], y1 = a.theta_rad[j];
      crossings.push_back(y1 != y0 ? t0 + (t1 - t0) * (-y0) / (y1 - y0) : t0);
    }
    side = s;
  }
  if (crossings.size() < 3) {
    throw std::runtime_error("angle record " + a.path + ": " + std::to_string(crossings.size()) +
                             " zero crossings of theta; at least 3 (one full swing period) are needed "
                             "to fit c1 and c2 -- record a longer swing");
  }
  SwingStart s;
  s.period_s = 2.0 * (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  const double span_s = a.t_s.back() - a.t_s.front();
  const double samples_per_period = static_cast<double>(n - 1) / span_s * s.period_s;
  if (samples_per_period < kMinSamplesPerPeriod) {
    throw std::runtime_error("angle record " + a.path + ": " + std::to_string(samples_per_period) +
                             " samples per swing period; at least 10 are needed to fit c1 and c2");
  }
  // Peaks between crossings: ln(amplitude) falls at c1 / 2.
  std::vector<double> tp, lp;
  double amplitude_sum = 0.0;
  for (std::size_t k = 0; k + 1 < crossings.size(); ++k) {
    double best = 0.0, t_best = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      if (a.t_s[i] > crossings[k] && a.t_s[i] < crossings[k + 1] && std::fabs(a.theta_rad[i]) > best) {
        best = std::fabs(a.theta_rad[i]);
        t_best = a.t_s[i];
      }
    }
    if (best > 0.0) {
      tp.push_back(t_best);
      lp.push_back(std::log(best));
      amplitude_sum += best;
    }
  }
  double c1 = 0.0;
  if (tp.size() >= 2) {
    const double mt = std::accumulate(tp.begin(), tp.end(), 0.0) / tp.size();
    const double ml = std::accumulate(lp.begin(), lp.end(), 0.0) / lp.size();
    double sxy = 0.0, sxx = 0.0;
    for (std::size_t k = 0; k < tp.size(); ++k) {
      sxy += (tp[k] - mt) * (lp[k] - ml);
      sxx += (tp[k] - mt) * (tp[k] - mt);
    }
    if (sxx > 0.0) c1 = std::max(0.0, -2.0 * sxy / sxx);
  }
  const double amp = tp.empty() ? peak : amplitude_sum / static_cast<double>(tp.size());
  const double w_d = 2.0 * M_PI / s.period_s;
  const double w0 = std::sqrt(w_d * w_d + 0.25 * c1 * c1) *
                    (1.0 + amp * amp / 16.0 + 11.0 * std::pow(amp, 4) / 3072.0);
  // theta0 and rate0: a least-squares quadratic through the samples of the first 1/20 period
  // (at least three).
  std::size_t m = 0;
  while (m < n && a.t_s[m] - a.t_s[0] <= s.period_s / 20.0) ++m;
  m = std::min(n, std::max<std::size_t>(m, 3));
  Eigen::MatrixXd A(m, 3);
  Eigen::VectorXd y(m);
  for (std::size_t i = 0; i < m; ++i) {
    const double dt = a.t_s[i] - a.t_s[0];
    A.row(i) << 1.0, dt, dt * dt;
    y(i) = a.theta_rad[i];
  }
  const Eigen::Vector3d q = LeastSquaresColPivQr(A, y);
  s.p = {c1, w0 * w0, q(0), q(1)};
  return s;
}

ceres::Solver::Options FitOptions() {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = 100;
  o.function_tolerance = 1e-12;
  o.gradient_tolerance = 1e-16;
  o.parameter_tolerance = 1e-12;
  o.logging_type = ceres::SILENT;
  return o;
}

// --------------------------------------------------------------- the truth

/// The swing and the running integrals of sin(theta), cos(theta) and theta'^2.
struct Augmented {
  double theta = 0.0, rate = 0.0, int_sin = 0.0, int_cos = 0.0, int_rate2 = 0.0;
};

Augmented operator+(const Augmented& a, const Augmented& b) {
  return {a.theta + b.theta, a.rate + b.rate, a.int_sin + b.int_sin, a.int_cos + b.int_cos,
          a.int_rate2 + b.int_rate2};
}
Augmented operator*(double s, const Augmented& a) {
  return {s * a.theta, s * a.rate, s * a.int_sin, s * a.int_cos, s * a.int_rate2};
}

/// Advances the augmented swing by dt (either sign) with RK4 steps of at most h_max.
void Advance(double c1, double c2, double dt, double h_max, Augmented* y) {
  const auto f = [c1, c2](const Augmented& s) {
    return Augmented{s.rate, -c1 * s.rate - c2 * std::sin(s.theta), std::sin(s.theta), std::cos(s.theta),
                     s.rate * s.rate};
  };
  const int m = StepsFor(dt, h_max);
  const double h = dt / m;
  for (int k = 0; k < m; ++k) {
    const Augmented k1 = f(*y);
    const Augmented k2 = f(*y + (0.5 * h) * k1);
    const Augmented k3 = f(*y + (0.5 * h) * k2);
    const Augmented k4 = f(*y + h * k3);
    *y = *y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
}

// ------------------------------------------------------------- least squares

constexpr int kParameters = 2 * kTriadParameters + kGSensitivityParameters;  // 33
constexpr int kGyroOffset = kTriadParameters;
constexpr int kGOffset = 2 * kTriadParameters;
/// A regressor whose weighted rms is below this is "not excited": 1 mg of specific force
/// (the Coriolis force along the pivot, ~2e-4 m/s^2, is below it), 0.06 deg/s of rate (ten
/// times the Earth rate: the Earth rate alone cannot separate a misalignment in minutes).
constexpr double kMinSpecificForce_mps2 = 1e-2;
constexpr double kMinRate_radps = 1e-3;
/// Normalised normal matrices with an eigenvalue below this fraction of the largest are
/// singular: the parameters in that direction are a combination of the others.
constexpr double kCollinear = 1e-10;

std::string ParameterName(int g) {
  if (g < kGyroOffset) return TriadParameterName("accel", g);
  if (g < kGOffset) return TriadParameterName("gyro", g - kGyroOffset);
  return GSensitivityParameterName(g - kGOffset);
}

using detail::AxisProblem;

/// What a regressor multiplies: the specific force, the rate or one (a bias).
enum class Column { kForce, kRate, kOne };

Column KindOf(const AxisProblem& axis, int i) {
  if (axis.regressors.row(i).head<3>().any()) return Column::kForce;
  if (axis.regressors.row(i).segment<3>(3).any()) return Column::kRate;
  return Column::kOne;
}

/// An interval's input: z = (f_b, omega_ib_b, 1), the true mean rates.
using Input = Eigen::Matrix<double, 7, 1>;

/// The model of core/imu_error_model.h over the 33-vector p: the measured mean rates of
/// accel x, y, z and gyro x, y, z for the input z (G applied only when with_g).
Eigen::Matrix<double, 6, 1> Measured(const Eigen::Matrix<double, kParameters, 1>& p, bool with_g, const Input& z) {
  const Eigen::Vector3d f = z.head<3>(), omega = z.segment<3>(3);
  Eigen::Matrix<double, 6, 1> m;
  m << MeasuredSpecificForce(p.data(), f), MeasuredRate(p.data() + kGyroOffset, with_g ? p.data() + kGOffset : nullptr, omega, f);
  return m;
}

/// Normal equations of one axis problem (all its columns) over one run.
/// At most 7 columns (gyro axis with g-sensitivity): fixed-capacity storage, no heap.
using Regressor = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 7, 1>;
using NormalMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 7, 7>;

struct Normal {
  NormalMatrix N;
  Regressor b;
  double yy = 0.0;
  double weight_s = 0.0;  ///< sum of dt
  long rows = 0;
};

/// A run prepared for the least squares: its samples within the angle record, the fitted
/// swing, the truth and the per-axis normal equations.
struct PreparedRun {
  std::vector<ImuSample> meas;
  SwingFit fit;
  PendulumGeometry geometry;
  std::vector<Normal> normals;  ///< per axis problem
};

/// Per axis problem, the normal equations of one run: rows x = regressors z sqrt(dt) and
/// y = (measured - true mean rate) sqrt(dt), white increment noise having variance ~ dt.
std::vector<Normal> RunNormals(const std::vector<AxisProblem>& axes, const std::vector<ImuSample>& meas,
                               const std::vector<ImuSample>& truth) {
  std::vector<Normal> out(axes.size());
  for (std::size_t a = 0; a < axes.size(); ++a) {
    const Eigen::Index columns = axes[a].regressors.rows();
    out[a].N = NormalMatrix::Zero(columns, columns);
    out[a].b = Regressor::Zero(columns);
  }
  const Eigen::Matrix<double, kParameters, 1> zero = Eigen::Matrix<double, kParameters, 1>::Zero();
  Input z;
  Regressor x;
  for (std::size_t k = 0; k < meas.size(); ++k) {
    const double dt = truth[k].dt_s, w = std::sqrt(dt);
    z << truth[k].dv_b_mps / dt, truth[k].dtheta_b_rad / dt, 1.0;
    const Eigen::Matrix<double, 6, 1> u = Measured(zero, true, z);  // the truth
    for (std::size_t a = 0; a < axes.size(); ++a) {
      const double measured = (a < 3 ? meas[k].dv_b_mps(a) : meas[k].dtheta_b_rad(a - 3)) / dt;
      const double y = (measured - u(a)) * w;
      x.noalias() = axes[a].regressors * z;
      x *= w;
      Normal& n = out[a];
      n.N.noalias() += x * x.transpose();
      n.b += x * y;
      n.yy += y * y;
      n.weight_s += dt;
      ++n.rows;
    }
  }
  return out;
}

/// Rows/columns `keep` of N and b.
Eigen::MatrixXd Sub(const NormalMatrix& N, const std::vector<int>& keep) {
  Eigen::MatrixXd S(keep.size(), keep.size());
  for (std::size_t i = 0; i < keep.size(); ++i)
    for (std::size_t j = 0; j < keep.size(); ++j) S(i, j) = N(keep[i], keep[j]);
  return S;
}
Eigen::VectorXd Sub(const Regressor& b, const std::vector<int>& keep) {
  Eigen::VectorXd s(keep.size());
  for (std::size_t i = 0; i < keep.size(); ++i) s(i) = b(keep[i]);
  return s;
}

/// Sum over runs of axis problem a's normal equations, with run `replace` (if >= 0) taken
/// from `replacement` instead.
/// One run's residual RMS per axis (over its samples, weighted by dt) before calibration and
/// at the solution p: the axis problems are accel x, y, z, gyro x, y, z.
CalibrationResidual RunResidual(const PreparedRun& run, const std::vector<AxisProblem>& axes, const Eigen::VectorXd& p,
                                int index) {
  CalibrationResidual out;
  out.rms = true;
  out.run = index;
  out.t0_s = run.meas.empty() ? 0.0 : run.meas.front().t_s;
  out.t1_s = run.meas.empty() ? 0.0 : run.meas.back().t_s;
  for (std::size_t a = 0; a < axes.size() && a < 6; ++a) {
    const Normal& n = run.normals[a];
    Eigen::VectorXd x = Eigen::VectorXd::Zero(axes[a].params.size());
    for (std::size_t j = 0; j < axes[a].params.size(); ++j) x(j) = p(axes[a].params[j]);
    const double w = n.weight_s > 0.0 ? n.weight_s : 1.0;
    const double before = std::sqrt(std::max(0.0, n.yy) / w);
    const double after = std::sqrt(std::max(0.0, n.yy - 2.0 * x.dot(n.b) + x.dot(n.N * x)) / w);
    (a < 3 ? out.accel_before_mps2 : out.gyro_before_radps)(a % 3) = before;
    (a < 3 ? out.accel_after_mps2 : out.gyro_after_radps)(a % 3) = after;
  }
  return out;
}

Normal Total(const std::vector<PreparedRun>& runs, std::size_t a, int replace = -1,
             const std::vector<Normal>* replacement = nullptr) {
  Normal t;
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const Normal& n = static_cast<int>(r) == replace ? (*replacement)[a] : runs[r].normals[a];
    if (r == 0) {
      t = n;
      continue;
    }
    t.N += n.N;
    t.b += n.b;
    t.yy += n.yy;
    t.weight_s += n.weight_s;
    t.rows += n.rows;
  }
  return t;
}

/// Decides which columns of one axis problem the runs can estimate; the others go to
/// `unobservable` with the reason.
std::vector<int> ObservableColumns(const AxisProblem& axis, const Normal& total, std::vector<std::string>* unobservable) {
  std::vector<int> keep;
  for (std::size_t j = 0; j < axis.params.size(); ++j) {
    const double rms = std::sqrt(total.N(j, j) / total.weight_s);
    const std::string name = ParameterName(axis.params[j]);
    const Column kind = KindOf(axis, static_cast<int>(j));
    if (kind == Column::kForce && rms < kMinSpecificForce_mps2) {
      unobservable->push_back(name + ": not excited (no run puts specific force along the axis it multiplies; "
                                     "rms " + std::to_string(rms) + " m/s^2)");
    } else if (kind == Column::kRate && rms < kMinRate_radps) {
      unobservable->push_back(name + ": not excited (no run turns about the axis it multiplies; rms " +
                              std::to_string(rms) + " rad/s, the Earth rate alone)");
    } else {
      keep.push_back(static_cast<int>(j));
    }
  }
  // Collinearity: the smallest eigenvalue of the normalised normal matrix.
  while (keep.size() > 1) {
    const Eigen::MatrixXd S = Sub(total.N, keep);
    const Eigen::VectorXd d = S.diagonal().cwiseSqrt().cwiseInverse();
    const SymmetricEigen eig = SymmetricEigenDecomposition(d.asDiagonal() * S * d.asDiagonal());
    if (eig.values(0) >= kCollinear * eig.values.maxCoeff()) break;
    const Eigen::VectorXd v = eig.vectors.col(0);
    Eigen::Index worst = 0;
    v.cwiseAbs().maxCoeff(&worst);
    std::string with;
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      if (i != worst && std::fabs(v(i)) > 0.1) with += (with.empty() ? "" : ", ") + ParameterName(axis.params[keep[i]]);
    }
    if (with.empty()) with = "the other parameters";
    unobservable->push_back(ParameterName(axis.params[keep[worst]]) + ": a combination of " + with +
                            " in these runs (add a mounting that moves another axis)");
    keep.erase(keep.begin() + worst);
  }
  return keep;
}

/// The solution of every axis problem over its kept columns, as a full 33-vector.
Eigen::VectorXd SolveAll(const std::vector<PreparedRun>& runs, const std::vector<AxisProblem>& axes,
                         const std::vector<std::vector<int>>& keep, int replace = -1,
                         const std::vector<Normal>* replacement = nullptr) {
  Eigen::VectorXd p = Eigen::VectorXd::Zero(kParameters);
  for (std::size_t a = 0; a < axes.size(); ++a) {
    if (keep[a].empty()) continue;
    const Normal t = Total(runs, a, replace, replacement);
    const Eigen::VectorXd x = Sub(t.N, keep[a]).ldlt().solve(Sub(t.b, keep[a]));
    for (std::size_t i = 0; i < keep[a].size(); ++i) p(axes[a].params[keep[a][i]]) = x(i);
  }
  return p;
}

/// Square root of a covariance (Cholesky, or the eigen form when only semidefinite).
Eigen::Matrix4d CovarianceRoot(const Eigen::Matrix4d& P) {
  const Eigen::LLT<Eigen::Matrix4d> llt(P);
  if (llt.info() == Eigen::Success) return llt.matrixL();
  const SymmetricEigen eig = SymmetricEigenDecomposition(P);
  return eig.vectors * eig.values.cwiseMax(0.0).cwiseSqrt().asDiagonal();
}

SwingFit Perturbed(const SwingFit& fit, const Eigen::Vector4d& d) {
  SwingFit f = fit;
  f.c1_per_s += d(0);
  f.c2_per_s2 += d(1);
  f.theta0_rad += d(2);
  f.rate0_radps += d(3);
  return f;
}

std::string Fixed(double v, int digits) {
  std::ostringstream s;
  s.precision(digits);
  s << v;
  return s.str();
}

}  // namespace

// ------------------------------------------------------------------ angle file

namespace detail {

std::vector<AxisProblem> AxisProblems(bool with_g) {
  // Column k < 6 of parameter j's map: the model at (e_j, unit input k) minus at (0, unit
  // input k), less its constant part (column 6: the model at (e_j, 0) minus at (0, 0)).
  const int parameters = with_g ? kParameters : kGOffset;
  const Eigen::Matrix<double, kParameters, 1> zero = Eigen::Matrix<double, kParameters, 1>::Zero();
  const Input none = Input::Zero();
  std::vector<AxisProblem> out(6);
  for (int j = 0; j < parameters; ++j) {
    const Eigen::Matrix<double, kParameters, 1> unit = Eigen::Matrix<double, kParameters, 1>::Unit(j);
    Eigen::Matrix<double, 6, 7> map;
    map.col(6) = Measured(unit, with_g, none) - Measured(zero, with_g, none);
    for (int k = 0; k < 6; ++k) {
      const Input e = Input::Unit(k);
      map.col(k) = Measured(unit, with_g, e) - Measured(zero, with_g, e) - map.col(6);
    }
    for (int a = 0; a < 6; ++a) {
      if (!map.row(a).any()) continue;
      AxisProblem& axis = out[a];
      axis.params.push_back(j);
      axis.regressors.conservativeResize(axis.regressors.rows() + 1, Eigen::NoChange);
      axis.regressors.bottomRows<1>() = map.row(a);
    }
  }
  return out;
}

}  // namespace detail

AngleRecord ReadAngleFile(const std::string& path) {
  ScalarSeries series = ReadScalarSeriesCsv(path, "theta", {{"_rad", 1.0}, {"_deg", kDegToRad}});
  AngleRecord out;
  out.t_s = std::move(series.t_s);
  out.theta_rad = std::move(series.value);
  out.path = path;
  return out;
}

// ------------------------------------------------------------------- swing fit

double SwingFit::c1_sigma() const { return std::sqrt(std::max(0.0, covariance(0, 0))); }
double SwingFit::c2_sigma() const { return std::sqrt(std::max(0.0, covariance(1, 1))); }

SwingFit FitSwing(const AngleRecord& angle) {
  if (angle.t_s.size() != angle.theta_rad.size()) {
    throw std::invalid_argument("FitSwing: times and angles differ in number");
  }
  const SwingStart start = StartOfSwing(angle);
  std::array<double, 4> p = start.p;
  const int n = static_cast<int>(angle.t_s.size());
  const double t0 = angle.t_s.front();
  // Grow the window from eight periods, doubling: a start whose period is off by a little
  // would slip whole cycles against a long record (the start's period is good to ~1e-3,
  // a phase error of ~0.05 rad over eight periods).
  double window_s = 8.0 * start.period_s;
  std::unique_ptr<ceres::Problem> problem;
  int used = 0;
  while (true) {
    used = static_cast<int>(std::upper_bound(angle.t_s.begin(), angle.t_s.end(), t0 + window_s) - angle.t_s.begin());
    const bool last = used >= n;
    if (last) used = n;
    auto* cost = new ceres::DynamicAutoDiffCostFunction<SwingResidual, 4>(
        new SwingResidual(angle, used, StepFor(p[1])));
    cost->AddParameterBlock(4);
    cost->SetNumResiduals(used);
    problem = std::make_unique<ceres::Problem>();
    problem->AddResidualBlock(cost, nullptr, p.data());
    ceres::Solver::Summary summary;
    ceres::Solve(FitOptions(), problem.get(), &summary);
    if (!summary.IsSolutionUsable() || !(p[1] > 0.0)) {
      throw std::runtime_error("angle record " + angle.path + ": the swing fit failed (" + summary.message + ")");
    }
    if (last) break;
    window_s *= 2.0;
  }
  SwingFit fit;
  fit.t0_s = t0;
  fit.c1_per_s = p[0];
  fit.c2_per_s2 = p[1];
  fit.theta0_rad = p[2];
  fit.rate0_radps = p[3];
  fit.samples = n;
  double cost = 0.0;
  problem->Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  const double ssr = 2.0 * cost;
  fit.residual_rms_rad = std::sqrt(ssr / n);
  ceres::Covariance::Options copt;
  copt.algorithm_type = ceres::DENSE_SVD;
  ceres::Covariance covariance(copt);
  const std::vector<std::pair<const double*, const double*>> blocks = {{p.data(), p.data()}};
  if (n <= 4 || !covariance.Compute(blocks, problem.get())) {
    throw std::runtime_error("angle record " + angle.path +
                             ": the swing does not determine c1, c2, theta0 and rate0 (singular fit)");
  }
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> C;
  covariance.GetCovarianceBlock(p.data(), p.data(), C.data());
  fit.covariance = C * (ssr / (n - 4));
  return fit;
}

std::vector<SwingPoint> EvaluateSwing(const SwingFit& fit, const std::vector<double>& t_s) {
  std::vector<SwingPoint> out;
  out.reserve(t_s.size());
  const double h_max = StepFor(fit.c2_per_s2);
  double theta = fit.theta0_rad, rate = fit.rate0_radps, t = fit.t0_s;
  for (const double target : t_s) {
    const double dt = target - t;
    if (dt != 0.0) {
      const int m = StepsFor(dt, h_max);
      for (int k = 0; k < m; ++k) SwingStep(fit.c1_per_s, fit.c2_per_s2, dt / m, &theta, &rate);
    }
    t = target;
    out.push_back({theta, rate, -fit.c1_per_s * rate - fit.c2_per_s2 * std::sin(theta)});
  }
  return out;
}

// ------------------------------------------------------------------ the truth

std::vector<ImuSample> TrueIncrements(const SwingFit& fit, const PendulumGeometry& g,
                                      const std::vector<ImuSample>& intervals) {
  const double h_max = StepFor(fit.c2_per_s2);
  const double L = g.length_m;
  const double gravity = wgs84::NormalGravity(g.latitude_rad, g.height_m);
  const Eigen::Vector3d w_ie = wgs84::EarthRateNed(g.latitude_rad);
  const double rm_h = wgs84::MeridianRadius(g.latitude_rad) + g.height_m;
  const Eigen::Matrix3d R_b_p = g.mounting_p_b.transpose();
  Augmented y{fit.theta0_rad, fit.rate0_radps, 0.0, 0.0, 0.0};
  double t = fit.t0_s;
  const auto advance_to = [&](double target) {
    if (target != t) Advance(fit.c1_per_s, fit.c2_per_s2, target - t, h_max, &y);
    t = target;
  };
  std::vector<ImuSample> out;
  out.reserve(intervals.size());
  for (const ImuSample& s : intervals) {
    advance_to(s.t_s - s.dt_s);
    const Augmented a = y;
    advance_to(s.t_s);
    const Augmented& b = y;
    const double d_theta = b.theta - a.theta, d_rate = b.rate - a.rate;
    const double d_sin = std::sin(b.theta) - std::sin(a.theta), d_cos = std::cos(b.theta) - std::cos(a.theta);
    const double i_sin = b.int_sin - a.int_sin, i_cos = b.int_cos - a.int_cos, i_rate2 = b.int_rate2 - a.int_rate2;
    // Bob frame p: the pivot rotation, the Earth rate Ry(theta)^T omega_ie_n and the
    // transport rate (0, -v_N / (R_M + h), 0) with v_N = L theta' cos(theta).
    const Eigen::Vector3d dtheta_p(w_ie.x() * i_cos - w_ie.z() * i_sin, d_theta - L * d_sin / rm_h,
                                   w_ie.x() * i_sin + w_ie.z() * i_cos);
    // Tangential and centripetal acceleration minus gravity, and the Coriolis term
    // 2 (Ry^T omega_ie_n) x (L theta' e_x) along the pivot. The omega_en x v term
    // (L^2 theta'^2 cos / R, < 1e-6 m/s^2) is left out.
    const Eigen::Vector3d dv_p(L * d_rate + gravity * i_sin, 2.0 * L * (-w_ie.x() * d_cos + w_ie.z() * d_sin),
                               -L * i_rate2 - gravity * i_cos);
    ImuSample o;
    o.t_s = s.t_s;
    o.dt_s = s.dt_s;
    o.dtheta_b_rad = R_b_p * dtheta_p;
    o.dv_b_mps = R_b_p * dv_p;
    out.push_back(o);
  }
  return out;
}

// --------------------------------------------------------------- calibration

ImuCalibrationResult CalibratePendulum(const PendulumData& data, const PendulumOptions& options,
                                       std::vector<SwingFit>* fits) {
  if (data.runs.empty()) {
    throw std::runtime_error(
        "pendulum calibration: no run; the record needs at least one run (the seed uses the "
        "mountings NED, DNE, EDN and one rotated about two axes)");
  }
  const std::vector<AxisProblem> axes = detail::AxisProblems(options.estimate_g_sensitivity);
  std::vector<PreparedRun> runs;
  ImuCalibrationResult result;
  for (std::size_t r = 0; r < data.runs.size(); ++r) {
    const PendulumRun& in = data.runs[r];
    const std::string label = "run " + std::to_string(r + 1) + " (" + in.imu_path + ")";
    if (!(in.length_m > 0.0)) throw std::runtime_error("pendulum calibration: " + label + ": length_m must be > 0");
    PreparedRun run;
    run.fit = FitSwing(in.angle);
    run.geometry = {in.length_m, in.mounting_p_b, data.latitude_rad, data.height_m};
    const double t_first = in.angle.t_s.front(), t_last = in.angle.t_s.back();
    for (const ImuSample& s : in.imu) {
      if (s.dt_s > 0.0 && s.t_s - s.dt_s >= t_first && s.t_s <= t_last) run.meas.push_back(s);
    }
    if (run.meas.empty()) {
      throw std::runtime_error("pendulum calibration: " + label + ": no IMU sample within the angle record [" +
                               Fixed(t_first, 10) + ", " + Fixed(t_last, 10) + "] s of " + in.angle.path +
                               " (are the two on the same time scale?)");
    }
    run.normals = RunNormals(axes, run.meas, TrueIncrements(run.fit, run.geometry, run.meas));
    result.notes.push_back(label + ": c1 = " + Fixed(run.fit.c1_per_s, 6) + " +- " + Fixed(run.fit.c1_sigma(), 2) +
                           " 1/s, c2 = " + Fixed(run.fit.c2_per_s2, 8) + " +- " + Fixed(run.fit.c2_sigma(), 2) +
                           " 1/s^2, angle residual rms " + Fixed(run.fit.residual_rms_rad * kRadToDeg, 3) +
                           " deg, " + std::to_string(run.meas.size()) + " IMU samples");
    if (fits != nullptr) fits->push_back(run.fit);
    runs.push_back(std::move(run));
  }

  // Observability, the solution and the per-axis covariance s^2 (A^T A)^-1.
  std::vector<std::vector<int>> keep(axes.size());
  std::vector<int> position(kParameters, -1);  // global index -> position in `estimated`
  for (std::size_t a = 0; a < axes.size(); ++a) {
    const Normal t = Total(runs, a);
    keep[a] = ObservableColumns(axes[a], t, &result.unobservable);
    if (t.rows <= static_cast<long>(keep[a].size())) {
      throw std::runtime_error("pendulum calibration: " + std::to_string(t.rows) + " IMU samples for " +
                               std::to_string(keep[a].size()) + " parameters of an axis; record longer runs");
    }
    for (const int j : keep[a]) position[axes[a].params[j]] = 0;
  }
  for (int g = 0; g < kParameters; ++g) {
    if (position[g] < 0) continue;
    position[g] = static_cast<int>(result.estimated.size());
    result.estimated.push_back(ParameterName(g));
  }
  const int n_est = static_cast<int>(result.estimated.size());
  const Eigen::VectorXd p = SolveAll(runs, axes, keep);
  result.covariance = Eigen::MatrixXd::Zero(n_est, n_est);
  double accel_ss = 0.0, gyro_ss = 0.0, accel_w = 0.0, gyro_w = 0.0;
  for (std::size_t a = 0; a < axes.size(); ++a) {
    const Normal t = Total(runs, a);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(axes[a].params.size());
    for (std::size_t j = 0; j < axes[a].params.size(); ++j) x(j) = p(axes[a].params[j]);
    const double ssr = std::max(0.0, t.yy - 2.0 * x.dot(t.b) + x.dot(t.N * x));
    (a < 3 ? accel_ss : gyro_ss) += ssr;
    (a < 3 ? accel_w : gyro_w) += t.weight_s;
    if (keep[a].empty()) continue;
    const double s2 = ssr / static_cast<double>(t.rows - static_cast<long>(keep[a].size()));
    const Eigen::MatrixXd C = s2 * Sub(t.N, keep[a]).ldlt().solve(Eigen::MatrixXd::Identity(keep[a].size(), keep[a].size()));
    for (std::size_t i = 0; i < keep[a].size(); ++i) {
      for (std::size_t j = 0; j < keep[a].size(); ++j) {
        result.covariance(position[axes[a].params[keep[a][i]]], position[axes[a].params[keep[a][j]]]) = C(i, j);
      }
    }
  }
  result.accel_residual_rms_mps2 = std::sqrt(accel_ss / accel_w);
  result.gyro_residual_rms_rad_per_s = std::sqrt(gyro_ss / gyro_w);
  for (std::size_t r = 0; r < runs.size(); ++r) result.residuals.push_back(RunResidual(runs[r], axes, p, static_cast<int>(r)));

  // The swing fits' uncertainty through the solution: central differences along the
  // columns of each fit's covariance root (exact for a solution linear in the swing).
  if (options.propagate_swing_uncertainty) {
    for (std::size_t r = 0; r < runs.size(); ++r) {
      const Eigen::Matrix4d root = CovarianceRoot(runs[r].fit.covariance);
      for (int j = 0; j < 4; ++j) {
        Eigen::VectorXd dp[2];
        for (int sign = 0; sign < 2; ++sign) {
          const SwingFit f = Perturbed(runs[r].fit, (sign == 0 ? 1.0 : -1.0) * root.col(j));
          const std::vector<Normal> normals =
              RunNormals(axes, runs[r].meas, TrueIncrements(f, runs[r].geometry, runs[r].meas));
          dp[sign] = SolveAll(runs, axes, keep, static_cast<int>(r), &normals);
        }
        const Eigen::VectorXd d_all = 0.5 * (dp[0] - dp[1]);
        Eigen::VectorXd d(n_est);
        for (int g = 0; g < kParameters; ++g) {
          if (position[g] >= 0) d(position[g]) = d_all(g);
        }
        result.covariance += d * d.transpose();
      }
    }
    result.notes.push_back("sigma includes the swing fits' uncertainty");
  }

  // The calibration blocks; sigma NaN where not estimated.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ImuCalibration& c = result.calibration;
  c.accel = p.segment<kTriadParameters>(0);
  c.gyro = p.segment<kTriadParameters>(kGyroOffset);
  c.g_sensitivity = p.segment<kGSensitivityParameters>(kGOffset);
  Eigen::VectorXd sigma = Eigen::VectorXd::Constant(kParameters, nan);
  for (int g = 0; g < kParameters; ++g) {
    if (position[g] >= 0) sigma(g) = std::sqrt(std::max(0.0, result.covariance(position[g], position[g])));
  }
  c.accel_sigma = sigma.segment<kTriadParameters>(0);
  c.gyro_sigma = sigma.segment<kTriadParameters>(kGyroOffset);
  c.g_sensitivity_sigma = sigma.segment<kGSensitivityParameters>(kGOffset);
  result.positions = static_cast<int>(runs.size());
  return result;
}

// -------------------------------------------------------------------- record

PendulumData ReadPendulumRecord(const std::string& record_path) {
  const ConfigNode root = LoadYamlFile(record_path);
  root.RequireKeys({"latitude_deg", "height_m", "runs"});
  PendulumData data;
  if (!root.Has("latitude_deg")) root.Fail("latitude_deg", "required (the Earth rate in the truth depends on it)");
  data.latitude_rad = root.Double("latitude_deg", 0.0, -90.0, 90.0) * kDegToRad;
  data.height_m = root.Double("height_m", 0.0, -1e4, 1e5);
  if (!root.Has("runs")) root.Fail("runs", "required: a list of {imu, angle, length_m, mounting}");
  const std::filesystem::path base = std::filesystem::path(record_path).parent_path();
  const auto resolve = [&base](const std::string& p) {
    const std::filesystem::path f(p);
    return (f.is_absolute() || base.empty() ? f : base / f).string();
  };
  for (const ConfigNode& node : root.Elements("runs")) {
    node.RequireKeys({"imu", "angle", "length_m", "mounting", "mounting_deg"});
    for (const char* key : {"imu", "angle", "length_m"}) {
      if (!node.Has(key)) node.Fail(key, "required");
    }
    if (!node.Has("mounting") && !node.Has("mounting_deg")) {
      node.Fail("mounting", "required: the IMU axes on the bob as letters (e.g. NED, DNE, EDN) or mounting_deg");
    }
    PendulumRun run;
    run.length_m = node.Double("length_m", 0.0, 0.0, 1e3);
    if (!(run.length_m > 0.0)) node.Fail("length_m", "must be > 0");
    run.mounting_p_b = sim::ParsePendulumMounting(node);
    run.imu_path = resolve(node.String("imu", ""));
    std::unique_ptr<ImuReader> imu = OpenImu(run.imu_path);
    run.imu = ReadAll(*imu);
    run.angle = ReadAngleFile(resolve(node.String("angle", "")));
    data.runs.push_back(std::move(run));
  }
  return data;
}

ImuCalibrationResult CalibratePendulumRecord(const std::string& record_path) {
  return CalibratePendulum(ReadPendulumRecord(record_path));
}

}  // namespace navtwin::calibration
