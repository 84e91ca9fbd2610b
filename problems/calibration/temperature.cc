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
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include "core/io/input_error.h"
#include "core/sim/yaml_config.h"

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

std::string Num(double v, int precision = 4) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

/// Indices of the triad parameters that depend on temperature: scale factors and biases.
bool IsTemperatureDependent(int triad_index) { return triad_index < 3 || triad_index >= 9; }

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
  Eigen::Matrix<double, kTriadParameters, 1> gyro_sigma, accel_sigma;
  Eigen::Matrix<double, kGSensitivityParameters, 1> g_sigma;
  gyro_sigma.setConstant(std::numeric_limits<double>::quiet_NaN());
  accel_sigma = gyro_sigma;
  g_sigma.setConstant(std::numeric_limits<double>::quiet_NaN());
  TemperatureTerms terms;
  terms.reference_degC = reference_degC;
  for (int k = 1; k <= options.order; ++k) {
    terms.gyro_bias_rad_per_s.push_back(Eigen::Vector3d::Zero());
    terms.gyro_scale_factor.push_back(Eigen::Vector3d::Zero());
    terms.accel_bias_mps2.push_back(Eigen::Vector3d::Zero());
    terms.accel_scale_factor.push_back(Eigen::Vector3d::Zero());
  }

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
      const int axis = p.index < 3 ? p.index : p.index - 9;
      for (int k = 1; k <= order; ++k) {
        const double c = fit.fit.coefficients(k);
        if (p.triad == "gyro") {
          (p.index < 3 ? terms.gyro_scale_factor : terms.gyro_bias_rad_per_s)[k - 1](axis) = c;
        } else {
          (p.index < 3 ? terms.accel_scale_factor : terms.accel_bias_mps2)[k - 1](axis) = c;
        }
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
  std::string set_points;
  for (double t : out.temperatures_degC) set_points += (set_points.empty() ? "" : ", ") + Num(t);
  result.notes.insert(result.notes.begin(), std::to_string(n_runs) + " runs at " + set_points + " degC; order " +
                                                std::to_string(options.order) + " in dT = T - " +
                                                Num(reference_degC) + " degC");
  return out;
}

std::vector<TemperatureRun> ReadTemperatureRuns(const std::string& record_path,
                                                TemperatureCalibrationOptions* options) {
  const sim::ConfigNode root = sim::LoadYamlFile(record_path);
  root.RequireKeys({"order", "latitude_deg", "height_m", "reference_degC", "runs"});
  options->order = root.Int("order", 2, 1, kMaxOrder);
  if (!root.Has("latitude_deg")) root.Fail("latitude_deg", "missing (the latitude of the chamber, deg)");
  root.Double("latitude_deg", 0.0, -90.0, 90.0);
  root.Double("height_m", 0.0, -1000.0, 10000.0);
  if (root.Has("reference_degC")) {
    options->reference_degC =
        root.Double("reference_degC", 0.0, kMinRecordTemperatureDegC, kMaxRecordTemperatureDegC);
  }
  if (!root.Has("runs")) root.Fail("runs", "missing (a list of {temperature_degC, imu, trajectory})");
  const std::vector<sim::ConfigNode> run_nodes = root.Elements("runs");
  if (run_nodes.empty()) root.Fail("runs", "the list is empty");
  const std::string base_dir = std::filesystem::path(record_path).parent_path().string();

  std::vector<TemperatureRun> runs;
  for (const sim::ConfigNode& node : run_nodes) {
    node.RequireKeys({"temperature_degC", "imu", "trajectory"});
    TemperatureRun run;
    if (!node.Has("temperature_degC")) node.Fail("temperature_degC", "missing (the soak temperature, degC)");
    run.temperature_degC =
        node.Double("temperature_degC", 0.0, kMinRecordTemperatureDegC, kMaxRecordTemperatureDegC);
    // The multi-position reader takes {imu, latitude_deg, height_m, trajectory}: the run's
    // own keys plus the record's site (the nodes keep their lines for messages).
    YAML::Node merged(YAML::NodeType::Map);
    for (const char* key : {"imu", "trajectory"}) {
      if (node.Has(key)) merged[key] = node.yaml()[key];
    }
    for (const char* key : {"latitude_deg", "height_m"}) {
      if (root.Has(key)) merged[key] = root.yaml()[key];
    }
    run.data = ReadMultiPositionData(sim::ConfigNode(merged, node.file(), node.path()), base_dir);
    runs.push_back(std::move(run));
  }
  return runs;
}

ImuCalibrationResult CalibrateTemperatureRecord(const std::string& record_path) {
  TemperatureCalibrationOptions options;
  const std::vector<TemperatureRun> runs = ReadTemperatureRuns(record_path, &options);
  return CalibrateTemperature(runs, options).result;
}

}  // namespace navtwin::calibration
