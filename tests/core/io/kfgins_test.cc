// KF-GINS text formats: writer -> reader round trips and every class of bad input.
#include "core/io/kfgins.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/open.h"
#include "core/io/text_line.h"
#include "core/rotation.h"
#include "tests/core/io/io_test_util.h"

namespace navtwin {
namespace io_kfgins_test {

using testing::ExpectInputError;
using testing::ReadAllSamples;
using testing::TempFilePath;
using testing::WriteTempFile;

/// IMU samples at ~200 Hz with jittered time tags, dt consistent with the tags (the first
/// dt equal to the second interval, as the reader reconstructs it).
std::vector<ImuSample> RandomImu(int n) {
  std::mt19937 rng(1234);
  std::normal_distribution<double> inc(0.0, 1e-3);
  std::uniform_real_distribution<double> step(0.0049, 0.0051);
  std::vector<ImuSample> v(n);
  double t = 388000.0;
  for (int k = 0; k < n; ++k) {
    v[k].t_s = t;
    v[k].dtheta_b_rad = Eigen::Vector3d(inc(rng), inc(rng), inc(rng));
    v[k].dv_b_mps = Eigen::Vector3d(inc(rng), inc(rng), inc(rng) - 0.049);
    t += step(rng);
  }
  for (int k = 1; k < n; ++k) v[k].dt_s = v[k].t_s - v[k - 1].t_s;
  v[0].dt_s = v[1].dt_s;
  return v;
}

TEST(KfginsTest, ImuRoundTripIsExact) {
  const std::vector<ImuSample> in = RandomImu(500);
  const std::string path = TempFilePath("imu_roundtrip.txt");
  KfginsImuWriter w(path);
  for (const ImuSample& s : in) w.Write(s);
  w.Commit();
  const std::vector<ImuSample> out = ReadAllSamples(*OpenKfginsImu(path));
  ASSERT_EQ(out.size(), in.size());
  // 17 significant digits round-trip a double exactly, so everything compares equal.
  for (std::size_t k = 0; k < in.size(); ++k) {
    EXPECT_EQ(out[k].t_s, in[k].t_s);
    EXPECT_EQ(out[k].dt_s, in[k].dt_s);
    EXPECT_EQ(out[k].dtheta_b_rad, in[k].dtheta_b_rad);
    EXPECT_EQ(out[k].dv_b_mps, in[k].dv_b_mps);
  }
}

TEST(KfginsTest, ReadsKfginsStyleWhitespaceAndCommas) {
  const std::string path = WriteTempFile("imu_styles.txt",
                                         "  100.000  1e-4 2e-4 3e-4   0.01 0.02 -0.049\n"
                                         "\n"
                                         "100.005,1e-4,2e-4,3e-4,0.01,0.02,-0.049\r\n"
                                         "# a comment line\n"
                                         "100.011\t1e-4\t2e-4\t3e-4\t0.01\t0.02\t-0.049\n");
  const std::vector<ImuSample> out = ReadAllSamples(*OpenKfginsImu(path));
  ASSERT_EQ(out.size(), 3u);
  // Differences of decimal time tags: exact to 1e-9 s (values near 100 s).
  EXPECT_NEAR(out[0].dt_s, 0.005, 1e-9);
  EXPECT_NEAR(out[1].dt_s, 0.005, 1e-9);
  EXPECT_NEAR(out[2].dt_s, 0.006, 1e-9);
  EXPECT_EQ(out[2].dv_b_mps.z(), -0.049);
}

// OB_GINS writes the odometer speed as an 8th column of its IMU file: the IMU reader reads
// the increments, ReadOdometer the speeds; a 7-column file has no odometer column.
TEST(KfginsTest, ObginsEighthColumnIsTheOdometer) {
  const std::string path = WriteTempFile("imu_odo.txt", "100.00 1e-4 0 0 0 0 -0.098 3.5\n100.01 1e-4 0 0 0 0 -0.098 3.25\n");
  EXPECT_EQ(DetectFormat(path), FileFormat::kKfginsImu);
  const std::vector<ImuSample> imu = ReadAllSamples(*OpenImu(path));
  ASSERT_EQ(imu.size(), 2u);
  EXPECT_EQ(imu[1].dv_b_mps.z(), -0.098);
  const std::vector<OdometerSample> odo = ReadOdometer(path);
  ASSERT_EQ(odo.size(), 2u);
  EXPECT_EQ(odo[0].t_s, 100.0);
  EXPECT_EQ(odo[1].speed_mps, 3.25);
  const std::string seven = WriteTempFile("imu7.txt", "100.00 1e-4 0 0 0 0 -0.098\n100.01 1e-4 0 0 0 0 -0.098\n");
  ExpectInputError([&] { ReadOdometer(seven); }, {seven, "line 1", "odo", "no odometer column"});
  const std::string nan =
      WriteTempFile("imu_nan.txt", "100.00 1e-4 0 0 0 0 -0.098 3.5\n100.01 1e-4 0 0 0 0 -0.098 nan\n");
  ExpectInputError([&] { ReadOdometer(nan); }, {nan, "line 2", "odo", "not a finite number"});
}

TEST(KfginsTest, GnssRoundTripWithAndWithoutVelocity) {
  for (bool velocity : {false, true}) {
    std::vector<GnssSample> in(20);
    for (int k = 0; k < 20; ++k) {
      GnssSample& g = in[k];
      g.t_s = 388000.0 + k;
      g.lat_rad = 0.5372 + 1e-6 * k;
      g.lon_rad = 1.9942 - 2e-6 * k;
      g.h_m = 23.4567 + 0.1 * k;
      g.pos_std_ned_m = Eigen::Vector3d(0.01, 0.012, 0.03);
      g.has_velocity = velocity;
      g.v_n_mps = Eigen::Vector3d(1.5, -0.25, 0.01 * k);
      g.vel_std_ned_mps = Eigen::Vector3d(0.05, 0.05, 0.08);
    }
    const std::string path = TempFilePath(velocity ? "gnss13.txt" : "gnss7.txt");
    KfginsGnssWriter w(path);
    for (const GnssSample& g : in) w.Write(g);
    w.Commit();
    const std::vector<GnssSample> out = ReadAllSamples(*OpenKfginsGnss(path));
    ASSERT_EQ(out.size(), in.size());
    for (std::size_t k = 0; k < in.size(); ++k) {
      EXPECT_EQ(out[k].t_s, in[k].t_s);
      EXPECT_EQ(out[k].gps_week, -1);  // KF-GINS GNSS files do not say the week
      // rad -> deg (printed exactly) -> rad: two roundings, a few 1e-16 rad (1e-9 m).
      EXPECT_NEAR(out[k].lat_rad, in[k].lat_rad, 1e-15);
      EXPECT_NEAR(out[k].lon_rad, in[k].lon_rad, 1e-15);
      EXPECT_EQ(out[k].h_m, in[k].h_m);
      EXPECT_EQ(out[k].pos_std_ned_m, in[k].pos_std_ned_m);
      EXPECT_EQ(out[k].has_velocity, velocity);
      if (velocity) {
        EXPECT_EQ(out[k].v_n_mps, in[k].v_n_mps);
        EXPECT_EQ(out[k].vel_std_ned_mps, in[k].vel_std_ned_mps);
      }
    }
  }
}

TEST(KfginsTest, NavRoundTripAndUnknownWeekWrittenAsZero) {
  std::vector<NavState> in(10);
  for (int k = 0; k < 10; ++k) {
    NavState& s = in[k];
    s.gps_week = k < 5 ? -1 : 2381;
    s.t_s = 408000.0 + 0.1 * k;
    s.lat_rad = 0.6998 + 1e-7 * k;
    s.lon_rad = -1.8352;
    s.h_m = 1601.4;
    s.v_n_mps = Eigen::Vector3d(0.5, -1.0, 0.02);
    s.q_n_b = QuatFromEuler(0.01 * k, -0.2, 2.5 - 0.3 * k);
  }
  const std::string path = TempFilePath("nav.txt");
  KfginsNavWriter w(path);
  for (const NavState& s : in) w.Write(s);
  w.Commit();
  const std::vector<NavState> out = ReadAllSamples(*OpenKfginsNav(path));
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t k = 0; k < in.size(); ++k) {
    EXPECT_EQ(out[k].gps_week, k < 5 ? 0 : 2381);
    EXPECT_EQ(out[k].t_s, in[k].t_s);
    EXPECT_NEAR(out[k].lat_rad, in[k].lat_rad, 1e-15);  // deg <-> rad roundings
    EXPECT_EQ(out[k].h_m, in[k].h_m);
    EXPECT_EQ(out[k].v_n_mps, in[k].v_n_mps);
    // Euler angles printed exactly; quaternion -> Euler -> quaternion: ~1e-15 rad.
    EXPECT_LT(AttitudeError(out[k].q_n_b, in[k].q_n_b).norm(), 1e-12);
  }
}

TEST(KfginsTest, WritersRefuseValuesTheReadersWouldReject) {
  KfginsGnssWriter w(TempFilePath("refused.txt"));
  GnssSample g;  // sigma NaN by default
  EXPECT_THROW(w.Write(g), std::invalid_argument);
  KfginsImuWriter wi(TempFilePath("refused_imu.txt"));
  ImuSample s;
  s.dv_b_mps.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(wi.Write(s), std::invalid_argument);
}

TEST(KfginsTest, NavWriterRefusesImpossibleStates) {
  NavState ok;
  ok.t_s = 12.5;
  ok.lat_rad = 0.5;
  ok.h_m = 100.0;
  const auto refused = [](const NavState& s, const std::string& part) {
    TextLine line;
    try {
      AppendNavFields(s, ' ', &line);
      ADD_FAILURE() << "not refused: " << part;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("t = 12.5 s"), std::string::npos) << e.what();
    }
  };
  NavState s = ok;
  s.lat_rad = -180.9 * kDegToRad;
  refused(s, "latitude");
  s = ok;
  s.h_m = 7e19;
  refused(s, "height");
  s = ok;
  s.h_m = -4881946.0;
  refused(s, "height");
  s = ok;
  s.v_n_mps.x() = -5.7e9;
  refused(s, "velocity");
  // At the limits: written.
  s = ok;
  s.lat_rad = -0.5 * kPi;
  s.h_m = -12e3;
  TextLine line;
  AppendNavFields(s, ' ', &line);
  s.h_m = 1e7;
  AppendNavFields(s, ' ', &line);
}

TEST(KfginsTest, NavWriterWrapsTheLongitude) {
  NavState s;
  s.lon_rad = 200.0 * kDegToRad;  // past the antimeridian: -160 deg
  const std::string path = TempFilePath("wrapped.nav");
  KfginsNavWriter w(path);
  w.Write(s);
  s.t_s = 1.0;
  s.lon_rad = -kPi;  // -180 deg stays as it is
  w.Write(s);
  w.Commit();
  const std::vector<NavState> out = ReadAllSamples(*OpenKfginsNav(path));
  ASSERT_EQ(out.size(), 2u);
  EXPECT_NEAR(out[0].lon_rad * kRadToDeg, -160.0, 1e-12);
  EXPECT_NEAR(out[1].lon_rad * kRadToDeg, -180.0, 1e-12);
}

TEST(KfginsTest, SubnormalSigmaIsRefused) {
  const std::string path = WriteTempFile("denormal_sigma.txt",
                                         "100.0 30.0 114.0 20.0 0.5 0.5 1.0\n"
                                         "101.0 30.0 114.0 20.0 0.5 1e-320 1.0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsGnss(path)); },
                   {path, "line 2", "field 'sigma_e'", "subnormal"});
}

// Finite but absurd values (core/io/plausibility.h): each refused where it is read, naming
// file, line, field, the value and the limit.
TEST(KfginsTest, ImplausibleImuValuesAreRefused) {
  const std::string good = "0.01 1e-4 -0.00113 2e-5 0.001 -0.002 -0.0980665\n";
  const auto imu = [&](const std::string& name, const std::string& third_line,
                       std::initializer_list<std::string> parts) {
    const std::string path = WriteTempFile(name, "0.00 1e-4 -0.00113 2e-5 0.001 -0.002 -0.0980665\n" + good +
                                                     third_line + "0.03 0 0 0 0 0 -0.0980665\n");
    ExpectInputError([&] { ReadAllSamples(*OpenKfginsImu(path)); }, parts);
  };
  // One deleted byte: -0.00113 -> -1.13e16 ("-1.13e-16" lost its exponent sign).
  imu("deleted_byte.txt", "0.02 1e-4 -1.13e16 2e-5 0.001 -0.002 -0.0980665\n",
      {"line 3", "field 'dtheta_y'", "implausible angle increment", "-1.13e+16"});
  imu("huge_dv.txt", "0.02 1e-4 -0.00113 2e-5 1e300 -0.002 -0.0980665\n",
      {"line 3", "field 'dv_x'", "implausible velocity increment"});
  imu("huge_time.txt", "1e16 1e-4 -0.00113 2e-5 0.001 -0.002 -0.0980665\n",
      {"line 3", "field 't'", "implausible time", "1e+16"});
  // 1e-4 rad in 0.01 s is 0.57 deg/s; 1.7 rad in 0.01 s (1e4 deg/s) still passes.
  const std::string fast = WriteTempFile("fast.txt", "0.00 1.7 0 0 0 0 0\n0.01 1.7 0 0 97 0 0\n");
  EXPECT_EQ(ReadAllSamples(*OpenKfginsImu(fast)).size(), 2u);
}

TEST(KfginsTest, ImplausibleGnssAndNavValuesAreRefused) {
  const std::string fix = "100.0 30.0 114.0 20.0 0.5 0.5 1.0 1 2 3 0.1 0.1 0.1\n";
  const auto gnss = [&](const std::string& name, const std::string& line2, std::initializer_list<std::string> parts) {
    const std::string path = WriteTempFile(name, fix + line2);
    ExpectInputError([&] { ReadAllSamples(*OpenKfginsGnss(path)); }, parts);
  };
  gnss("height.txt", "101.0 30.0 114.0 1e16 0.5 0.5 1.0 1 2 3 0.1 0.1 0.1\n",
       {"line 2", "field 'h'", "implausible height"});
  gnss("lon.txt", "101.0 30.0 1e16 20.0 0.5 0.5 1.0 1 2 3 0.1 0.1 0.1\n",
       {"line 2", "field 'lon'", "implausible longitude"});
  gnss("sigma.txt", "101.0 30.0 114.0 20.0 1e9 0.5 1.0 1 2 3 0.1 0.1 0.1\n",
       {"line 2", "field 'sigma_n'", "implausible standard deviation", "1e+09"});
  gnss("tiny_sigma.txt", "101.0 30.0 114.0 20.0 0.5 1e-15 1.0 1 2 3 0.1 0.1 0.1\n",
       {"line 2", "field 'sigma_e'", "implausible standard deviation"});
  gnss("velocity.txt", "101.0 30.0 114.0 20.0 0.5 0.5 1.0 1 -1e16 3 0.1 0.1 0.1\n",
       {"line 2", "field 'v_e'", "implausible velocity"});
  gnss("vsigma.txt", "101.0 30.0 114.0 20.0 0.5 0.5 1.0 1 2 3 0.1 1e300 0.1\n",
       {"line 2", "field 'sigma_ve'", "implausible standard deviation"});
  gnss("time.txt", "1e16 30.0 114.0 20.0 0.5 0.5 1.0 1 2 3 0.1 0.1 0.1\n", {"line 2", "field 't'", "implausible time"});
  const std::string nav_line = "2381 100.0 30.0 114.0 20.0 1 2 3 0 0 90\n";
  const auto nav = [&](const std::string& name, const std::string& line2, std::initializer_list<std::string> parts) {
    const std::string path = WriteTempFile(name, nav_line + line2);
    ExpectInputError([&] { ReadAllSamples(*OpenKfginsNav(path)); }, parts);
  };
  nav("nav_h.nav", "2381 101.0 30.0 114.0 -1e16 1 2 3 0 0 90\n", {"line 2", "field 'h'", "implausible height"});
  nav("nav_v.nav", "2381 101.0 30.0 114.0 20.0 1 2 3e16 0 0 90\n", {"line 2", "field 'v_d'", "implausible velocity"});
  nav("nav_t.nav", "2381 1e16 30.0 114.0 20.0 1 2 3 0 0 90\n", {"line 2", "field 'sow'", "implausible time"});
}

TEST(KfginsTest, UncommittedWriterLeavesNoFile) {
  const std::string path = TempFilePath("uncommitted.txt");
  std::remove(path.c_str());
  {
    KfginsImuWriter w(path);
    w.Write(RandomImu(2)[0]);
  }
  EXPECT_FALSE(std::ifstream(path).good());
}

// Acceptance test: time going backwards at line 1234 is reported at line 1234.
TEST(KfginsTest, TimeBackwardsAtLine1234IsReportedThere) {
  std::ostringstream text;
  for (int line = 1; line <= 1300; ++line) {
    const double t = line == 1234 ? 100.0 + 0.005 * 1232 : 100.0 + 0.005 * line;
    text.precision(17);
    text << t << " 0 0 0 0 0 -0.049\n";
  }
  const std::string path = WriteTempFile("backwards.txt", text.str());
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsImu(path)); },
                   {path, "line 1234", "field 't'", "does not increase"});
}

TEST(KfginsTest, BadInputMessagesNameFileLineAndField) {
  const std::string good = "100.000 0 0 0 0 0 -0.049\n";
  const std::string malformed = WriteTempFile("malformed.txt", good + "100.005 0 0 0 0 0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsImu(malformed)); },
                   {malformed, "line 2", "expected 7 columns, found 6"});
  const std::string nan = WriteTempFile("nan.txt", good + "100.005 0 0 0 0 nan -0.049\n");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsImu(nan)); },
                   {"line 2", "field 'dv_y'", "not a finite number"});
  const std::string text = WriteTempFile("text.txt", good + "100.005 0 0 abc 0 0 -0.049\n");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsImu(text)); },
                   {"line 2", "field 'dtheta_z'", "not a number: 'abc'"});
  const std::string empty = WriteTempFile("empty.txt", "");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsImu(empty)); }, {empty, "empty"});
  const std::string blank = WriteTempFile("blank.txt", "\n  \n");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsGnss(blank)); }, {blank, "empty"});
  const std::string single = WriteTempFile("single.txt", good);
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsImu(single)); },
                   {"line 1", "at least two lines"});
}

TEST(KfginsTest, GnssValidation) {
  const std::string zero_sigma = WriteTempFile(
      "zero_sigma.txt", "1 30.5 114.2 20 0.01 0.01 0.02\n2 30.5 114.2 20 0.01 0 0.02\n");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsGnss(zero_sigma)); },
                   {"line 2", "field 'sigma_e'", "must be > 0"});
  const std::string mixed = WriteTempFile(
      "mixed.txt",
      "1 30.5 114.2 20 0.01 0.01 0.02\n2 30.5 114.2 20 0.01 0.01 0.02 1 2 3 .1 .1 .1\n");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsGnss(mixed)); },
                   {"line 2", "expected 7 columns, found 13"});
  const std::string lat = WriteTempFile("lat.txt", "1 91 114.2 20 0.01 0.01 0.02\n");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsGnss(lat)); }, {"line 1", "field 'lat'"});
  const std::string count = WriteTempFile("count.txt", "1 30.5 114.2 20 0.01 0.01\n");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsGnss(count)); },
                   {"line 1", "expected 7 or 13 columns, found 6"});
}

TEST(KfginsTest, NavValidation) {
  const std::string back = WriteTempFile(
      "nav_back.txt", "2381 10 30 114 20 0 0 0 0 0 0\n2381 9 30 114 20 0 0 0 0 0 0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsNav(back)); },
                   {"line 2", "field 'sow'", "does not increase"});
  const std::string week = WriteTempFile("nav_week.txt", "2381.5 10 30 114 20 0 0 0 0 0 0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenKfginsNav(week)); }, {"line 1", "field 'week'"});
}

}  // namespace io_kfgins_test
}  // namespace navtwin
