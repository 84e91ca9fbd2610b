#include "problems/calibration/monte_carlo.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <fstream>
#include <limits>
#include <stdexcept>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "core/imu_error_model.h"
#include "core/io/atomic_file.h"
#include "core/sim/scenario.h"
#include "core/sim/simulator.h"
#include "core/units.h"
#include "problems/calibration/imu_calibration.h"

namespace navtwin::calibration {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// A triad's true block (core/imu_error_model.h layout, SI) from errors.yaml's imu.errors.<triad>.
Eigen::Matrix<double, kTriadParameters, 1> TrueTriad(const YAML::Node& t, double bias_unit, const char* bias_key) {
  Eigen::Matrix<double, kTriadParameters, 1> v = Eigen::Matrix<double, kTriadParameters, 1>::Zero();
  for (int r = 0; r < 3; ++r) {
    v(r) = t["scale_factor_ppm"][r].as<double>() * kPpm;
    v(9 + r) = t[bias_key][r].as<double>() * bias_unit;
    for (int c = 0; c < 3; ++c) {
      if (c != r) v(MisalignmentIndex(r, c)) = t["misalignment_arcsec"][r][c].as<double>() * kArcsec_rad;
    }
  }
  return v;
}

struct TrueErrors {
  Eigen::Matrix<double, kTriadParameters, 1> accel, gyro;
  Eigen::Matrix<double, kGSensitivityParameters, 1> g_sensitivity;
};

TrueErrors ReadTruth(const std::string& errors_yaml) {
  const YAML::Node e = YAML::LoadFile(errors_yaml)["imu"]["errors"];
  TrueErrors t;
  t.accel = TrueTriad(e["accel"], kMicroG_mps2, "bias_ug");
  t.gyro = TrueTriad(e["gyro"], kDegPerHour_radps, "bias_deg_h");
  for (int i = 0; i < kGSensitivityParameters; ++i) {
    t.g_sensitivity(i) = e["g_sensitivity_deg_h_per_g"][i / 3][i % 3].as<double>() * kDegPerHour_radps /
                         kStandardGravity_mps2;
  }
  return t;
}

/// The record a user writes for the simulated table run (docs/calibration-imu.md).
void WriteRecord(const std::string& scenario_path, const std::string& record_path) {
  const YAML::Node s = YAML::LoadFile(scenario_path);
  YAML::Node rec;
  rec["imu"] = "imu.txt";
  rec["latitude_deg"] = s["start"]["lat_deg"];
  rec["height_m"] = s["start"]["h_m"];
  rec["trajectory"] = s["trajectory"];
  AtomicFile f(record_path);
  f.stream() << rec << "\n";
  f.Commit();
}

/// One parameter group: its names (TriadParameterName / GSensitivityParameterName) and values.
struct Group {
  std::string name;
  std::string unit;
  double scale;  ///< display per SI
  std::vector<std::string> components, parameters;
  std::vector<double> truth, estimate;
};

/// The triad's three groups (scale factor, misalignment, bias) named <triad>_...
void AddTriadGroups(const std::string& triad, const Eigen::Matrix<double, kTriadParameters, 1>& estimate,
                    const Eigen::Matrix<double, kTriadParameters, 1>& truth, double bias_scale, const char* bias_unit,
                    std::vector<Group>* out) {
  Group sf{triad + "_scale_factor", "ppm", 1.0 / kPpm, {}, {}, {}, {}};
  Group mis{triad + "_misalignment", "arcsec", 1.0 / kArcsec_rad, {}, {}, {}, {}};
  Group bias{triad + "_bias", bias_unit, bias_scale, {}, {}, {}, {}};
  for (int i = 0; i < kTriadParameters; ++i) {
    Group& g = i < 3 ? sf : (i < 9 ? mis : bias);
    g.parameters.push_back(TriadParameterName(triad, i));
    g.components.push_back(g.parameters.back().substr(g.parameters.back().rfind('.') + 1));
    g.truth.push_back(truth(i));
    g.estimate.push_back(estimate(i));
  }
  out->push_back(sf);
  out->push_back(mis);
  out->push_back(bias);
}

std::vector<Group> Groups(const ImuCalibration& est, const TrueErrors& truth) {
  std::vector<Group> out;
  AddTriadGroups("accel", est.accel, truth.accel, 1.0 / kMilliG_mps2, "mg", &out);
  AddTriadGroups("gyro", est.gyro, truth.gyro, 1.0 / kDegPerHour_radps, "deg/h", &out);
  Group g{"g_sensitivity", "deg/h/g", kStandardGravity_mps2 / kDegPerHour_radps, {}, {}, {}, {}};
  for (int i = 0; i < kGSensitivityParameters; ++i) {
    g.parameters.push_back(GSensitivityParameterName(i));
    g.components.push_back(g.parameters.back().substr(g.parameters.back().rfind('.') + 1));
    g.truth.push_back(truth.g_sensitivity(i));
    g.estimate.push_back(est.g_sensitivity(i));
  }
  out.push_back(g);
  return out;
}

std::vector<mc::Quantity> QuantitiesOf(const ImuCalibrationResult& r, const TrueErrors& truth) {
  std::vector<mc::Quantity> out;
  for (const Group& g : Groups(r.calibration, truth)) {
    const int d = static_cast<int>(g.parameters.size());
    mc::Quantity q = mc::Quantity::Empty(g.name, g.unit, g.scale, "final", g.components, {1.0});
    std::vector<int> at(d, -1);
    for (int i = 0; i < d; ++i) {
      const auto it = std::find(r.estimated.begin(), r.estimated.end(), g.parameters[i]);
      if (it != r.estimated.end()) at[i] = static_cast<int>(it - r.estimated.begin());
    }
    std::vector<double> e(d), cov(d * d, kNaN);
    for (int i = 0; i < d; ++i) {
      e[i] = g.estimate[i] - g.truth[i];
      for (int j = 0; j < d; ++j) {
        if (at[i] >= 0 && at[j] >= 0) cov[i * d + j] = r.covariance(at[i], at[j]);
      }
    }
    q.Set(0, e.data(), cov.data());
    out.push_back(std::move(q));
  }
  return out;
}

}  // namespace

void CheckCalibrationMcSetup(const CalibrationMcSetup& setup) {
  for (const std::string& m : setup.methods) {
    if (m != "batch" && m != "recursive") {
      throw std::invalid_argument("calibration Monte Carlo: unknown method '" + m + "' (batch, recursive)");
    }
  }
  if (setup.methods.empty()) throw std::invalid_argument("calibration Monte Carlo: no method");
  std::ifstream f(setup.scenario_path);
  if (!f) throw std::invalid_argument("--scenario: the calibration problem needs a scenario YAML file (e.g. data/calibration/multiposition/scenario.yaml)");
  const YAML::Node s = YAML::LoadFile(setup.scenario_path);
  if (!s["trajectory"] || s["trajectory"]["kind"].as<std::string>("") != "multiposition" || !s["start"]) {
    throw std::invalid_argument("--scenario " + setup.scenario_path + ": needs a start and a multiposition trajectory");
  }
}

mc::RunRecord CalibrationMcRun(const CalibrationMcSetup& setup, std::uint64_t seed, int run) {
  mc::RunRecord record;
  record.run = run;
  record.seed = seed;
  sim::SimulationOptions options;
  options.seed = seed;
  const sim::TemporarySimulation simulated(sim::LoadScenario(setup.scenario_path), options, "navtwin_mc_cal_");
  WriteRecord(setup.scenario_path, simulated.path("record.yaml"));
  const TrueErrors truth = ReadTruth(simulated.path("errors.yaml"));
  for (const std::string& method : setup.methods) {
    mc::MethodRecord m;
    m.method = method;
    try {
      const ImuCalibrationResult r = method == "batch"
                                         ? CalibrateMultiPositionRecord(simulated.path("record.yaml"))
                                         : CalibrateMultiPositionRecordRecursive(simulated.path("record.yaml"), {});
      m.quantities = QuantitiesOf(r, truth);
    } catch (const std::exception& e) {
      m.failure = e.what();
    }
    record.methods.push_back(std::move(m));
  }
  return record;
}

}  // namespace navtwin::calibration
