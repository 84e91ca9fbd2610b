// Temperature calibration (issue 8 item 4, seed 001 section 3 "Temperature"): bias and
// scale factor of every axis of both triads as polynomials in temperature, from chamber
// data: several runs, each a multi-position table schedule (+1 g and -1 g on every axis)
// soaked at one temperature. docs/calibration-temperature.md gives the method and figures.
//
//   1. one multi-position calibration per run (problems/calibration/multiposition.h):
//      every parameter with its sigma and the run's full covariance;
//   2. per bias / scale-factor parameter p, a weighted least-squares polynomial
//        p(T) = c_0 + c_1 dT + ... + c_n dT^n,   dT = T - reference_degC   (degC)
//      over the runs, weights 1 / sigma_r^2 (the seed's a T^2 + b T + c, with T in degC
//      instead of the seed's raw ADC counts);
//   3. misalignment, g-sensitivity (and the gyro scale factor when no run rotates the table)
//      do not depend on temperature: their weighted mean over the runs (an order-0 fit,
//      whose chi-square tests that independence).
// Every output is a linear combination of the runs' estimates, so the full covariance of
// the outputs follows from the runs' covariances (runs independent).
//
// Warm-up data (CalibrateWarmUp): runs whose temperature drifts (the IMU's self-heating
// after switch-on), each a multi-position schedule with the IMU temperature sensor's file.
// Every static hold is cut into segments of segment_s at their mean temperature, and one
// linear least squares over all segments of all runs fits the static model with the
// temperature polynomials inside it (docs/calibration-temperature.md "Warm-up data"):
//   f_m     = (K_a0 + diag(sum_k c_k dT^k)) f + b_a0 + sum_k d_k dT^k
//   omega_m = omega + G f + b_g0 + sum_k e_k dT^k
// (the gyro scale factor and misalignment need rotations: not estimated from the holds).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "problems/calibration/imu_calibration.h"
#include "problems/calibration/multiposition.h"

namespace navtwin::calibration {

/// One estimate of a parameter at one temperature.
struct TemperaturePoint {
  double temperature_degC = 0.0;
  double value = 0.0;
  double sigma = 0.0;  ///< one standard deviation (> 0)
};

/// A weighted least-squares polynomial in dT = T - reference_degC.
struct TemperaturePolynomial {
  double reference_degC = 0.0;
  /// c_0 .. c_order, c_k in value units per degC^k (c_0: the value at the reference).
  Eigen::VectorXd coefficients;
  Eigen::MatrixXd covariance;  ///< of the coefficients
  /// coefficients = gain * values (order + 1 rows, one column per point): the linear map
  /// that propagates the points' covariance to the coefficients.
  Eigen::MatrixXd gain;
  double chi_square = 0.0;  ///< sum ((value - p(T)) / sigma)^2
  int dof = 0;              ///< points - (order + 1)

  int order() const { return static_cast<int>(coefficients.size()) - 1; }
  double Evaluate(double temperature_degC) const;
};

/// Temperatures closer than this count as one chamber set point.
constexpr double kDistinctTemperatureDegC = 1.0;
/// Default minimum span per polynomial order (docs/calibration-temperature.md "Span").
constexpr double kMinSpanPerOrderDegC = 10.0;

/// Throws std::runtime_error unless the temperatures hold at least order + 1 distinct
/// values ("order 2 needs at least 3 temperatures, got 2") and span at least
/// order * min_span_per_order_degC. `what` prefixes the messages.
void CheckTemperatureCoverage(const std::vector<double>& temperatures_degC, int order,
                              double min_span_per_order_degC, const std::string& what);

/// The fit (order >= 0; order 0 is the weighted mean). Checks the coverage as above and
/// throws std::runtime_error naming `what` for a non-finite value or a sigma that is not
/// finite and > 0.
TemperaturePolynomial FitTemperaturePolynomial(const std::vector<TemperaturePoint>& points, int order,
                                               double reference_degC,
                                               double min_span_per_order_degC = kMinSpanPerOrderDegC,
                                               const std::string& what = "temperature fit");

/// One chamber run: its temperature and its multi-position data.
struct TemperatureRun {
  double temperature_degC = 0.0;
  MultiPositionData data;
};

struct TemperatureCalibrationOptions {
  int order = 2;  ///< polynomial order of bias and scale factor (>= 1)
  /// dT = T - reference; default: the mean of the run temperatures.
  std::optional<double> reference_degC;
  double min_span_per_order_degC = kMinSpanPerOrderDegC;
  /// Warm-up data only: the length of the segments each static hold is cut into (s, > 0).
  double segment_s = 10.0;
  MultiPositionOptions multiposition;
};

/// A parameter's fit over the runs, by its name (TriadParameterName, ...).
struct TemperatureParameterFit {
  std::string name;
  TemperaturePolynomial fit;
};

struct TemperatureCalibration {
  /// calibration: the constant blocks at the reference temperature, `temperature` the
  /// coefficients k = 1..order. `estimated` names the constant parameters as usual and the
  /// coefficients as "<name>.dT<k>" (e.g. "accel.bias.x.dT2", units per degC^k); the
  /// covariance covers all of them.
  ImuCalibrationResult result;
  std::vector<double> temperatures_degC;      ///< of the runs, in run order
  std::vector<ImuCalibrationResult> runs;     ///< the multi-position results
  std::vector<TemperatureParameterFit> fits;  ///< bias and scale-factor polynomials
  std::vector<TemperatureParameterFit> pooled;  ///< temperature-independent parameters (order 0)
};

/// Throws std::runtime_error for too few distinct temperatures or too small a span for the
/// order, and when a bias or scale factor cannot be estimated in some run (e.g. a run
/// without +1 g and -1 g on an axis), naming the parameter, the run and the reason.
TemperatureCalibration CalibrateTemperature(const std::vector<TemperatureRun>& runs,
                                            const TemperatureCalibrationOptions& options = {});

/// The IMU temperature sensor's readings along a run (a temperature.csv).
struct TemperatureSeries {
  std::vector<double> t_s;  ///< strictly increasing, on the IMU's time scale
  std::vector<double> temperature_degC;
  std::string path;  ///< for messages
};

/// Reads t_s,temperature_degC (CSV with a header; also t_ms). Throws InputError naming the
/// file, line and field for a missing column, a value that is not a finite number, time
/// that does not increase, or a file without samples.
TemperatureSeries ReadTemperatureFile(const std::string& path);

/// One warm-up run: a multi-position schedule during which the temperature drifts.
struct WarmUpRun {
  MultiPositionData data;
  TemperatureSeries temperature;
};

/// One segment of a static hold: the means the least squares uses.
struct WarmUpSegment {
  int run = 0;
  int position = 0;            ///< 0-based hold of the run's schedule
  double t0_s = 0.0, t1_s = 0.0;
  double duration_s = 0.0;     ///< sum of the samples' dt (the weight)
  double temperature_degC = 0.0;  ///< mean of the readings within (interpolated if none)
  Eigen::Vector3d f_true_b_mps2, omega_true_b_rad_per_s;
  Eigen::Vector3d f_mean_b_mps2, omega_mean_b_rad_per_s;
};

struct WarmUpCalibration {
  /// The same layout as TemperatureCalibration::result: constant blocks at the reference,
  /// `temperature` the coefficients k >= 1, "<name>.dT<k>" in `estimated`.
  ImuCalibrationResult result;
  std::vector<WarmUpSegment> segments;
};

/// The warm-up calibration. Throws std::runtime_error for a schedule with fewer than 6
/// static positions, a hold without IMU samples or outside the temperature file, too few
/// distinct segment temperatures or too small a span for the order, fewer segments than
/// unknowns, and parameters the positions and temperatures cannot separate (naming them).
WarmUpCalibration CalibrateWarmUp(const std::vector<WarmUpRun>& runs, const TemperatureCalibrationOptions& options = {});

/// A temperature record: chamber runs (temperature_degC) or warm-up runs (temperature:
/// FILE), never both.
struct TemperatureRecord {
  TemperatureCalibrationOptions options;
  std::vector<TemperatureRun> chamber;
  std::vector<WarmUpRun> warm_up;
};

/// Reads a temperature record (schema in imu_calibration.h and
/// docs/calibration-temperature.md). Throws InputError (file, line, key), also for a
/// record that mixes chamber and warm-up runs.
TemperatureRecord ReadTemperatureRecord(const std::string& record_path);

}  // namespace navtwin::calibration
