// A navigation solution as GNSS fixes (core/io/nav_as_gnss.h), the converter behind
// `navtwin convert --what gnss` from the ANSFL DJI reference: every record becomes one fix
// with the stated sigma, the KF-GINS GNSS file it is written to reads back as the same
// fixes (what smooth and navigate read), and a sigma that the GNSS readers would refuse is
// refused here already.
#include "core/io/nav_as_gnss.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/ansfl.h"
#include "core/io/kfgins.h"
#include "core/io/open.h"
#include "core/units.h"
#include "tests/core/io/io_test_util.h"

namespace navtwin {
namespace io_nav_as_gnss_test {

using testing::MakeTempDir;
using testing::ReadAllSamples;
using testing::WriteFile;

/// A Horizontal-style GT.csv (no GTExtended.csv beside it): 2 m/s north, 1 m/s west,
/// climbing 0.5 m/s, 10 Hz.
std::string GtText(int rows) {
  std::string text =
      "time,distance(meters),speed(m/s), compass_heading(degrees), pitch(degrees), "
      "roll(degrees),height_above_takeoff(meters),North,East,Down\n";
  for (int k = 0; k < rows; ++k) {
    text += std::to_string(0.1 * k) + ",0,0,270,-2,1,0," + std::to_string(0.2 * k) + "," +
            std::to_string(-0.1 * k) + "," + std::to_string(-0.05 * k) + "\n";
  }
  return text;
}

TEST(NavAsGnss, EveryRecordIsAFixWithTheStatedSigma) {
  const std::string dir = MakeTempDir();
  const std::string gt = WriteFile(dir + "/GT.csv", GtText(6));
  const std::vector<NavState> nav = ReadAllSamples(*OpenAnsflGt(gt));
  const std::vector<GnssSample> fixes = ReadAllSamples(*NavAsGnssReader(OpenNav(gt), {0.1, 0.15}));
  ASSERT_EQ(fixes.size(), nav.size());
  for (std::size_t k = 0; k < fixes.size(); ++k) {
    // Exactly the record's values: the adapter copies, it computes nothing.
    EXPECT_EQ(fixes[k].t_s, nav[k].t_s);
    EXPECT_EQ(fixes[k].lat_rad, nav[k].lat_rad);
    EXPECT_EQ(fixes[k].lon_rad, nav[k].lon_rad);
    EXPECT_EQ(fixes[k].h_m, nav[k].h_m);
    ASSERT_TRUE(fixes[k].has_velocity);
    EXPECT_EQ(fixes[k].v_n_mps, nav[k].v_n_mps);
    EXPECT_EQ(fixes[k].pos_std_ned_m, Eigen::Vector3d::Constant(0.1));
    EXPECT_EQ(fixes[k].vel_std_ned_mps, Eigen::Vector3d::Constant(0.15));
  }
}

TEST(NavAsGnss, KfginsGnssFileReadsBackAsTheSameFixes) {
  const std::string dir = MakeTempDir();
  const std::string gt = WriteFile(dir + "/GT.csv", GtText(6));
  const std::string out = dir + "/gnss.txt";
  const std::vector<GnssSample> fixes = ReadAllSamples(*NavAsGnssReader(OpenNav(gt), {0.1, 0.15}));
  {
    KfginsGnssWriter writer(out);
    for (const GnssSample& g : fixes) writer.Write(g);
    writer.Commit();
  }
  EXPECT_EQ(DetectFormat(out), FileFormat::kKfginsGnss);
  const std::vector<GnssSample> back = ReadAllSamples(*OpenGnss(out));
  ASSERT_EQ(back.size(), fixes.size());
  for (std::size_t k = 0; k < back.size(); ++k) {
    // 17 significant digits in the file: the degrees' round trip through text and radians
    // is within 1e-15 rad (6 nm); heights, speeds and sigmas are exact to 1e-12.
    EXPECT_NEAR(back[k].t_s, fixes[k].t_s, 1e-12);
    EXPECT_NEAR(back[k].lat_rad, fixes[k].lat_rad, 1e-15);
    EXPECT_NEAR(back[k].lon_rad, fixes[k].lon_rad, 1e-15);
    EXPECT_NEAR(back[k].h_m, fixes[k].h_m, 1e-9);
    ASSERT_TRUE(back[k].has_velocity);
    EXPECT_LT((back[k].v_n_mps - fixes[k].v_n_mps).norm(), 1e-12);
    EXPECT_LT((back[k].pos_std_ned_m - fixes[k].pos_std_ned_m).norm(), 1e-12);
    EXPECT_LT((back[k].vel_std_ned_mps - fixes[k].vel_std_ned_mps).norm(), 1e-12);
  }
}

TEST(NavAsGnss, SigmaThatIsNotPositiveAndFiniteIsRefused) {
  const std::string dir = MakeTempDir();
  const std::string gt = WriteFile(dir + "/GT.csv", GtText(3));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const NavAsGnssOptions& o : {NavAsGnssOptions{0.0, 0.1}, NavAsGnssOptions{0.1, -0.1},
                                    NavAsGnssOptions{nan, 0.1}, NavAsGnssOptions{0.1, INFINITY}}) {
    EXPECT_THROW(NavAsGnssReader(OpenNav(gt), o), std::invalid_argument)
        << o.pos_sigma_m << " " << o.vel_sigma_mps;
  }
}

}  // namespace io_nav_as_gnss_test
}  // namespace navtwin
