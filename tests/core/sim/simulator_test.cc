// The simulator end to end: files of every preset reproduce their truth under the
// mechanization when the sensors are perfect; the same seed gives the same bytes.
#include "core/sim/simulator.h"

#include <dirent.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/io/input_error.h"
#include "core/io/kfgins.h"
#include "core/rotation.h"
#include "core/sim/calibration_rig.h"
#include "core/sim/presets.h"
#include "core/strapdown.h"

namespace navtwin::sim {
namespace sim_simulator_test {

std::string MakeTempDir() {
  std::string tmpl = ::testing::TempDir() + "navtwin_sim_XXXXXX";
  EXPECT_NE(::mkdtemp(tmpl.data()), nullptr);
  return tmpl;
}

void RemoveDir(const std::string& dir) {
  if (DIR* d = ::opendir(dir.c_str())) {
    while (const dirent* e = ::readdir(d)) {
      if (e->d_name[0] != '.') std::remove((dir + "/" + e->d_name).c_str());
    }
    ::closedir(d);
  }
  ::rmdir(dir.c_str());
}

std::string ReadAll(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

struct RoundTrip {
  double max_position_error_m = 0.0;
  double max_attitude_error_deg = 0.0;
  std::size_t epochs = 0;
};

// Mechanizes imu.txt from the first truth record and compares with truth.nav at every
// epoch. The IMU's mounting is undone on the attitude: the mechanization runs in the IMU
// axes, q_n_imu = q_n_b q_b_imu.
RoundTrip MechanizeAgainstTruth(const std::string& dir, const Eigen::Vector3d& mounting_rpy_rad,
                                bool hold_height) {
  const Eigen::Quaterniond q_b_imu =
      QuatFromEuler(mounting_rpy_rad.x(), mounting_rpy_rad.y(), mounting_rpy_rad.z());
  auto imu = OpenKfginsImu(dir + "/imu.txt");
  auto truth = OpenKfginsNav(dir + "/truth.nav");
  NavState first;
  EXPECT_TRUE(truth->Next(&first));
  NavState start = first;
  start.q_n_b = first.q_n_b * q_b_imu;
  StrapdownOptions options;
  if (hold_height) options.hold_height_m = first.h_m;
  Strapdown ins(start, options);
  RoundTrip r;
  ImuSample s;
  NavState t;
  while (imu->Next(&s) && truth->Next(&t)) {
    EXPECT_NEAR(s.t_s, t.t_s, 1e-9);
    ins.Update(s);
    NavState body = ins.state();
    body.q_n_b = body.q_n_b * q_b_imu.conjugate();
    const Eigen::Vector3d dp = wgs84::GeodeticToNed({body.lat_rad, body.lon_rad, body.h_m},
                                                    {t.lat_rad, t.lon_rad, t.h_m});
    r.max_position_error_m = std::max(r.max_position_error_m, dp.norm());
    r.max_attitude_error_deg =
        std::max(r.max_attitude_error_deg, AttitudeError(t.q_n_b, body.q_n_b).norm() * kRadToDeg);
    ++r.epochs;
  }
  return r;
}

// Presets short enough for a unit test (the 1 h one is run end to end in tests/apps).
std::vector<std::string> ShortPresets() {
  std::vector<std::string> names;
  for (const std::string& name : PresetNames()) {
    if (LoadScenario(name).duration_s <= 1200.0) names.push_back(name);
  }
  return names;
}

class PresetRoundTrip : public ::testing::TestWithParam<std::string> {};

// The bound: error-free data reproduce the truth within 1 cm and 1e-4 deg (the
// 1 h preset is checked end to end by the CLI test; here each preset's own length).
TEST_P(PresetRoundTrip, PerfectSensorsReproduceTruth) {
  const Scenario scenario = LoadScenario(GetParam());
  const std::string dir = MakeTempDir();
  SimulationOptions options;
  options.perfect = true;
  const SimulationReport report = Simulate(scenario, options, dir);
  EXPECT_EQ(report.imu_samples, static_cast<std::size_t>(std::lround(scenario.duration_s *
                                                                     scenario.imu.rate_hz)));
  const RoundTrip r = MechanizeAgainstTruth(dir, scenario.imu.mounting_rpy_rad, false);
  EXPECT_EQ(r.epochs, report.imu_samples);
  EXPECT_LT(r.max_position_error_m, 0.01) << GetParam();
  EXPECT_LT(r.max_attitude_error_deg, 1e-4) << GetParam();
  RemoveDir(dir);
}

INSTANTIATE_TEST_SUITE_P(Presets, PresetRoundTrip, ::testing::ValuesIn(ShortPresets()),
                         [](const auto& info) {
                           std::string name = info.param;
                           for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return name;
                         });

// The calibration rigs go through the same scenario path: a pendulum and a
// multi-position table with a rate-table rotation, perfect sensors, reproduce their truth.
TEST(Simulator, CalibrationRigScenariosRoundTrip) {
  const std::string dir = MakeTempDir();
  const std::string rigs[] = {
      "name: pendulum\nduration_s: 30\nstart: {lat_deg: 37.45, lon_deg: 126.65, h_m: 20}\n"
      "trajectory: {kind: pendulum, length_m: 0.8, damping_per_s: 0.05, initial_angle_deg: 40,"
      " mounting: DNE}\nimu: {rate_hz: 200}\n",
      "name: table\nduration_s: 60\nstart: {lat_deg: 37.45, lon_deg: 126.65, h_m: 20}\n"
      "trajectory:\n  kind: multiposition\n  rotation_s: 4\n  dwell_s: 5\n  steps:\n"
      "    - euler_deg: [0, 0, 0]\n    - euler_deg: [90, 0, 0]\n    - euler_deg: [0, 60, 0]\n"
      "    - {rotate: yaw, rate_deg_s: 30, duration_s: 6, ramp_s: 1}\nimu: {rate_hz: 200}\n"};
  for (const std::string& yaml : rigs) {
    const Scenario scenario = ParseScenario(ParseYaml(yaml, "rig.yaml"));
    SimulationOptions options;
    options.perfect = true;
    Simulate(scenario, options, dir);
    const RoundTrip r = MechanizeAgainstTruth(dir, scenario.imu.mounting_rpy_rad, false);
    EXPECT_EQ(r.epochs, static_cast<std::size_t>(scenario.duration_s * 200.0)) << scenario.name;
    // The preset bound: 1 cm and 1e-4 deg.
    EXPECT_LT(r.max_position_error_m, 0.01) << scenario.name;
    EXPECT_LT(r.max_attitude_error_deg, 1e-4) << scenario.name;
    const YAML::Node errors = YAML::LoadFile(dir + "/errors.yaml");
    EXPECT_TRUE(errors["trajectory"]) << scenario.name << ": the rig's truth is not in errors.yaml";
  }
  RemoveDir(dir);
}

// A pendulum scenario also writes the pivot encoder, angle.csv: one reading per IMU sample
// with its time tag, the rig's angle plus white noise, rounded to the encoder's quantum.
TEST(Simulator, PendulumWritesTheEncoderAngle) {
  const std::string dir = MakeTempDir();
  const std::string yaml =
      "name: pendulum\nduration_s: 20\nstart: {lat_deg: 37.45, lon_deg: 126.65, h_m: 20}\n"
      "trajectory: {kind: pendulum, length_m: 0.8, damping_per_s: 0.05, initial_angle_deg: 40,"
      " mounting: NED, angle_noise_deg: 0.01, angle_quantum_deg: 0.001}\nimu: {rate_hz: 100}\n";
  const Scenario scenario = ParseScenario(ParseYaml(yaml, "pendulum.yaml"));
  const auto& rig = dynamic_cast<const PendulumRig&>(*scenario.trajectory);
  for (const bool perfect : {false, true}) {
    SimulationOptions options;
    options.perfect = perfect;
    const SimulationReport report = Simulate(scenario, options, dir);
    std::ifstream in(dir + "/angle.csv");
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "t_s,theta_rad");
    auto imu = OpenKfginsImu(dir + "/imu.txt");
    ImuSample s;
    std::size_t rows = 0;
    double sum2 = 0.0, worst_quantum = 0.0;
    constexpr double kQuantum = 0.001 * kDegToRad;
    while (std::getline(in, line) && imu->Next(&s)) {
      const double t = std::stod(line.substr(0, line.find(','))), theta = std::stod(line.substr(line.find(',') + 1));
      EXPECT_EQ(t, s.t_s);
      const double e = theta - rig.Angle_rad(t);
      sum2 += e * e;
      worst_quantum = std::max(worst_quantum, std::fabs(theta / kQuantum - std::round(theta / kQuantum)));
      ++rows;
    }
    EXPECT_EQ(rows, report.imu_samples);
    const double rms_deg = std::sqrt(sum2 / rows) * kRadToDeg;
    if (perfect) {
      EXPECT_EQ(rms_deg, 0.0);  // --perfect: the true angle
    } else {
      // 2000 readings of 0.01 deg noise and a 0.001 deg quantum (its rms 0.0003 deg): the
      // rms within 5 % of the noise (its relative sigma 1.6 %), every reading a multiple.
      EXPECT_NEAR(rms_deg, 0.01, 0.0005);
      EXPECT_LT(worst_quantum, 1e-6);
    }
  }
  const YAML::Node errors = YAML::LoadFile(dir + "/errors.yaml");
  EXPECT_DOUBLE_EQ(errors["trajectory"]["angle_noise_deg"].as<double>(), 0.01);
  RemoveDir(dir);
}

// A warm-up (temperature_profile not constant) also writes the IMU's temperature sensor,
// temperature.csv: one reading per IMU sample with its time tag, the profile at that time;
// a constant profile writes none.
TEST(Simulator, WarmUpWritesTheImuTemperature) {
  const std::string dir = MakeTempDir();
  const std::string base =
      "name: warmup\nduration_s: 20\nstart: {lat_deg: 37.45, lon_deg: 126.65, h_m: 20}\n"
      "trajectory: {kind: multiposition, dwell_s: 5, steps: [{euler_deg: [0, 0, 0]}, {euler_deg: [90, 0, 0]}]}\n";
  const Scenario scenario = ParseScenario(ParseYaml(
      base + "imu: {rate_hz: 100, errors: {temperature_profile: {initial_degC: 0, final_degC: 40, time_constant_s: 300}}}\n",
      "warmup.yaml"));
  const TemperatureProfile& profile = scenario.imu.errors.temperature;
  const SimulationReport report = Simulate(scenario, SimulationOptions(), dir);
  EXPECT_NE(std::find(report.files.begin(), report.files.end(), dir + "/temperature.csv"), report.files.end());
  std::ifstream in(dir + "/temperature.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t_s,temperature_degC");
  auto imu = OpenKfginsImu(dir + "/imu.txt");
  ImuSample s;
  std::size_t rows = 0;
  double previous = -1.0;
  while (std::getline(in, line) && imu->Next(&s)) {
    const double t = std::stod(line.substr(0, line.find(','))), T = std::stod(line.substr(line.find(',') + 1));
    EXPECT_EQ(t, s.t_s);
    // No delay or clock offset: the time tag is the truth time; written in the shortest
    // form that reads back exactly.
    EXPECT_EQ(T, profile.At(t));
    EXPECT_GT(T, previous);  // warming
    previous = T;
    ++rows;
  }
  EXPECT_EQ(rows, report.imu_samples);
  // 20 s of a 300 s time constant from 0 to 40 degC: 40 (1 - e^(-1/15)) = 2.58 degC.
  EXPECT_NEAR(previous, 40.0 * (1.0 - std::exp(-20.0 / 300.0)), 1e-9);
  RemoveDir(dir);

  const std::string constant_dir = MakeTempDir();
  const Scenario constant = ParseScenario(ParseYaml(
      base + "imu: {rate_hz: 100, errors: {temperature_profile: {initial_degC: 40}}}\n", "constant.yaml"));
  Simulate(constant, SimulationOptions(), constant_dir);
  EXPECT_FALSE(std::ifstream(constant_dir + "/temperature.csv").good());
  RemoveDir(constant_dir);
}

TEST(Simulator, SameSeedSameBytesOtherSeedOtherDraws) {
  Scenario scenario = LoadScenario("mems-gps-mag-maneuver");
  scenario.duration_s = 20.0;
  const std::string a = MakeTempDir(), b = MakeTempDir(), c = MakeTempDir();
  SimulationOptions options;
  options.seed = 42;
  const SimulationReport ra = Simulate(scenario, options, a);
  Simulate(scenario, options, b);
  options.seed = 43;
  Simulate(scenario, options, c);
  ASSERT_GE(ra.files.size(), 6u);  // imu, truth, init, gnss, mag, errors
  for (const std::string& path : ra.files) {
    const std::string name = path.substr(path.rfind('/') + 1);
    const std::string bytes = ReadAll(a + "/" + name);
    EXPECT_FALSE(bytes.empty()) << name;
    EXPECT_TRUE(bytes == ReadAll(b + "/" + name)) << name << " differs for the same seed";
    if (name != "truth.nav" && name != "init.nav") {
      EXPECT_FALSE(bytes == ReadAll(c + "/" + name)) << name << " equal for another seed";
    }
  }
  RemoveDir(a);
  RemoveDir(b);
  RemoveDir(c);
}

TEST(Simulator, ErrorsFileListsTheDrawnValues) {
  Scenario scenario = LoadScenario("transfer-alignment-high-maneuver");
  scenario.duration_s = 5.0;
  const std::string dir = MakeTempDir();
  SimulationOptions options;
  options.seed = 9;
  Simulate(scenario, options, dir);
  const YAML::Node errors = YAML::LoadFile(dir + "/errors.yaml");
  EXPECT_EQ(errors["seed"].as<int>(), 9);
  EXPECT_EQ(errors["scenario"].as<std::string>(), "transfer-alignment-high-maneuver");
  EXPECT_TRUE(errors["imu"]["errors"]["gyro"]) << ReadAll(dir + "/errors.yaml");
  EXPECT_TRUE(errors["master"]) << ReadAll(dir + "/errors.yaml");
  EXPECT_NEAR(errors["imu"]["mounting_deg"][2].as<double>(), 0.8, 1e-12);
  RemoveDir(dir);
}

TEST(Simulator, BadScenarioNamesFileLineAndKey) {
  const std::string dir = MakeTempDir();
  const std::string path = dir + "/bad.yaml";
  std::ofstream(path) << "name: bad\nstart: {lat_deg: 10, lon_deg: 20}\ntrajectory:\n"
                         "  segments:\n    - {kind: cruise, duration_s: 10}\nimu:\n"
                         "  rate_hz: 100\n  errors:\n    gyro: {bias_deg_hr: 1}\n";
  try {
    LoadScenario(path);
    ADD_FAILURE() << "no error for a misspelt key";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_NE(m.find("line 9"), std::string::npos) << m;
    EXPECT_NE(m.find("imu.errors.gyro.bias_deg_hr"), std::string::npos) << m;
  }
  RemoveDir(dir);
}

TEST(Simulator, DuplicateScenarioKeyNamesFileLineAndKey) {
  const std::string dir = MakeTempDir();
  const std::string nested = dir + "/nested.yaml";
  std::ofstream(nested) << "name: dup\nstart: {lat_deg: 10, lon_deg: 20}\ntrajectory:\n"
                           "  segments:\n    - {kind: cruise, duration_s: 10}\nimu:\n"
                           "  rate_hz: 100\n  errors:\n    gyro: {bias_deg_h: 1}\n"
                           "  rate_hz: 200\n";
  const std::string top = dir + "/top.yaml";
  std::ofstream(top) << "name: dup\nstart: {lat_deg: 10, lon_deg: 20}\nname: again\n";
  const std::string flow = dir + "/flow.yaml";
  std::ofstream(flow) << "name: dup\nstart: {lat_deg: 10, lon_deg: 20, lat_deg: 11}\n";
  const struct {
    std::string path;
    long line;
    const char* key;
  } cases[] = {{nested, 10, "imu.rate_hz"}, {top, 3, "name"}, {flow, 2, "start.lat_deg"}};
  for (const auto& c : cases) {
    try {
      LoadScenario(c.path);
      ADD_FAILURE() << "no error for a repeated key in " << c.path;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), c.path);
      EXPECT_EQ(e.line(), c.line) << e.what();
      EXPECT_EQ(e.field(), c.key) << e.what();
      EXPECT_NE(std::string(e.what()).find("repeated"), std::string::npos) << e.what();
    }
  }
  RemoveDir(dir);
}

}  // namespace sim_simulator_test
}  // namespace navtwin::sim
