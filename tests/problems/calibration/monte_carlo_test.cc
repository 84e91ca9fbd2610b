// IMU calibration under `navtwin mc --problem calibration`: a run of the repository's
// multi-position record with both methods, errors against the simulated truth with each
// method's covariance blocks; the setup check.
#include <cmath>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "problems/calibration/monte_carlo.h"

namespace navtwin::calibration {
namespace calibration_monte_carlo_test {

const std::string kScenario = std::string(NAVTWIN_SOURCE_DIR) + "/data/calibration/multiposition/scenario.yaml";

TEST(CalibrationMcTest, ARunScoresBothMethodsWithTheirCovariances) {
  CalibrationMcSetup setup;
  setup.scenario_path = kScenario;
  const mc::RunRecord r = CalibrationMcRun(setup, 3, 0);
  ASSERT_EQ(r.methods.size(), 2u);
  for (const mc::MethodRecord& m : r.methods) {
    ASSERT_TRUE(m.failure.empty()) << m.method << ": " << m.failure;
    ASSERT_EQ(m.quantities.size(), 7u) << m.method;
    for (const mc::Quantity& q : m.quantities) {
      const int d = q.dim();
      const Eigen::Map<const Eigen::MatrixXd> P(q.covariance.data(), d, d);
      const Eigen::Map<const Eigen::VectorXd> e(q.error.data(), d);
      ASSERT_TRUE(P.allFinite()) << m.method << " " << q.name;  // every parameter is estimated here
      ASSERT_EQ(Eigen::LLT<Eigen::MatrixXd>(P).info(), Eigen::Success) << m.method << " " << q.name;
      // The scenario's errors (4000 ppm, 800 arcsec, 8 mg, 500 deg/h) are recovered to a few
      // sigma: NEES below the chi-square 99.99 % point of its dimension (at most 9: 33.7).
      const double nees = e.dot(Eigen::LLT<Eigen::MatrixXd>(P).solve(e));
      EXPECT_LT(nees, 33.7) << m.method << " " << q.name;
    }
  }
  EXPECT_EQ(r.methods[0].quantities[0].name, "accel_scale_factor");
  EXPECT_EQ(r.methods[0].quantities[1].components[0], "xy");
}

TEST(CalibrationMcTest, TheSetupNamesWhatIsWrong) {
  CalibrationMcSetup setup;
  setup.scenario_path = kScenario;
  setup.methods = {"batch", "kalman"};
  EXPECT_THROW(CheckCalibrationMcSetup(setup), std::invalid_argument);
  setup.methods = {"batch"};
  setup.scenario_path = "mems-gps-mag-maneuver";  // a preset, not a table scenario file
  EXPECT_THROW(CheckCalibrationMcSetup(setup), std::invalid_argument);
  setup.scenario_path = kScenario;
  EXPECT_NO_THROW(CheckCalibrationMcSetup(setup));
}

}  // namespace calibration_monte_carlo_test
}  // namespace navtwin::calibration
