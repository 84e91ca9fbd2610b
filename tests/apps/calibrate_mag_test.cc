// End-to-end checks of `navtwin calibrate-mag`: a simulated rate table turning about every
// axis with hard and soft iron (ellipsoid fit, heading against the truth), a simulated level
// turn of a 2-axis sensor (bidirectional), a level turn of a 3-axis sensor (planar), the
// calibration file it writes, and bad input
// (exit non-zero, a message naming file, line and field, no output file).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "tests/apps/cli_util.h"

#include "core/calibration_file.h"

namespace navtwin {
namespace apps_calibrate_mag_test {

using namespace cli_test;  // RunResult, Navtwin, MakeTempDir, JsonNumberAfter, Exists

class CalibrateMagTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = MakeTempDir("calibrate_mag"); }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  /// Simulates `yaml` (a scenario) into dir_/NAME.
  void Simulate(const std::string& name, const std::string& yaml) {
    std::ofstream(dir_ + "/" + name + ".yaml") << yaml;
    const RunResult r = Navtwin("simulate --scenario " + dir_ + "/" + name + ".yaml --seed 1 --out " + dir_ + "/" + name);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  std::string dir_;
};

/// The 3-array `key` of the JSON output (NaN when absent).
Eigen::Vector3d Array3(const std::string& json, const std::string& key = "hard_iron_uT") {
  Eigen::Vector3d h = Eigen::Vector3d::Constant(NAN);
  const std::string anchor = "\"" + key + "\":[";
  const std::size_t at = json.find(anchor);
  if (at != std::string::npos) std::sscanf(json.c_str() + at + anchor.size(), "%lf,%lf,%lf", &h[0], &h[1], &h[2]);
  return h;
}

/// A level 390 deg turn at 30 deg/s; `mag` is the scenario's mag section.
std::string LevelTurn(const std::string& mag) {
  return "name: mag-turn\nduration_s: 30\nstart: {lat_deg: 37.45, lon_deg: 126.65, h_m: 20}\n"
         "trajectory:\n  kind: multiposition\n  rotation_s: 3\n  dwell_s: 1\n  steps:\n"
         "    - euler_deg: [0, 0, 0]\n    - {rotate: yaw, rate_deg_s: 30, duration_s: 13, ramp_s: 1}\n"
         "imu: {rate_hz: 100}\n" +
         mag;
}

const char* const kMagSection =
    "mag:\n  rate_hz: 20\n  declination_deg: -8.5\n  noise_uT: 0.3\n"
    "  hard_iron_fixed_uT: [12, -7, 4]\n"
    "  soft_iron_fixed: [[0.05, 0.02, -0.01], [0.02, -0.03, 0.015], [-0.01, 0.015, 0.02]]\n";

// A rate table: two yaw turns (level, then on its side), a roll turn at 60 deg pitch, a
// yaw turn at -45 deg pitch: field directions all over the sphere.
const char* const kTable =
    "name: mag-table\nduration_s: 60\nstart: {lat_deg: 37.45, lon_deg: 126.65, h_m: 20}\n"
    "trajectory:\n  kind: multiposition\n  rotation_s: 3\n  dwell_s: 1\n  steps:\n"
    "    - euler_deg: [0, 0, 0]\n"
    "    - {rotate: yaw, rate_deg_s: 45, duration_s: 8, ramp_s: 1}\n"
    "    - euler_deg: [90, 0, 360]\n"
    "    - {rotate: yaw, rate_deg_s: 45, duration_s: 8, ramp_s: 1}\n"
    "    - euler_deg: [90, 60, 720]\n"
    "    - {rotate: roll, rate_deg_s: 45, duration_s: 8, ramp_s: 1}\n"
    "    - euler_deg: [450, -45, 720]\n"
    "    - {rotate: yaw, rate_deg_s: -45, duration_s: 8, ramp_s: 1}\n"
    "imu: {rate_hz: 100}\n";

TEST_F(CalibrateMagTest, EllipsoidOnARateTableRecoversTheHardIronAndTheHeading) {
  Simulate("table", std::string(kTable) + kMagSection);
  const std::string sim = dir_ + "/table";
  const std::string out = dir_ + "/cal.yaml";
  const RunResult r = Navtwin("calibrate-mag --mag " + sim + "/mag.csv --truth " + sim +
                              "/truth.nav --method ellipsoid --declination_deg -8.5 --format=json --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const YAML::Node truth = YAML::LoadFile(sim + "/errors.yaml")["mag"];
  const Eigen::Vector3d h = Array3(r.out), sigma = Array3(r.out, "hard_iron_sigma_uT");
  for (int i = 0; i < 3; ++i) {
    // The fit's sigma (0.03-0.04 uT here: 1200 samples of 0.3 uT noise) is honest (docs:
    // 96 of 100 Monte Carlo runs within 3 sigma) and the fit unbiased (the simulated soft
    // iron is symmetric, as the fit models it): 5 sigma.
    EXPECT_GT(sigma[i], 0.0) << r.out;
    EXPECT_NEAR(h[i], truth["hard_iron_uT"][i].as<double>(), 5.0 * sigma[i]) << "axis " << i << "\n" << r.out;
  }
  const double before = JsonNumberAfter(r.out, "{", "heading_error_before_deg");
  const double after = JsonNumberAfter(r.out, "{", "heading_error_after_deg");
  EXPECT_GT(before, 10.0) << r.out;  // 12 uT of hard iron against ~23 uT horizontal field
  // Noise alone: 0.3 uT over the 23 uT horizontal field is 0.75 deg RMS; 1 deg leaves room
  // for the remaining calibration error.
  EXPECT_LT(after, 1.0) << r.out;
  // The |m| spread falls to the noise (0.3 uT).
  EXPECT_LT(JsonNumberAfter(r.out, "{", "field_spread_after_uT"), 0.35) << r.out;

  // The file: the mag section only, read back by the calibration reader; the correction A
  // undoes the simulated I + S up to the scale to the field (A (I + S) = k I).
  const CalibrationFile file = ReadCalibrationFile(out);
  EXPECT_FALSE(file.imu);
  ASSERT_TRUE(file.mag);
  EXPECT_NE(file.created_by.find("calibrate-mag"), std::string::npos);
  // The file holds what was printed (JSON numbers have 10 significant digits).
  EXPECT_LT((file.mag->hard_iron_uT - h).norm(), 1e-8 * h.norm());
  Eigen::Matrix3d I_plus_S = Eigen::Matrix3d::Identity();
  for (int r_ = 0; r_ < 3; ++r_)
    for (int c = 0; c < 3; ++c) I_plus_S(r_, c) += truth["soft_iron"][r_][c].as<double>();
  const Eigen::Matrix3d product = file.mag->correction * I_plus_S;
  const double k = product.trace() / 3.0;
  // The soft iron's sigma is ~0.3 uT / 42 uT / sqrt(400) = 4e-4; 0.005 is ~10 sigma.
  EXPECT_LT((product / k - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 0.005) << product;

  // Without --truth the heading errors are not known: n/a in the text, null in JSON.
  const RunResult text = Navtwin("calibrate-mag --mag " + sim + "/mag.csv --method ellipsoid");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("before n/a  after n/a"), std::string::npos) << text.out;
  const RunResult json = Navtwin("calibrate-mag --mag " + sim + "/mag.csv --imu " + sim +
                                 "/imu.txt --method ellipsoid --format=json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_NE(json.out.find("\"heading_error_before_deg\":null"), std::string::npos) << json.out;
  EXPECT_EQ(json.out.find("nan"), std::string::npos) << json.out;
}

// --run_dir: every sample's field before and after (flat at the field after the fit), the
// calibration file beside it, and the page with --report.
TEST_F(CalibrateMagTest, RunFolderHoldsTheFieldBeforeAndAfter) {
  Simulate("table", std::string(kTable) + kMagSection);
  const std::string run = dir_ + "/run";
  const RunResult r =
      Navtwin("calibrate-mag --mag " + dir_ + "/table/mag.csv --method ellipsoid --report --run_dir " + run);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* file : {"summary.json", "calibration.yaml", "residuals.csv", "report.html"}) {
    EXPECT_TRUE(Exists(run + "/" + file)) << file;
  }
  std::ifstream csv(run + "/residuals.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "t_s,field_before_uT,field_after_uT");
  double min_before = 1e9, max_before = 0.0, min_after = 1e9, max_after = 0.0;
  int rows = 0;
  while (std::getline(csv, line)) {
    double t = 0.0, before = 0.0, after = 0.0;
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf", &t, &before, &after), 3) << line;
    min_before = std::min(min_before, before);
    max_before = std::max(max_before, before);
    min_after = std::min(min_after, after);
    max_after = std::max(max_after, after);
    ++rows;
  }
  EXPECT_EQ(rows, 1201);  // 60 s at 20 Hz, both ends
  // 12 uT of hard iron swings |m| by ~25 uT over the attitudes; after, the 0.3 uT noise
  // (±5σ over 1201 samples: 3 uT).
  EXPECT_GT(max_before - min_before, 15.0);
  EXPECT_LT(max_after - min_after, 3.0);
  EXPECT_EQ(Occurrences(ReadAll(run + "/report.html"), "<figure"), 1u);
}

// --method recursive: the estimate after every 1/20 of the samples, convergence.csv with a
// row per estimate, and a final hard iron near the simulated one.
TEST_F(CalibrateMagTest, RecursiveMethodConvergesToTheHardIron) {
  Simulate("table", std::string(kTable) + kMagSection);
  const std::string run = dir_ + "/run";
  const RunResult r = Navtwin("calibrate-mag --mag " + dir_ + "/table/mag.csv --method recursive --run_dir " + run);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Occurrences(r.out, " samples (t = "), 21u) << r.out;  // 1201 samples: every 60, and the last
  EXPECT_EQ(Occurrences(ReadAll(run + "/convergence.csv"), "\n"), 22u);
  const RunResult json = Navtwin("calibrate-mag --mag " + dir_ + "/table/mag.csv --method recursive --format=json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const Eigen::Vector3d h = Array3(json.out);
  const YAML::Node truth = YAML::LoadFile(dir_ + "/table/errors.yaml")["mag"];
  for (int i = 0; i < 3; ++i) {
    // The algebraic fit with 0.3 uT noise over 1201 samples: a few 0.01 uT (the robust batch
    // fit's sigma is 0.03-0.04 uT); 0.5 uT still tells a fit that missed the 12 uT.
    EXPECT_NEAR(h[i], truth["hard_iron_uT"][i].as<double>(), 0.5) << "axis " << i << "\n" << json.out;
  }
}

TEST_F(CalibrateMagTest, BidirectionalOnALevelTurnOfA2AxisSensor) {
  Simulate("turn", LevelTurn("mag:\n  rate_hz: 20\n  declination_deg: -8.5\n  noise_uT: 0.1\n  two_axis: true\n"
                              "  hard_iron_fixed_uT: [12, -7, 0]\n"
                              "  soft_iron_fixed: [[0.05, 0.03, 0], [0.03, -0.03, 0], [0, 0, 0]]\n"));
  const std::string sim = dir_ + "/turn";
  // Roll and pitch from the accelerometer for the tilt gate; the heading from the truth.
  for (const std::string& attitude : {"--truth " + sim + "/truth.nav", "--imu " + sim + "/imu.txt"}) {
    const RunResult r = Navtwin("calibrate-mag --mag " + sim + "/mag.csv " + attitude +
                                " --method bidirectional --declination_deg -8.5 --format=json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    // Hard iron from the midpoints of the extremes: noise 0.1 uT on ~25 uT extremes read
    // near their flat tops; 0.1 uT.
    EXPECT_NEAR(Array3(r.out).x(), 12.0, 0.1) << r.out;
    EXPECT_NEAR(Array3(r.out).y(), -7.0, 0.1) << r.out;
    if (attitude.find("truth") != std::string::npos) {
      const double before = JsonNumberAfter(r.out, "{", "heading_error_before_deg");
      const double after = JsonNumberAfter(r.out, "{", "heading_error_after_deg");
      EXPECT_GT(before, 10.0) << r.out;
      // The 2-axis method models soft iron as a phase and a y/x scale only: a few degrees.
      EXPECT_LT(after, 3.0) << r.out;
    }
    // The 2-axis method estimates no sigmas and leaves z alone.
    EXPECT_NE(r.out.find("\"hard_iron_sigma_uT\":[null,null,null]"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\"uncalibrated_axis_sensor\":[0,0,1]"), std::string::npos) << r.out;
  }
  const RunResult text = Navtwin("calibrate-mag --mag " + sim + "/mag.csv --method bidirectional");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("hard iron sigma [uT]         n/a        n/a        n/a"), std::string::npos) << text.out;
  // A level turn cannot calibrate the third axis: the ellipsoid fit refuses, writes nothing.
  const std::string out = dir_ + "/refused.yaml";
  const RunResult refused = Navtwin("calibrate-mag --mag " + sim + "/mag.csv --method ellipsoid --out " + out);
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("plane"), std::string::npos) << refused.err;
  EXPECT_FALSE(Exists(out));
}

// A level turn of a 3-axis sensor: the planar fit calibrates x and y (the soft iron has no
// x-z or y-z part, so the plane of the readings is the sensor's x/y plane) and leaves z.
TEST_F(CalibrateMagTest, PlanarOnALevelTurnOfA3AxisSensor) {
  Simulate("turn3", LevelTurn("mag:\n  rate_hz: 20\n  declination_deg: -8.5\n  noise_uT: 0.1\n"
                               "  hard_iron_fixed_uT: [12, -7, 4]\n"
                               "  soft_iron_fixed: [[0.05, 0.03, 0], [0.03, -0.03, 0], [0, 0, 0.02]]\n"));
  const std::string sim = dir_ + "/turn3";
  const RunResult r = Navtwin("calibrate-mag --mag " + sim + "/mag.csv --truth " + sim +
                              "/truth.nav --method planar --declination_deg -8.5 --format=json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Eigen::Vector3d h = Array3(r.out), sigma = Array3(r.out, "hard_iron_sigma_uT");
  const Eigen::Vector3d n = Array3(r.out, "uncalibrated_axis_sensor");
  // sigma of the centre: 0.1 uT noise over ~600 samples, ~0.006 uT; 5 sigma each.
  EXPECT_NEAR(h.x(), 12.0, 5.0 * sigma.x()) << r.out;
  EXPECT_NEAR(h.y(), -7.0, 5.0 * sigma.y()) << r.out;
  // Not calibrated along the normal: no hard iron along it by convention (JSON numbers
  // have 10 significant digits).
  EXPECT_NEAR(n.dot(h), 0.0, 1e-8 * h.norm()) << r.out;
  EXPECT_GT(n.z(), 0.9999) << r.out;  // the plane normal (down: the vertical field's side)
  const double before = JsonNumberAfter(r.out, "{", "heading_error_before_deg");
  const double after = JsonNumberAfter(r.out, "{", "heading_error_after_deg");
  EXPECT_GT(before, 10.0) << r.out;  // 12 uT of hard iron against ~27 uT horizontal field
  // Noise 0.1 uT over 27 uT is 0.2 deg; the symmetric in-plane correction models this soft
  // iron exactly: 0.5 deg.
  EXPECT_LT(after, 0.5) << r.out;
  EXPECT_LT(JsonNumberAfter(r.out, "{", "field_spread_after_uT"), 0.12) << r.out;  // the noise
  EXPECT_NE(r.out.find("\"spread_of\":\"in-plane |m|\""), std::string::npos) << r.out;
  const RunResult text = Navtwin("calibrate-mag --mag " + sim + "/mag.csv --method planar");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("NOT calibrated along"), std::string::npos) << text.out;
  EXPECT_EQ(Navtwin("calibrate-mag --mag " + sim + "/mag.csv --method planar --field_uT 50").exit_code, 2);
}

TEST_F(CalibrateMagTest, BadInputNamesFileLineAndFieldAndWritesNothing) {
  const std::string out = dir_ + "/cal.yaml";
  struct Case {
    std::string name, text, expect;
  };
  const Case cases[] = {
      {"empty.csv", "", "empty"},
      {"nan.csv", "t_s,mx_uT,my_uT,mz_uT\n0,1,2,3\n0.05,nan,2,3\n", "line 3: field 'mx_uT'"},
      {"column.csv", "t_s,mx_uT,my_uT\n0,1,2\n0.05,1,2\n", "field 'mz_uT'"},
  };
  for (const Case& c : cases) {
    std::ofstream(dir_ + "/" + c.name) << c.text;
    const RunResult r = Navtwin("calibrate-mag --mag " + dir_ + "/" + c.name + " --method ellipsoid --out " + out);
    EXPECT_EQ(r.exit_code, 1) << c.name;
    EXPECT_NE(r.err.find(dir_ + "/" + c.name), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << r.err;
    EXPECT_FALSE(Exists(out)) << c.name;
  }
  const std::string good = dir_ + "/nan.csv";
  EXPECT_EQ(Navtwin("calibrate-mag --mag " + good + " --method spline --out " + out).exit_code, 2);
  EXPECT_EQ(Navtwin("calibrate-mag --method ellipsoid").exit_code, 2);
  EXPECT_EQ(Navtwin("calibrate-mag --mag " + good + " --method ellipsoid --field_uT -1").exit_code, 2);
  EXPECT_FALSE(Exists(out));
}

}  // namespace apps_calibrate_mag_test
}  // namespace navtwin
