// IMU calibration reports: parameter names, the JSON object of --format=json and the text
// table for people (units in its header: ppm, mrad, mg, deg/h, deg/h/g).
#include "problems/calibration/imu_calibration.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/imu_error_model.h"
#include "core/io/csv_imu.h"
#include "core/io/json_writer.h"
#include "core/units.h"

namespace navtwin::calibration {
namespace {

/// One row of a report: name, SI value and sigma, the factor to the printed unit and the unit.
struct Row {
  std::string name;
  double value = 0.0;
  double sigma = std::numeric_limits<double>::quiet_NaN();
  double per_si = 1.0;
  const char* unit = "";
};


double SigmaOr(const std::optional<Eigen::Matrix<double, kTriadParameters, 1>>& s, int i) {
  return s ? (*s)(i) : std::numeric_limits<double>::quiet_NaN();
}

std::vector<Row> Rows(const ImuCalibration& c) {
  std::vector<Row> rows;
  const auto triad = [&rows](const std::string& name, const Eigen::Matrix<double, kTriadParameters, 1>& v,
                             const std::optional<Eigen::Matrix<double, kTriadParameters, 1>>& s,
                             double bias_per_si, const char* bias_unit) {
    for (int i = 0; i < kTriadParameters; ++i) {
      Row r;
      r.name = TriadParameterName(name, i);
      r.value = v(i);
      r.sigma = SigmaOr(s, i);
      if (i < 3) {
        r.per_si = 1.0 / kPpm;
        r.unit = "ppm";
      } else if (i < 9) {
        r.per_si = 1e3;
        r.unit = "mrad";
      } else {
        r.per_si = bias_per_si;
        r.unit = bias_unit;
      }
      rows.push_back(r);
    }
  };
  triad("accel", c.accel, c.accel_sigma, 1.0 / kMilliG_mps2, "mg");
  triad("gyro", c.gyro, c.gyro_sigma, 1.0 / kDegPerHour_radps, "deg/h");
  for (int i = 0; i < kGSensitivityParameters; ++i) {
    Row r;
    r.name = GSensitivityParameterName(i);
    r.value = c.g_sensitivity(i);
    r.sigma = c.g_sensitivity_sigma ? (*c.g_sensitivity_sigma)(i) : std::numeric_limits<double>::quiet_NaN();
    r.per_si = kStandardGravity_mps2 / kDegPerHour_radps;
    r.unit = "deg/h/g";
    rows.push_back(r);
  }
  return rows;
}

/// Sigma of the estimated parameter `name` from the result's covariance (NaN if absent).
double SigmaByName(const ImuCalibrationResult& result, const std::string& name) {
  for (std::size_t i = 0; i < result.estimated.size(); ++i) {
    if (result.estimated[i] == name && static_cast<Eigen::Index>(i) < result.covariance.rows()) {
      return std::sqrt(result.covariance(i, i));
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

/// The temperature coefficients (`<triad>.bias.x.dT1`, `<triad>.scale_factor.z.dT2`, ...),
/// each per degC^k, with the sigma of the temperature calibration's covariance.
std::vector<Row> TemperatureRows(const ImuCalibrationResult& result) {
  std::vector<Row> rows;
  if (!result.calibration.temperature) return rows;
  const TemperatureTerms& t = *result.calibration.temperature;
  const auto terms = [&](const std::string& prefix, const std::vector<Eigen::Vector3d>& coefficients, double per_si,
                         const char* unit) {
    for (std::size_t k = 0; k < coefficients.size(); ++k) {
      for (int a = 0; a < 3; ++a) {
        Row r;
        r.name = prefix + AxisLetter(a) + ".dT" + std::to_string(k + 1);
        r.value = coefficients[k](a);
        r.sigma = SigmaByName(result, r.name);
        r.per_si = per_si;
        r.unit = unit;
        rows.push_back(r);
      }
    }
  };
  terms("accel.scale_factor.", t.accel_scale_factor, 1.0 / kPpm, "ppm/degC^k");
  terms("accel.bias.", t.accel_bias_mps2, 1.0 / kMilliG_mps2, "mg/degC^k");
  terms("gyro.scale_factor.", t.gyro_scale_factor, 1.0 / kPpm, "ppm/degC^k");
  terms("gyro.bias.", t.gyro_bias_rad_per_s, 1.0 / kDegPerHour_radps, "deg/h/degC^k");
  return rows;
}

/// Every row of a report: the constant blocks, then the temperature coefficients.
std::vector<Row> AllRows(const ImuCalibrationResult& result) {
  std::vector<Row> rows = Rows(result.calibration);
  const std::vector<Row> temperature = TemperatureRows(result);
  rows.insert(rows.end(), temperature.begin(), temperature.end());
  return rows;
}

}  // namespace

std::vector<CalibrationResidual> StaticResiduals(const ImuCalibration& c, const std::vector<StaticPosition>& positions) {
  std::vector<CalibrationResidual> out;
  out.reserve(positions.size());
  for (const StaticPosition& p : positions) {
    // Without a temperature the constant blocks hold (those at the reference temperature).
    const double reference_degC = c.temperature ? c.temperature->reference_degC : 0.0;
    const ImuCalibration at = c.At(std::isfinite(p.temperature_degC) ? p.temperature_degC : reference_degC);
    CalibrationResidual r;
    r.t0_s = p.t0_s;
    r.t1_s = p.t1_s;
    r.run = p.run;
    r.temperature_degC = p.temperature_degC;
    r.accel_before_mps2 = p.f_mean_b_mps2 - p.f_true_b_mps2;
    r.gyro_before_radps = p.omega_mean_b_radps - p.omega_true_b_radps;
    r.accel_after_mps2 = p.f_mean_b_mps2 - MeasuredSpecificForce(at.accel.data(), p.f_true_b_mps2);
    r.gyro_after_radps =
        p.omega_mean_b_radps - MeasuredRate(at.gyro.data(), at.g_sensitivity.data(), p.omega_true_b_radps, p.f_true_b_mps2);
    out.push_back(r);
  }
  return out;
}

std::string ImuCalibrationJson(const ImuCalibrationResult& result, const std::string& rig, const std::string& command) {
  std::ostringstream out;
  JsonWriter json(out);
  json.BeginObject();
  if (!command.empty()) json.Field("command", command);
  json.Field("rig", rig);
  json.Key("parameters").BeginObject();
  for (const Row& r : AllRows(result)) {
    json.Key(r.name).BeginObject();
    json.Field("value", r.value);
    json.Field("sigma", r.sigma);  // NaN (not estimated) is written as null
    json.EndObject();
  }
  json.EndObject();
  json.Key("unobservable").BeginArray();
  for (const std::string& u : result.unobservable) json.Value(u);
  json.EndArray();
  if (result.calibration.temperature) json.Field("reference_degC", result.calibration.temperature->reference_degC);
  json.Field("accel_residual_rms_mps2", result.accel_residual_rms_mps2);
  json.Field("gyro_residual_rms_rad_per_s", result.gyro_residual_rms_rad_per_s);
  json.Field("positions", result.positions);
  json.Key("notes").BeginArray();
  for (const std::string& n : result.notes) json.Value(n);
  json.EndArray();
  json.EndObject();
  return out.str();
}

void WriteImuParametersCsv(std::ostream& out, const ImuCalibrationResult& result) {
  out << "name,value,sigma,unit\n";
  for (const Row& r : AllRows(result)) {
    out << r.name << "," << r.value * r.per_si << "," << r.sigma * r.per_si << "," << r.unit << "\n";
  }
}

void WriteImuResidualsCsv(std::ostream& out, const ImuCalibrationResult& result) {
  out << "t0_s,t1_s,run,temperature_degC,rms";
  for (const char* sensor : {"accel", "gyro"}) {
    for (const char* when : {"before", "after"}) {
      for (const char* axis : {"x", "y", "z"}) {
        out << "," << sensor << "_" << when << "_" << axis << (sensor[0] == 'a' ? "_mg" : "_deg_h");
      }
    }
  }
  out << "\n";
  for (const CalibrationResidual& r : result.residuals) {
    out << r.t0_s << "," << r.t1_s << "," << r.run << "," << r.temperature_degC << "," << (r.rms ? 1 : 0);
    for (const Eigen::Vector3d* v : {&r.accel_before_mps2, &r.accel_after_mps2}) {
      for (int i = 0; i < 3; ++i) out << "," << (*v)(i) / kMilliG_mps2;
    }
    for (const Eigen::Vector3d* v : {&r.gyro_before_radps, &r.gyro_after_radps}) {
      for (int i = 0; i < 3; ++i) out << "," << (*v)(i) / kDegPerHour_radps;
    }
    out << "\n";
  }
}

namespace {

/// A column-name unit: '/' as '_' ("deg/h/g" -> "deg_h_g").
std::string UnitSuffix(const char* unit) {
  std::string s = unit;
  for (char& c : s) c = c == '/' ? '_' : c;
  return s;
}

}  // namespace

std::string RecursiveStepText(const ImuCalibrationResult& estimate, bool header) {
  std::ostringstream out;
  const std::vector<std::string> shown = {"accel.bias.", "gyro.bias.", "accel.scale_factor.", "gyro.scale_factor."};
  if (header) {
    out << "recursive multi-position calibration: the estimate after each position (value +- 1 sigma; - not yet "
           "observable, held at 0, and the sigma of the others conditional on that)\n";
    char head[256];
    std::snprintf(head, sizeof head, "%3s %9s  %-54s %-54s %-54s %s\n", "pos", "t_s", "accel bias x, y, z [mg]",
                  "gyro bias x, y, z [deg/h]", "accel scale factor x, y, z [ppm]", "gyro scale factor x, y, z [ppm]");
    out << head;
  }
  const double t_s = estimate.static_positions.empty() ? NAN : estimate.static_positions.back().t1_s;
  char line[96];
  std::snprintf(line, sizeof line, "%3d %9.1f ", estimate.positions, t_s);
  out << line;
  const std::vector<Row> rows = AllRows(estimate);
  for (const std::string& prefix : shown) {
    std::string cell;
    for (const Row& r : rows) {
      if (r.name.rfind(prefix, 0) != 0 || r.name.size() != prefix.size() + 1) continue;
      if (std::isfinite(r.sigma)) {
        std::snprintf(line, sizeof line, " %8.4g+-%-6.2g", r.value * r.per_si, r.sigma * r.per_si);
      } else {
        std::snprintf(line, sizeof line, " %8s   %-6s", "-", "");
      }
      cell += line;
    }
    out << " " << cell;
  }
  out << "\n";
  return out.str();
}

void WriteImuConvergenceCsv(std::ostream& out, const std::vector<ImuCalibrationResult>& estimates) {
  if (estimates.empty()) return;
  const std::vector<Row> names = AllRows(estimates.back());
  out << "positions,t_s";
  for (const Row& r : names) out << "," << r.name << "_" << UnitSuffix(r.unit) << "," << r.name << "_sigma_" << UnitSuffix(r.unit);
  out << "\n";
  for (const ImuCalibrationResult& e : estimates) {
    out << e.positions << "," << (e.static_positions.empty() ? NAN : e.static_positions.back().t1_s);
    const std::vector<Row> rows = AllRows(e);
    for (const Row& name : names) {
      double value = NAN, sigma = NAN;
      for (const Row& r : rows) {
        if (r.name != name.name) continue;
        value = std::isfinite(r.sigma) ? r.value * r.per_si : NAN;
        sigma = r.sigma * r.per_si;
      }
      out << "," << value << "," << sigma;
    }
    out << "\n";
  }
}

std::string ImuCalibrationText(const ImuCalibrationResult& result, const std::string& rig) {
  std::ostringstream out;
  out << "IMU calibration (" << rig << "), " << result.positions
      << (rig == "pendulum" ? " runs" : " positions") << "\n";
  char line[160];
  std::snprintf(line, sizeof(line), "%-28s %14s %12s  %s\n", "parameter", "value", "sigma", "unit");
  out << line;
  for (const Row& r : AllRows(result)) {
    const bool estimated = std::isfinite(r.sigma);
    char sigma[32];
    if (estimated) {
      std::snprintf(sigma, sizeof(sigma), "%12.4g", r.sigma * r.per_si);
    } else {
      std::snprintf(sigma, sizeof(sigma), "%12s", "-");
    }
    std::snprintf(line, sizeof(line), "%-28s %14.6g %s  %s\n", r.name.c_str(), r.value * r.per_si, sigma, r.unit);
    out << line;
  }
  if (result.calibration.temperature) {
    std::snprintf(line, sizeof(line), "temperature terms: coefficient k of (T - %.6g degC)^k\n",
                  result.calibration.temperature->reference_degC);
    out << line;
  }
  if (!result.unobservable.empty()) {
    out << "not observable (held at 0):\n";
    for (const std::string& u : result.unobservable) out << "  " << u << "\n";
  }
  std::snprintf(line, sizeof(line), "residual rms: accel %.4g mg, gyro %.4g deg/h\n",
                result.accel_residual_rms_mps2 / kMilliG_mps2, result.gyro_residual_rms_rad_per_s / kDegPerHour_radps);
  out << line;
  for (const std::string& n : result.notes) out << "note: " << n << "\n";
  return out.str();
}

}  // namespace navtwin::calibration
