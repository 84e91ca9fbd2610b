// Temperature calibration: the methods of temperature.h. The equations are in
// docs/calibration-temperature.md; the comments below say what each step computes.
#include "problems/calibration/temperature.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include "core/io/csv_series.h"
#include "core/io/input_error.h"
#include "core/io/text_reader.h"
#include "core/linalg.h"
#include "core/sim/calibration_rig.h"
#include "core/config/yaml_config.h"

namespace navtwin::calibration {
namespace {

/// Highest polynomial order a record may ask for: a chamber gives a handful of set points,
/// and beyond a quartic the fit follows the noise of those few points.
constexpr int kMaxOrder = 4;
/// Record plausibility: IMU chambers run from about -55 to +125 degC.
constexpr double kMinRecordTemperatureDegC = -100.0;
constexpr double kMaxRecordTemperatureDegC = 200.0;
/// A pooled (temperature-independent) parameter whose chi-square exceeds its dof by more
/// than this many standard deviations of a chi-square (sqrt(2 dof)) is flagged in the notes:
/// the runs disagree beyond their sigma, i.e. the parameter seems to depend on temperature.
constexpr double kChiSquareFlagSigmas = 5.0;
/// Record bounds of segment_s: below 0.1 s a segment holds a handful of samples, above an
/// hour a warm-up has ended within one segment.
constexpr double kMinSegmentS = 0.1;
constexpr double kMaxSegmentS = 3600.0;

std::string Num(double v, int precision = 4) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

/// Indices of the triad parameters that depend on temperature: scale factors and biases.
bool IsTemperatureDependent(int triad_index) { return triad_index < 3 || triad_index >= 9; }

/// Temperature terms of the given order, all coefficients 0.
TemperatureTerms ZeroTerms(double reference_degC, int order) {
  TemperatureTerms terms;
  terms.reference_degC = reference_degC;
  const std::vector<Eigen::Vector3d> zero(static_cast<std::size_t>(order), Eigen::Vector3d::Zero());
  terms.gyro_bias_rad_per_s = terms.gyro_scale_factor = terms.accel_bias_mps2 = terms.accel_scale_factor = zero;
  return terms;
}

/// Stores coefficient k (1..order) of triad parameter `triad_index` (a scale factor 0..2 or
/// a bias 9..11, IsTemperatureDependent) in its place among the terms.
void SetTemperatureCoefficient(bool gyro, int triad_index, int k, double coefficient, TemperatureTerms* terms) {
  const bool scale = triad_index < 3;
  const int axis = scale ? triad_index : triad_index - 9;
  std::vector<Eigen::Vector3d>& column =
      gyro ? (scale ? terms->gyro_scale_factor : terms->gyro_bias_rad_per_s)
           : (scale ? terms->accel_scale_factor : terms->accel_bias_mps2);
  column[static_cast<std::size_t>(k - 1)](axis) = coefficient;
}

/// One sigma per parameter, NaN (not estimated) until set.
template <int N>
Eigen::Matrix<double, N, 1> NotEstimated() {
  return Eigen::Matrix<double, N, 1>::Constant(std::numeric_limits<double>::quiet_NaN());
}

/// Where a run's estimate of one parameter lives: its index in the run's covariance.
struct RunTerm {
  int run = 0;
  int index = 0;  ///< in runs[run].estimated / covariance
};

/// An output parameter as a linear combination sum_i weight_i * run_value(term_i).
struct LinearOutput {
  std::string name;
  double value = 0.0;
  std::vector<RunTerm> terms;
  std::vector<double> weights;
};

int FindIndex(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

/// The reason a run gives for a parameter it could not observe, or "" when it lists none.
std::string UnobservableReason(const ImuCalibrationResult& run, const std::string& name) {
  for (const std::string& u : run.unobservable) {
    if (u.compare(0, name.size(), name) == 0 && (u.size() == name.size() || u[name.size()] == ' ' ||
                                                 u[name.size()] == ':' || u[name.size()] == '(')) {
      return u;
    }
  }
  return "";
}

/// A parameter of the run's estimate: value and sigma by name, from its calibration blocks.
double RunValue(const ImuCalibrationResult& run, const std::string& triad, int index) {
  if (triad == "gyro") return run.calibration.gyro(index);
  if (triad == "accel") return run.calibration.accel(index);
  return run.calibration.g_sensitivity(index);
}

std::string RunLabel(const std::vector<double>& temperatures_degC, int r) {
  return "run " + std::to_string(r) + " (" + Num(temperatures_degC[r]) + " degC)";
}

}  // namespace

double TemperaturePolynomial::Evaluate(double temperature_degC) const {
  const double dT = temperature_degC - reference_degC;
  double v = 0.0;
  for (int k = order(); k >= 0; --k) v = v * dT + coefficients(k);
  return v;
}

void CheckTemperatureCoverage(const std::vector<double>& temperatures_degC, int order,
                              double min_span_per_order_degC, const std::string& what) {
  if (order < 0) throw std::runtime_error(what + ": the polynomial order must be >= 0, got " + std::to_string(order));
  for (double t : temperatures_degC) {
    if (!std::isfinite(t)) throw std::runtime_error(what + ": a temperature is not finite");
  }
  std::vector<double> sorted = temperatures_degC;
  std::sort(sorted.begin(), sorted.end());
  // Distinct set points: greedy clusters of width kDistinctTemperatureDegC.
  int distinct = 0;
  double last = -std::numeric_limits<double>::infinity();
  for (double t : sorted) {
    if (t - last >= kDistinctTemperatureDegC) {
      ++distinct;
      last = t;
    }
  }
  if (distinct < order + 1) {
    throw std::runtime_error(what + ": order " + std::to_string(order) + " needs at least " +
                             std::to_string(order + 1) + " temperatures, got " + std::to_string(distinct) +
                             " (temperatures closer than " + Num(kDistinctTemperatureDegC) + " degC count as one)");
  }
  const double span = sorted.back() - sorted.front();
  const double needed = min_span_per_order_degC * order;
  if (span < needed) {
    throw std::runtime_error(what + ": order " + std::to_string(order) + " needs a temperature span of at least " +
                             Num(needed) + " degC (" + Num(min_span_per_order_degC) + " degC per order), got " +
                             Num(span) + " degC (" + Num(sorted.front()) + " .. " + Num(sorted.back()) + " degC)");
  }
}

TemperaturePolynomial FitTemperaturePolynomial(const std::vector<TemperaturePoint>& points, int order,
                                               double reference_degC, double min_span_per_order_degC,
                                               const std::string& what) {
  std::vector<double> temperatures;
  for (const TemperaturePoint& p : points) {
    if (!std::isfinite(p.value)) throw std::runtime_error(what + ": a value is not finite");
    if (!std::isfinite(p.sigma) || p.sigma <= 0.0) {
      throw std::runtime_error(what + ": the sigma at " + Num(p.temperature_degC) +
                               " degC must be finite and > 0, got " + Num(p.sigma));
    }
    temperatures.push_back(p.temperature_degC);
  }
  CheckTemperatureCoverage(temperatures, order, min_span_per_order_degC, what);
  if (!std::isfinite(reference_degC)) throw std::runtime_error(what + ": the reference temperature is not finite");

  // Scaled abscissa x = dT / s (s = largest |dT|) keeps the Vandermonde columns near 1;
  // c_k = a_k / s^k undoes it.
  const int n = static_cast<int>(points.size());
  const int m = order + 1;
  double scale = 0.0;
  for (const TemperaturePoint& p : points) scale = std::max(scale, std::abs(p.temperature_degC - reference_degC));
  if (scale == 0.0) scale = 1.0;  // order 0 at the reference itself

  // Whitened design A_w = W^(1/2) A, y_w = W^(1/2) y, W = diag(1 / sigma^2).
  Eigen::MatrixXd A_w(n, m);
  Eigen::VectorXd y_w(n);
  Eigen::VectorXd inv_sigma(n);
  for (int i = 0; i < n; ++i) {
    const double x = (points[i].temperature_degC - reference_degC) / scale;
    inv_sigma(i) = 1.0 / points[i].sigma;
    double xk = 1.0;
    for (int k = 0; k < m; ++k, xk *= x) A_w(i, k) = xk * inv_sigma(i);
    y_w(i) = points[i].value * inv_sigma(i);
  }
  // Normal matrix N = A_w^T A_w via QR (A_w = Q R, N^-1 = R^-1 R^-T); the coverage check
  // guarantees full column rank.
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A_w);
  const Eigen::MatrixXd R = qr.matrixQR().topRows(m).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd R_inv = R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(m, m));
  const Eigen::MatrixXd N_inv = R_inv * R_inv.transpose();
  // Gain in scaled units: a = N^-1 A_w^T W^(1/2) y.
  const Eigen::MatrixXd gain_scaled = N_inv * A_w.transpose() * inv_sigma.asDiagonal();

  Eigen::VectorXd unscale(m);
  for (int k = 0; k < m; ++k) unscale(k) = std::pow(scale, -k);
  TemperaturePolynomial fit;
  fit.reference_degC = reference_degC;
  fit.gain = unscale.asDiagonal() * gain_scaled;
  Eigen::VectorXd values(n);
  for (int i = 0; i < n; ++i) values(i) = points[i].value;
  fit.coefficients = fit.gain * values;
  fit.covariance = unscale.asDiagonal() * N_inv * unscale.asDiagonal();
  fit.dof = n - m;
  for (int i = 0; i < n; ++i) {
    const double r = (points[i].value - fit.Evaluate(points[i].temperature_degC)) / points[i].sigma;
    fit.chi_square += r * r;
  }
  return fit;
}

TemperatureCalibration CalibrateTemperature(const std::vector<TemperatureRun>& runs,
                                            const TemperatureCalibrationOptions& options) {
  const std::string what = "temperature calibration";
  if (options.order < 1) {
    throw std::runtime_error(what + ": the polynomial order must be >= 1, got " + std::to_string(options.order));
  }
  TemperatureCalibration out;
  for (const TemperatureRun& run : runs) out.temperatures_degC.push_back(run.temperature_degC);
  // Fail before the expensive part when the set points cannot carry the order.
  CheckTemperatureCoverage(out.temperatures_degC, options.order, options.min_span_per_order_degC, what);
  double reference_degC = 0.0;
  if (options.reference_degC) {
    reference_degC = *options.reference_degC;
    if (!std::isfinite(reference_degC)) throw std::runtime_error(what + ": the reference temperature is not finite");
  } else {
    for (double t : out.temperatures_degC) reference_degC += t;
    reference_degC /= static_cast<double>(runs.size());
  }

  // 1. One multi-position calibration per run.
  for (std::size_t r = 0; r < runs.size(); ++r) {
    try {
      out.runs.push_back(CalibrateMultiPosition(runs[r].data, options.multiposition));
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(what + ": " + RunLabel(out.temperatures_degC, static_cast<int>(r)) + ": " + e.what());
    }
  }
  const int n_runs = static_cast<int>(runs.size());

  // 2./3. Fit every parameter over the runs; collect each output as a linear combination
  // of the runs' estimates for the covariance.
  std::vector<LinearOutput> outputs;
  ImuCalibrationResult& result = out.result;
  ImuCalibration& cal = result.calibration;
  Eigen::Matrix<double, kTriadParameters, 1> gyro_sigma = NotEstimated<kTriadParameters>();
  Eigen::Matrix<double, kTriadParameters, 1> accel_sigma = NotEstimated<kTriadParameters>();
  Eigen::Matrix<double, kGSensitivityParameters, 1> g_sigma = NotEstimated<kGSensitivityParameters>();
  TemperatureTerms terms = ZeroTerms(reference_degC, options.order);

  struct Parameter {
    std::string triad;  ///< "gyro", "accel" or "g_sensitivity"
    int index;
  };
  std::vector<Parameter> parameters;
  for (const char* triad : {"gyro", "accel"}) {
    for (int i = 0; i < kTriadParameters; ++i) parameters.push_back({triad, i});
  }
  for (int i = 0; i < kGSensitivityParameters; ++i) parameters.push_back({"g_sensitivity", i});

  for (const Parameter& p : parameters) {
    const bool is_g = p.triad == "g_sensitivity";
    const std::string name = is_g ? GSensitivityParameterName(p.index) : TriadParameterName(p.triad, p.index);
    // Which runs estimated it.
    std::vector<RunTerm> present;
    std::vector<int> missing;
    for (int r = 0; r < n_runs; ++r) {
      const int idx = FindIndex(out.runs[r].estimated, name);
      if (idx >= 0) {
        present.push_back({r, idx});
      } else {
        missing.push_back(r);
      }
    }
    const bool temperature_dependent = !is_g && IsTemperatureDependent(p.index);
    // Accelerometer scale factor and bias and gyro bias are what a chamber calibrates: every
    // run must give them. The gyro scale factor needs rate-table rotations, which a chamber
    // may not have: absent from every run it is reported unobservable, absent from some an
    // error (its polynomial would rest on a subset of the set points).
    const bool required = temperature_dependent && !(p.triad == "gyro" && p.index < 3);
    if (!missing.empty() && (required || (temperature_dependent && !present.empty()))) {
      const int r = missing.front();
      std::string reason = UnobservableReason(out.runs[r], name);
      if (reason.empty()) reason = "not estimated";
      throw std::runtime_error(what + ": " + name + " cannot be estimated in " + RunLabel(out.temperatures_degC, r) +
                               ": " + reason + "; every run needs the same observability (e.g. +1 g and -1 g on "
                               "every axis, rotations for the gyro scale factor)");
    }
    if (present.empty()) {
      std::string reason;
      for (int r = 0; r < n_runs && reason.empty(); ++r) reason = UnobservableReason(out.runs[r], name);
      if (!reason.empty()) result.unobservable.push_back(reason);
      continue;
    }

    std::vector<TemperaturePoint> points;
    for (const RunTerm& t : present) {
      const ImuCalibrationResult& run = out.runs[t.run];
      points.push_back({out.temperatures_degC[t.run], RunValue(run, p.triad, p.index),
                        std::sqrt(run.covariance(t.index, t.index))});
    }
    const int order = temperature_dependent ? options.order : 0;
    TemperatureParameterFit fit{name, FitTemperaturePolynomial(points, order, reference_degC,
                                                               options.min_span_per_order_degC, what + ": " + name)};
    for (int k = 0; k <= order; ++k) {
      LinearOutput o;
      o.name = k == 0 ? name : name + ".dT" + std::to_string(k);
      o.value = fit.fit.coefficients(k);
      o.terms = present;
      for (std::size_t j = 0; j < present.size(); ++j) o.weights.push_back(fit.fit.gain(k, static_cast<int>(j)));
      outputs.push_back(o);
    }
    const double c0 = fit.fit.coefficients(0);
    const double s0 = std::sqrt(fit.fit.covariance(0, 0));
    if (is_g) {
      cal.g_sensitivity(p.index) = c0;
      g_sigma(p.index) = s0;
    } else if (p.triad == "gyro") {
      cal.gyro(p.index) = c0;
      gyro_sigma(p.index) = s0;
    } else {
      cal.accel(p.index) = c0;
      accel_sigma(p.index) = s0;
    }
    if (temperature_dependent) {
      for (int k = 1; k <= order; ++k) {
        SetTemperatureCoefficient(p.triad == "gyro", p.index, k, fit.fit.coefficients(k), &terms);
      }
      if (fit.fit.dof > 0) {
        result.notes.push_back(name + ": order-" + std::to_string(order) + " fit chi-square " +
                               Num(fit.fit.chi_square) + " (dof " + std::to_string(fit.fit.dof) + ")");
      }
      out.fits.push_back(fit);
    } else {
      if (fit.fit.dof > 0 &&
          fit.fit.chi_square > fit.fit.dof + kChiSquareFlagSigmas * std::sqrt(2.0 * fit.fit.dof)) {
        result.notes.push_back(name + ": the runs disagree beyond their sigma (chi-square " +
                               Num(fit.fit.chi_square) + ", dof " + std::to_string(fit.fit.dof) +
                               "): it seems to depend on temperature; the weighted mean is used");
      }
      out.pooled.push_back(fit);
    }
  }
  cal.gyro_sigma = gyro_sigma;
  cal.accel_sigma = accel_sigma;
  cal.g_sensitivity_sigma = g_sigma;
  cal.temperature = terms;

  // Covariance: runs are independent, so cov(o1, o2) = sum over terms of the same run of
  // w1 w2 cov_run(i1, i2).
  const int n_out = static_cast<int>(outputs.size());
  result.covariance = Eigen::MatrixXd::Zero(n_out, n_out);
  for (int a = 0; a < n_out; ++a) {
    result.estimated.push_back(outputs[a].name);
    for (int b = a; b < n_out; ++b) {
      double c = 0.0;
      for (std::size_t i = 0; i < outputs[a].terms.size(); ++i) {
        for (std::size_t j = 0; j < outputs[b].terms.size(); ++j) {
          const RunTerm& ta = outputs[a].terms[i];
          const RunTerm& tb = outputs[b].terms[j];
          if (ta.run != tb.run) continue;
          c += outputs[a].weights[i] * outputs[b].weights[j] * out.runs[ta.run].covariance(ta.index, tb.index);
        }
      }
      result.covariance(a, b) = result.covariance(b, a) = c;
    }
  }

  // Residual RMS over all positions of all runs.
  double accel_ss = 0.0, gyro_ss = 0.0;
  for (int r = 0; r < n_runs; ++r) {
    const ImuCalibrationResult& run = out.runs[r];
    result.positions += run.positions;
    accel_ss += run.positions * run.accel_residual_rms_mps2 * run.accel_residual_rms_mps2;
    gyro_ss += run.positions * run.gyro_residual_rms_rad_per_s * run.gyro_residual_rms_rad_per_s;
    for (const std::string& note : run.notes) result.notes.push_back(RunLabel(out.temperatures_degC, r) + ": " + note);
  }
  if (result.positions > 0) {
    result.accel_residual_rms_mps2 = std::sqrt(accel_ss / result.positions);
    result.gyro_residual_rms_rad_per_s = std::sqrt(gyro_ss / result.positions);
  }
  for (int r = 0; r < n_runs; ++r) {
    for (StaticPosition p : out.runs[r].static_positions) {
      p.run = r;
      p.temperature_degC = out.temperatures_degC[r];
      result.static_positions.push_back(p);
    }
  }
  result.residuals = StaticResiduals(result.calibration, result.static_positions);
  std::string set_points;
  for (double t : out.temperatures_degC) set_points += (set_points.empty() ? "" : ", ") + Num(t);
  result.notes.insert(result.notes.begin(), std::to_string(n_runs) + " runs at " + set_points + " degC; order " +
                                                std::to_string(options.order) + " in dT = T - " +
                                                Num(reference_degC) + " degC");
  return out;
}

// ------------------------------------------------------------------------ warm-up

namespace {

/// A direction of the column-normalised normal matrix with a relative eigenvalue below
/// this cannot be separated (condition number 1e10), as in multiposition.cc.
constexpr double kWarmUpNullEigenvalueRatio = 1e-10;

/// One column of an axis's least squares: the parameter and the power of dT it carries.
struct Unknown {
  std::string name;
  int power = 0;  ///< k of dT^k in the column (0: none)
};

/// The weighted linear least squares of one sensor axis over all segments:
/// y = A x + e, var e_i = s0^2 / w_i, with A's dT^k columns in u = dT / scale.
struct AxisFit {
  std::string label;  ///< e.g. "accel x"
  std::vector<Unknown> unknowns;
  Eigen::MatrixXd A;
  Eigen::VectorXd y, w;
  Eigen::VectorXd x;           ///< in the parameters' own units (dT^k unscaled)
  Eigen::MatrixXd covariance;  ///< s0^2 N^-1, same units
  Eigen::VectorXd residual;
  double variance_factor = 1.0;
};

void SolveAxis(AxisFit* fit, double scale, const std::string& what) {
  const int m = static_cast<int>(fit->A.rows());
  const int p = static_cast<int>(fit->A.cols());
  if (m <= p) {
    throw std::runtime_error(what + ": " + fit->label + " has " + std::to_string(p) + " unknowns but only " +
                             std::to_string(m) + " segments; use longer holds, more positions or a shorter segment_s");
  }
  const Eigen::VectorXd sqrt_w = fit->w.cwiseSqrt();
  const Eigen::MatrixXd A_w = sqrt_w.asDiagonal() * fit->A;
  const Eigen::VectorXd y_w = sqrt_w.cwiseProduct(fit->y);
  // A column without signal: nothing excites that parameter (e.g. no gravity on an axis).
  const Eigen::VectorXd norms = A_w.colwise().norm();
  for (int j = 0; j < p; ++j) {
    if (!(norms(j) > 0.0)) {
      throw std::runtime_error(what + ": " + fit->unknowns[j].name +
                               " cannot be estimated: no position puts gravity on the axis it multiplies");
    }
  }
  // Directions the positions and temperatures cannot separate.
  const Eigen::MatrixXd A_n = A_w * norms.cwiseInverse().asDiagonal();
  const SymmetricEigen eig = SymmetricEigenDecomposition(A_n.transpose() * A_n);
  if (eig.values(0) < kWarmUpNullEigenvalueRatio * eig.values.maxCoeff()) {
    const Eigen::VectorXd v = eig.vectors.col(0);
    const double vmax = v.cwiseAbs().maxCoeff();
    std::string names;
    for (int j = 0; j < p; ++j) {
      if (std::abs(v(j)) > 0.1 * vmax) names += (names.empty() ? "" : ", ") + fit->unknowns[j].name;
    }
    throw std::runtime_error(what + ": " + names +
                             " cannot be separated with these positions and temperatures; hold every axis at "
                             "+1 g and -1 g at several temperatures while the IMU warms up");
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A_w);
  const Eigen::MatrixXd R = qr.matrixQR().topRows(p).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd R_inv = R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(p, p));
  const Eigen::VectorXd x_scaled = qr.solve(y_w);
  fit->residual = fit->y - fit->A * x_scaled;
  fit->variance_factor = fit->residual.cwiseAbs2().dot(fit->w) / (m - p);
  Eigen::VectorXd unscale(p);
  for (int j = 0; j < p; ++j) unscale(j) = std::pow(scale, -fit->unknowns[j].power);
  fit->x = unscale.cwiseProduct(x_scaled);
  fit->covariance = fit->variance_factor * unscale.asDiagonal() * (R_inv * R_inv.transpose()) * unscale.asDiagonal();
}

/// The segments of one run's static holds.
void CutSegments(const WarmUpRun& run, int run_index, const TemperatureCalibrationOptions& options,
                 const std::string& what, std::vector<WarmUpSegment>* segments, int* positions) {
  const MultiPositionData& data = run.data;
  const std::string label = "run " + std::to_string(run_index) + " (" +
                            (data.imu_path.empty() ? std::string("the IMU data") : data.imu_path) + ")";
  const sim::MultiPositionRig rig(data.schedule);
  const std::vector<sim::StaticInterval>& intervals = rig.static_intervals();
  constexpr int kMinPositions = 6;  // as the multi-position calibration: 12 accelerometer unknowns
  if (static_cast<int>(intervals.size()) < kMinPositions) {
    throw std::runtime_error(what + ": " + label + ": the schedule has " + std::to_string(intervals.size()) +
                             " static positions; at least " + std::to_string(kMinPositions) + " are needed");
  }
  const TemperatureSeries& temp = run.temperature;
  if (temp.t_s.empty() || temp.t_s.size() != temp.temperature_degC.size()) {
    throw std::runtime_error(what + ": " + label + ": no temperature readings" +
                             (temp.path.empty() ? std::string() : " in " + temp.path));
  }
  const std::vector<ImuSample>& imu = data.imu;
  constexpr double kEps_s = 1e-9;
  const double settle_s = options.multiposition.settle_s;
  for (std::size_t j = 0; j < intervals.size(); ++j) {
    const double h0 = intervals[j].start_s + settle_s, h1 = intervals[j].end_s - settle_s;
    const std::string where = label + ": position " + std::to_string(j + 1) + " (hold " +
                              Num(intervals[j].start_s, 6) + " to " + Num(intervals[j].end_s, 6) + " s)";
    if (!(h1 > h0)) throw std::runtime_error(what + ": " + where + " is not longer than twice settle_s");
    const StaticTruth truth = StaticTruthAt(intervals[j].euler_rad, data.latitude_rad, data.height_m);
    const int n_seg = std::max(1, static_cast<int>(std::floor((h1 - h0) / options.segment_s + 1e-9)));
    const double len = (h1 - h0) / n_seg;
    for (int k = 0; k < n_seg; ++k) {
      WarmUpSegment seg;
      seg.run = run_index;
      seg.position = static_cast<int>(j);
      seg.t0_s = h0 + k * len;
      seg.t1_s = h0 + (k + 1) * len;
      const auto begin = std::partition_point(imu.begin(), imu.end(), [&seg](const ImuSample& s) {
        return s.t_s - s.dt_s < seg.t0_s - kEps_s;
      });
      const auto end =
          std::partition_point(begin, imu.end(), [&seg](const ImuSample& s) { return s.t_s <= seg.t1_s + kEps_s; });
      Eigen::Vector3d dv = Eigen::Vector3d::Zero(), dth = Eigen::Vector3d::Zero();
      for (auto it = begin; it != end; ++it) {
        dv += it->dv_b_mps;
        dth += it->dtheta_b_rad;
        seg.duration_s += it->dt_s;
      }
      if (!(seg.duration_s > 0.0)) {
        throw std::runtime_error(what + ": no IMU samples in " + where + " between " + Num(seg.t0_s, 6) + " and " +
                                 Num(seg.t1_s, 6) + " s");
      }
      seg.f_mean_b_mps2 = dv / seg.duration_s;
      seg.omega_mean_b_rad_per_s = dth / seg.duration_s;
      seg.f_true_b_mps2 = truth.f_b_mps2;
      seg.omega_true_b_rad_per_s = truth.omega_ib_b_rad_per_s;
      // Temperature: the mean of the readings within, else interpolated at the middle.
      const auto t_begin = std::lower_bound(temp.t_s.begin(), temp.t_s.end(), seg.t0_s);
      const auto t_end = std::upper_bound(t_begin, temp.t_s.end(), seg.t1_s);
      if (t_begin != t_end) {
        double sum = 0.0;
        for (auto it = t_begin; it != t_end; ++it) sum += temp.temperature_degC[it - temp.t_s.begin()];
        seg.temperature_degC = sum / static_cast<double>(t_end - t_begin);
      } else {
        const double t_mid = 0.5 * (seg.t0_s + seg.t1_s);
        if (t_begin == temp.t_s.begin() || t_begin == temp.t_s.end()) {
          throw std::runtime_error(what + ": the temperature file " + temp.path + " (" + Num(temp.t_s.front(), 6) +
                                   " to " + Num(temp.t_s.back(), 6) + " s) does not cover " + where);
        }
        const std::size_t b = static_cast<std::size_t>(t_begin - temp.t_s.begin()), a = b - 1;
        const double f = (t_mid - temp.t_s[a]) / (temp.t_s[b] - temp.t_s[a]);
        seg.temperature_degC = temp.temperature_degC[a] + f * (temp.temperature_degC[b] - temp.temperature_degC[a]);
      }
      segments->push_back(seg);
    }
    ++*positions;
  }
}

}  // namespace

namespace {

/// The warm-up segments as the static positions of the result (their residuals).
std::vector<StaticPosition> SegmentPositions(const std::vector<WarmUpSegment>& segments) {
  std::vector<StaticPosition> out;
  for (const WarmUpSegment& seg : segments) {
    StaticPosition p;
    p.t0_s = seg.t0_s;
    p.t1_s = seg.t1_s;
    p.run = seg.run;
    p.temperature_degC = seg.temperature_degC;
    p.f_true_b_mps2 = seg.f_true_b_mps2;
    p.f_mean_b_mps2 = seg.f_mean_b_mps2;
    p.omega_true_b_radps = seg.omega_true_b_rad_per_s;
    p.omega_mean_b_radps = seg.omega_mean_b_rad_per_s;
    out.push_back(p);
  }
  return out;
}

}  // namespace

WarmUpCalibration CalibrateWarmUp(const std::vector<WarmUpRun>& runs, const TemperatureCalibrationOptions& options) {
  const std::string what = "warm-up temperature calibration";
  if (options.order < 1) {
    throw std::runtime_error(what + ": the polynomial order must be >= 1, got " + std::to_string(options.order));
  }
  if (!(options.segment_s > 0.0) || !std::isfinite(options.segment_s)) {
    throw std::runtime_error(what + ": segment_s must be finite and > 0, got " + Num(options.segment_s));
  }
  if (runs.empty()) throw std::runtime_error(what + ": no runs");
  WarmUpCalibration out;
  int positions = 0;
  for (std::size_t r = 0; r < runs.size(); ++r) {
    CutSegments(runs[r], static_cast<int>(r), options, what, &out.segments, &positions);
  }
  const std::vector<WarmUpSegment>& segments = out.segments;
  const int m = static_cast<int>(segments.size());
  std::vector<double> temperatures;
  for (const WarmUpSegment& seg : segments) temperatures.push_back(seg.temperature_degC);
  CheckTemperatureCoverage(temperatures, options.order, options.min_span_per_order_degC,
                           what + " (mean temperatures of the " + std::to_string(m) + " segments)");
  double reference_degC = 0.0;
  if (options.reference_degC) {
    reference_degC = *options.reference_degC;
    if (!std::isfinite(reference_degC)) throw std::runtime_error(what + ": the reference temperature is not finite");
  } else {
    for (double t : temperatures) reference_degC += t;
    reference_degC /= m;
  }
  double scale = 0.0;
  for (double t : temperatures) scale = std::max(scale, std::abs(t - reference_degC));

  // One least squares per axis: the axes share no unknown (white noise independent per axis).
  const int order = options.order;
  const bool estimate_g = options.multiposition.estimate_g_sensitivity;
  std::vector<AxisFit> fits;
  for (int i = 0; i < 3; ++i) {
    AxisFit a;
    a.label = std::string("accel ") + "xyz"[i];
    a.unknowns.push_back({TriadParameterName("accel", i), 0});
    for (int j = 0; j < 3; ++j) {
      if (j != i) a.unknowns.push_back({TriadParameterName("accel", MisalignmentIndex(i, j)), 0});
    }
    a.unknowns.push_back({TriadParameterName("accel", 9 + i), 0});
    for (int k = 1; k <= order; ++k) a.unknowns.push_back({TriadParameterName("accel", i) + ".dT" + std::to_string(k), k});
    for (int k = 1; k <= order; ++k) {
      a.unknowns.push_back({TriadParameterName("accel", 9 + i) + ".dT" + std::to_string(k), k});
    }
    AxisFit g;
    g.label = std::string("gyro ") + "xyz"[i];
    g.unknowns.push_back({TriadParameterName("gyro", 9 + i), 0});
    for (int k = 1; k <= order; ++k) {
      g.unknowns.push_back({TriadParameterName("gyro", 9 + i) + ".dT" + std::to_string(k), k});
    }
    if (estimate_g) {
      for (int j = 0; j < 3; ++j) g.unknowns.push_back({GSensitivityParameterName(3 * i + j), 0});
    }
    for (AxisFit* fit : {&a, &g}) {
      fit->A.resize(m, static_cast<Eigen::Index>(fit->unknowns.size()));
      fit->y.resize(m);
      fit->w.resize(m);
    }
    for (int s = 0; s < m; ++s) {
      const WarmUpSegment& seg = segments[s];
      const Eigen::Vector3d& f = seg.f_true_b_mps2;
      const double u = scale > 0.0 ? (seg.temperature_degC - reference_degC) / scale : 0.0;
      int c = 0;
      a.A(s, c++) = f(i);
      for (int j = 0; j < 3; ++j) {
        if (j != i) a.A(s, c++) = f(j);
      }
      a.A(s, c++) = 1.0;
      for (int k = 1; k <= order; ++k) a.A(s, c++) = std::pow(u, k) * f(i);
      for (int k = 1; k <= order; ++k) a.A(s, c++) = std::pow(u, k);
      a.y(s) = seg.f_mean_b_mps2(i) - f(i);
      c = 0;
      g.A(s, c++) = 1.0;
      for (int k = 1; k <= order; ++k) g.A(s, c++) = std::pow(u, k);
      if (estimate_g) {
        for (int j = 0; j < 3; ++j) g.A(s, c++) = f(j);
      }
      g.y(s) = seg.omega_mean_b_rad_per_s(i) - seg.omega_true_b_rad_per_s(i);
      a.w(s) = g.w(s) = seg.duration_s;
    }
    fits.push_back(std::move(a));
    fits.push_back(std::move(g));
  }
  for (AxisFit& fit : fits) SolveAxis(&fit, scale > 0.0 ? scale : 1.0, what);

  // Where each parameter lives: (fit, column).
  const auto locate = [&fits](const std::string& name) -> std::pair<int, int> {
    for (std::size_t f = 0; f < fits.size(); ++f) {
      for (std::size_t j = 0; j < fits[f].unknowns.size(); ++j) {
        if (fits[f].unknowns[j].name == name) return {static_cast<int>(f), static_cast<int>(j)};
      }
    }
    return {-1, -1};
  };

  ImuCalibrationResult& result = out.result;
  ImuCalibration& cal = result.calibration;
  Eigen::Matrix<double, kTriadParameters, 1> gyro_sigma = NotEstimated<kTriadParameters>();
  Eigen::Matrix<double, kTriadParameters, 1> accel_sigma = NotEstimated<kTriadParameters>();
  Eigen::Matrix<double, kGSensitivityParameters, 1> g_sigma = NotEstimated<kGSensitivityParameters>();
  TemperatureTerms terms = ZeroTerms(reference_degC, order);
  // Outputs in the chamber path's order: gyro block, accel block, g-sensitivity; each
  // temperature-dependent parameter followed by its .dT<k>.
  std::vector<std::pair<int, int>> where;
  const auto add = [&](const std::string& name) {
    const std::pair<int, int> loc = locate(name);
    if (loc.first < 0) return false;
    where.push_back(loc);
    result.estimated.push_back(name);
    return true;
  };
  for (const char* triad : {"gyro", "accel"}) {
    const bool gyro = std::string(triad) == "gyro";
    for (int idx = 0; idx < kTriadParameters; ++idx) {
      const std::string name = TriadParameterName(triad, idx);
      if (!add(name)) {
        result.unobservable.push_back(name + ": not estimated from warm-up data (the static holds see only the "
                                             "Earth rate; the gyro scale factor and misalignment need rotations)");
        continue;
      }
      const auto [f, j] = where.back();
      (gyro ? cal.gyro : cal.accel)(idx) = fits[f].x(j);
      (gyro ? gyro_sigma : accel_sigma)(idx) = std::sqrt(fits[f].covariance(j, j));
      if (!IsTemperatureDependent(idx)) continue;
      for (int k = 1; k <= order; ++k) {
        if (!add(name + ".dT" + std::to_string(k))) continue;
        SetTemperatureCoefficient(gyro, idx, k, fits[where.back().first].x(where.back().second), &terms);
      }
    }
  }
  for (int idx = 0; idx < kGSensitivityParameters && estimate_g; ++idx) {
    add(GSensitivityParameterName(idx));
    const auto [f, j] = where.back();
    cal.g_sensitivity(idx) = fits[f].x(j);
    g_sigma(idx) = std::sqrt(fits[f].covariance(j, j));
  }
  cal.gyro_sigma = gyro_sigma;
  cal.accel_sigma = accel_sigma;
  if (estimate_g) cal.g_sensitivity_sigma = g_sigma;
  cal.temperature = terms;
  // Axes are independent least squares: covariance blocks between them are 0.
  const int n_out = static_cast<int>(where.size());
  result.covariance = Eigen::MatrixXd::Zero(n_out, n_out);
  for (int a = 0; a < n_out; ++a) {
    for (int b = 0; b < n_out; ++b) {
      if (where[a].first == where[b].first) {
        result.covariance(a, b) = fits[where[a].first].covariance(where[a].second, where[b].second);
      }
    }
  }

  double accel_ss = 0.0, gyro_ss = 0.0;
  for (const AxisFit& fit : fits) (fit.label[0] == 'a' ? accel_ss : gyro_ss) += fit.residual.squaredNorm();
  result.accel_residual_rms_mps2 = std::sqrt(accel_ss / (3.0 * m));
  result.gyro_residual_rms_rad_per_s = std::sqrt(gyro_ss / (3.0 * m));
  result.positions = positions;
  result.static_positions = SegmentPositions(out.segments);
  result.residuals = StaticResiduals(result.calibration, result.static_positions);
  const auto [t_min, t_max] = std::minmax_element(temperatures.begin(), temperatures.end());
  result.notes.push_back(std::to_string(runs.size()) + " warm-up run(s), " + std::to_string(positions) +
                         " static positions cut into " + std::to_string(m) + " segments (segment_s " +
                         Num(options.segment_s) + " s) at " + Num(*t_min) + " .. " + Num(*t_max) + " degC; order " +
                         std::to_string(order) + " in dT = T - " + Num(reference_degC) + " degC");
  for (const AxisFit& fit : fits) {
    // With weights in seconds, the a-posteriori sigma is the noise of a 1 s mean.
    result.notes.push_back(fit.label + ": noise of a 1 s mean " + Num(std::sqrt(fit.variance_factor)) +
                           (fit.label[0] == 'a' ? " m/s^2" : " rad/s") + " (a posteriori, " +
                           std::to_string(m - static_cast<int>(fit.unknowns.size())) + " dof)");
  }
  return out;
}

TemperatureSeries ReadTemperatureFile(const std::string& path) {
  ScalarSeries series = ReadScalarSeriesCsv(path, "temperature", {{"_degC", 1.0}}, kMinRecordTemperatureDegC,
                                            kMaxRecordTemperatureDegC);
  TemperatureSeries out;
  out.t_s = std::move(series.t_s);
  out.temperature_degC = std::move(series.value);
  out.path = path;
  return out;
}

TemperatureRecord ReadTemperatureRecord(const std::string& record_path) {
  TemperatureRecord record;
  TemperatureCalibrationOptions* options = &record.options;
  const ConfigNode root = LoadYamlFile(record_path);
  root.RequireKeys({"order", "latitude_deg", "height_m", "reference_degC", "segment_s", "runs"});
  options->order = root.Int("order", 2, 1, kMaxOrder);
  if (!root.Has("latitude_deg")) root.Fail("latitude_deg", "missing (the latitude of the chamber, deg)");
  root.Double("latitude_deg", 0.0, -90.0, 90.0);
  root.Double("height_m", 0.0, -1000.0, 10000.0);
  if (root.Has("reference_degC")) {
    options->reference_degC =
        root.Double("reference_degC", 0.0, kMinRecordTemperatureDegC, kMaxRecordTemperatureDegC);
  }
  options->segment_s = root.Double("segment_s", options->segment_s, kMinSegmentS, kMaxSegmentS);
  if (!root.Has("runs")) root.Fail("runs", "missing (a list of {temperature_degC, imu, trajectory})");
  const std::vector<ConfigNode> run_nodes = root.Elements("runs");
  if (run_nodes.empty()) root.Fail("runs", "the list is empty");
  const std::string base_dir = std::filesystem::path(record_path).parent_path().string();

  for (const ConfigNode& node : run_nodes) {
    node.RequireKeys({"temperature_degC", "temperature", "imu", "trajectory"});
    const bool warm_up = node.Has("temperature");
    if (warm_up && node.Has("temperature_degC")) {
      node.Fail("temperature", "give temperature_degC (a chamber soak) or temperature (a warm-up file), not both");
    }
    if (!warm_up && !node.Has("temperature_degC")) {
      node.Fail("temperature_degC", "missing (the soak temperature, degC; or temperature: FILE for a warm-up)");
    }
    if ((warm_up && !record.chamber.empty()) || (!warm_up && !record.warm_up.empty())) {
      node.Fail(warm_up ? "temperature" : "temperature_degC",
                "the record mixes chamber runs (temperature_degC) and warm-up runs (temperature: FILE); "
                "calibrate them as two records");
    }
    // The multi-position reader takes {imu, latitude_deg, height_m, trajectory}: the run's
    // own keys plus the record's site (the nodes keep their lines for messages).
    YAML::Node merged(YAML::NodeType::Map);
    for (const char* key : {"imu", "trajectory"}) {
      if (node.Has(key)) merged[key] = node.yaml()[key];
    }
    for (const char* key : {"latitude_deg", "height_m"}) {
      if (root.Has(key)) merged[key] = root.yaml()[key];
    }
    if (warm_up) {
      WarmUpRun run;
      const std::string file = node.String("temperature", "");
      if (file.empty()) node.Fail("temperature", "must name the temperature file (t_s,temperature_degC)");
      std::filesystem::path p(file);
      if (p.is_relative() && !base_dir.empty()) p = std::filesystem::path(base_dir) / p;
      run.temperature = ReadTemperatureFile(p.string());
      run.data = ReadMultiPositionData(ConfigNode(merged, node.file(), node.path()), base_dir);
      record.warm_up.push_back(std::move(run));
    } else {
      TemperatureRun run;
      run.temperature_degC =
          node.Double("temperature_degC", 0.0, kMinRecordTemperatureDegC, kMaxRecordTemperatureDegC);
      run.data = ReadMultiPositionData(ConfigNode(merged, node.file(), node.path()), base_dir);
      record.chamber.push_back(std::move(run));
    }
  }
  if (!record.chamber.empty() && root.Has("segment_s")) {
    root.Fail("segment_s", "applies to warm-up runs (temperature: FILE) only");
  }
  return record;
}

ImuCalibrationResult CalibrateTemperatureRecord(const std::string& record_path) {
  const TemperatureRecord record = ReadTemperatureRecord(record_path);
  if (!record.warm_up.empty()) return CalibrateWarmUp(record.warm_up, record.options).result;
  return CalibrateTemperature(record.chamber, record.options).result;
}

}  // namespace navtwin::calibration
