// data/calibration/README.md runs as written: its shell block (with NAVTWIN naming the built
// binary) simulates every rig's record into a temporary copy of data/calibration and
// calibrates it; each result is then checked against the errors the simulator drew.
#include <cmath>
#include <fstream>
#include <regex>
#include <string>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "tests/apps/cli_util.h"

namespace navtwin::cli_test {
namespace apps_calibration_records_test {

const std::string kSource = NAVTWIN_SOURCE_DIR;

/// The README's ```sh block.
std::string ReadmeScript() {
  const std::string readme = ReadAll(kSource + "/data/calibration/README.md");
  const std::size_t begin = readme.find("```sh\n");
  const std::size_t end = readme.find("```", begin + 6);
  EXPECT_NE(begin, std::string::npos);
  EXPECT_NE(end, std::string::npos);
  return readme.substr(begin + 6, end - begin - 6);
}

/// A parameter of a calibrate-imu run folder's summary.json: value and sigma (SI).
std::pair<double, double> Parameter(const std::string& summary, const std::string& name) {
  const std::string anchor = "\"" + name + "\"";
  return {JsonNumberAfter(summary, anchor, "value"), JsonNumberAfter(summary, anchor, "sigma")};
}

/// |estimate - truth| in sigmas (one draw per check: 4 sigma leaves a false alarm below 1e-4).
void ExpectWithin4Sigma(const std::pair<double, double>& estimate, double truth, const std::string& what) {
  ASSERT_TRUE(std::isfinite(estimate.second) && estimate.second > 0.0) << what;
  EXPECT_LT(std::abs(estimate.first - truth) / estimate.second, 4.0)
      << what << ": " << estimate.first << " +- " << estimate.second << ", truth " << truth;
}

TEST(CalibrationRecords, ReadmeRunsAsWrittenAndRecoversTheSimulatedErrors) {
  const std::string dir = MakeTempDir("calibration_records");
  std::ofstream(dir + "/readme.sh") << ReadmeScript();
  const std::string cmd = "cd " + kSource + " && NAVTWIN=" + std::string(NAVTWIN_BIN_DIR) +
                          "/navtwin TMPDIR=" + dir + " bash -e " + dir + "/readme.sh > " + dir + "/out.txt 2> " + dir +
                          "/err.txt";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << ReadAll(dir + "/err.txt");
  std::smatch m;
  const std::string out = ReadAll(dir + "/out.txt");
  ASSERT_TRUE(std::regex_search(out, m, std::regex("results in (\\S+)"))) << out;
  const std::string w = m[1];
  constexpr double kUg = 9.80665e-6, kPpm = 1e-6;

  // Multi-position: the fixed scale factor and bias of x; the recursive form printed 14 positions.
  const YAML::Node mp = YAML::LoadFile(w + "/multiposition/sim/errors.yaml")["imu"]["errors"]["accel"];
  const std::string mp_summary = ReadAll(w + "/multiposition/run/summary.json");
  ExpectWithin4Sigma(Parameter(mp_summary, "accel.scale_factor.x"), mp["scale_factor_ppm"][0].as<double>() * kPpm,
                     "multiposition accel.scale_factor.x");
  ExpectWithin4Sigma(Parameter(mp_summary, "accel.bias.x"), mp["bias_ug"][0].as<double>() * kUg,
                     "multiposition accel.bias.x");
  EXPECT_TRUE(Exists(w + "/multiposition/run/report.html"));
  EXPECT_NE(ReadAll(w + "/multiposition/recursive.txt").find("\n 14 "), std::string::npos);

  // Pendulum: the errors drawn for the one IMU (the same seed in every run).
  const YAML::Node pe = YAML::LoadFile(w + "/pendulum/sim-ned/errors.yaml")["imu"]["errors"]["accel"];
  const std::string pe_summary = ReadAll(w + "/pendulum/run/summary.json");
  ExpectWithin4Sigma(Parameter(pe_summary, "accel.scale_factor.y"), pe["scale_factor_ppm"][1].as<double>() * kPpm,
                     "pendulum accel.scale_factor.y");
  ExpectWithin4Sigma(Parameter(pe_summary, "accel.bias.z"), pe["bias_ug"][2].as<double>() * kUg, "pendulum accel.bias.z");

  // Chamber and warm-up: the linear temperature term of the x accelerometer bias, 20 ug/degC
  // in both scenarios (the warm-up's quadratic term is 0 at its reference, 25 degC).
  for (const char* rig : {"chamber", "warmup"}) {
    ExpectWithin4Sigma(Parameter(ReadAll(w + "/" + rig + "/run/summary.json"), "accel.bias.x.dT1"), 20.0 * kUg,
                       std::string(rig) + " accel.bias.x.dT1");
  }

  // Handheld: the accelerometer's biases and scale factors are in the sensor's own axes,
  // comparable with the truth to first order (the 0.5-3 mrad misalignments move them by
  // ~1e-5, a fifth of their sigma).
  const YAML::Node hh = YAML::LoadFile(w + "/handheld/sim/errors.yaml")["imu"]["errors"]["accel"];
  const std::string hh_summary = ReadAll(w + "/handheld/run/summary.json");
  ExpectWithin4Sigma(Parameter(hh_summary, "accel.bias.y"), hh["bias_ug"][1].as<double>() * kUg, "handheld accel.bias.y");
  ExpectWithin4Sigma(Parameter(hh_summary, "accel.scale_factor.z"), hh["scale_factor_ppm"][2].as<double>() * kPpm,
                     "handheld accel.scale_factor.z");

  // Magnetometer: the hard iron, and the heading after calibration within 1 deg (noise alone
  // is 0.75 deg RMS: 0.3 uT over the 23 uT horizontal field).
  const std::string mag = ReadAll(w + "/magnetometer/run/summary.json");
  const double truth[3] = {12.0, -7.0, 4.0};
  std::smatch h;
  ASSERT_TRUE(std::regex_search(mag, h, std::regex("\"hard_iron_uT\":\\[([^,]+),([^,]+),([^\\]]+)\\]"))) << mag;
  std::smatch s;
  ASSERT_TRUE(std::regex_search(mag, s, std::regex("\"hard_iron_sigma_uT\":\\[([^,]+),([^,]+),([^\\]]+)\\]"))) << mag;
  for (int i = 0; i < 3; ++i) {
    ExpectWithin4Sigma({std::stod(h[i + 1]), std::stod(s[i + 1])}, truth[i], "hard iron " + std::to_string(i));
  }
  EXPECT_LT(JsonNumberAfter(mag, "{", "heading_error_after_deg"), 1.0) << mag;
  EXPECT_NE(ReadAll(w + "/magnetometer/recursive.txt").find("1201 samples"), std::string::npos);
}

}  // namespace apps_calibration_records_test
}  // namespace navtwin::cli_test
