// The two configuration loaders: navtwin's YAML (units in the key names, errors naming
// file, line and key) and KF-GINS' YAML taken unchanged.
#include "problems/gnss_ins/ins_vocabulary.h"  // before config.h, which uses InsState
#include "problems/gnss_ins/config.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "core/units.h"
#include "tests/core/io/io_test_util.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_config_test {

using navtwin::testing::ExpectInputError;
using navtwin::testing::MakeTempDir;
using navtwin::testing::WriteFile;
using navtwin::testing::WriteTempFile;

// Unit conversions are exact products of double constants: compare to 1e-15 relative.
constexpr double kRel = 1e-15;

const char* const kFull = R"(# a complete navtwin configuration
imu_noise:
  gyro_arw_deg_sqrt_h: 3
  accel_vrw_m_s_sqrt_h: 0.6
  gyro_bias_std_deg_h: 144
  accel_bias_std_ug: 25500
  gyro_scale_std_ppm: 2000
  accel_scale_std_ppm: 1000
  correlation_time_s: inf
installation:
  imu_mounting_deg: [180, 0, -90]
  imu_time_offset_s: 0.01
  antenna_lever_arm_b_m: [0.1, 0.2, -0.3]
init:
  source: given
  position_deg_m: [37.45, 126.65, 300]
  velocity_mps: [21, 22, -1]
  attitude_deg: [1, 2, 45]
  time_s: 10
  position_std_m: 5
  velocity_std_mps: [0.5, 0.5, 1]
  attitude_std_deg: [1, 1, 5]
  gyro_bias_deg_h: [10, 0, 0]
mag:
  mode: vector
  field: {declination_deg: -8.5, inclination_deg: 57, intensity_uT: 50}
  hard_iron_uT: [14, 2.4, -4.2]
  soft_iron: [[0.01, 0, 0], [0, -0.02, 0], [0, 0, 0.03]]
  noise_uT: 0.3
  heading_std_deg: 2
baro: {use: true, std_m: 2}
zupt: {enabled: true, gyro_threshold_deg_s: 0.5}
gnss: {use_velocity: false, pos_std_floor_m: 0.5, max_distance_m: 500}
outages: {start_s: 60, len_s: 15, period_s: 45}
filter: {scale_factors: true, gate_probability: 0.999, max_bridge_gap_s: 0.05}
batch: {max_state_interval_s: 0.5, huber_k: 2, threads: 2, covariance: false}
output_rate_hz: 10
start_s: 5
end_s: 300
)";

TEST(GnssInsConfig, FullFileConvertsUnits) {
  const GnssInsConfig c = LoadGnssInsConfig(WriteTempFile("c.yaml", kFull));
  EXPECT_NEAR(c.imu_noise.gyro_arw_rad_per_sqrt_s, 3.0 * kDegToRad / 60.0, 1e-18);
  EXPECT_NEAR(c.imu_noise.accel_vrw_mps_per_sqrt_s, 0.01, kRel);
  EXPECT_NEAR(c.imu_noise.gyro_bias_std_radps, 144.0 * kDegToRad / 3600.0, kRel);
  EXPECT_NEAR(c.imu_noise.accel_bias_std_mps2, 25500e-6 * kStandardGravity_mps2, kRel);
  EXPECT_NEAR(c.imu_noise.gyro_scale_std, 2000e-6, kRel);
  EXPECT_NEAR(c.imu_noise.accel_scale_std, 1000e-6, kRel);
  EXPECT_TRUE(std::isinf(c.imu_noise.correlation_time_s));
  EXPECT_NEAR(c.installation.imu_mounting_rpy_rad[0], M_PI, kRel);
  EXPECT_NEAR(c.installation.imu_mounting_rpy_rad[2], -M_PI / 2, kRel);
  EXPECT_EQ(c.installation.imu_time_offset_s, 0.01);
  EXPECT_EQ(c.installation.antenna_lever_arm_b_m, Eigen::Vector3d(0.1, 0.2, -0.3));
  ASSERT_TRUE(c.init.state.has_value());
  EXPECT_EQ(c.init.source, InitConfig::Source::kGiven);
  EXPECT_EQ(c.init.state->nav.t_s, 10.0);
  EXPECT_NEAR(c.init.state->nav.lat_rad, 37.45 * kDegToRad, kRel);
  EXPECT_EQ(c.init.state->nav.h_m, 300.0);
  EXPECT_EQ(c.init.state->nav.v_n_mps, Eigen::Vector3d(21, 22, -1));
  const Eigen::Vector3d rpy = EulerFromQuat(c.init.state->nav.q_n_b) / kDegToRad;
  EXPECT_NEAR(rpy[2], 45.0, 1e-12);  // Euler round trip, a few ulp of 45
  EXPECT_EQ(c.init.std.pos_ned_m, Eigen::Vector3d::Constant(5.0));
  EXPECT_NEAR(c.init.std.att_rad[2], 5.0 * kDegToRad, kRel);
  EXPECT_NEAR(c.init.imu_errors.bg_radps[0], 10.0 * kDegToRad / 3600.0, kRel);
  EXPECT_EQ(c.init.std.bg_radps, Eigen::Vector3d::Zero());  // absent: take imu_noise
  EXPECT_EQ(c.mag.mode, MagConfig::Mode::kVector);
  // B [cos I cos D, cos I sin D, sin I].
  const double D = -8.5 * kDegToRad, I = 57.0 * kDegToRad;
  EXPECT_NEAR(c.mag.field_ned_uT.x(), 50 * std::cos(I) * std::cos(D), 1e-12);
  EXPECT_NEAR(c.mag.field_ned_uT.y(), 50 * std::cos(I) * std::sin(D), 1e-12);
  EXPECT_NEAR(c.mag.field_ned_uT.z(), 50 * std::sin(I), 1e-12);
  EXPECT_NEAR(c.mag.declination_rad, D, kRel);
  EXPECT_EQ(c.mag.iron.soft_iron(1, 1), -0.02);
  EXPECT_EQ(c.mag.iron.hard_iron_uT, Eigen::Vector3d(14, 2.4, -4.2));
  EXPECT_NEAR(c.mag.heading_std_rad, 2 * kDegToRad, kRel);
  EXPECT_TRUE(c.baro.use);
  EXPECT_EQ(c.baro.std_m, 2.0);
  EXPECT_TRUE(c.zupt.enabled);
  EXPECT_NEAR(c.zupt.gyro_threshold_radps, 0.5 * kDegToRad, kRel);
  EXPECT_FALSE(c.gnss.use_velocity);
  EXPECT_EQ(c.gnss.max_distance_m, 500.0);
  EXPECT_EQ(c.outages.start_s, 60.0);
  EXPECT_EQ(c.outages.period_s, 45.0);
  EXPECT_TRUE(c.filter.scale_factors);
  EXPECT_EQ(c.filter.max_bridge_gap_s, 0.05);
  EXPECT_EQ(c.batch.threads, 2);
  EXPECT_FALSE(c.batch.covariance);
  EXPECT_EQ(c.output_rate_hz, 10.0);
  EXPECT_EQ(c.start_time_s, 5.0);
  EXPECT_EQ(c.end_time_s, 300.0);
  EXPECT_TRUE(c.imu_path.empty());
}

TEST(GnssInsConfig, DefaultsForOptionalSections) {
  const GnssInsConfig c = LoadGnssInsConfig(WriteTempFile("c.yaml", R"(imu_noise:
  gyro_arw_deg_sqrt_h: 0.1
  accel_vrw_m_s_sqrt_h: 0.1
  gyro_bias_std_deg_h: 1
  accel_bias_std_ug: 100
init: {source: static}
)"));
  const GnssInsConfig d;
  EXPECT_EQ(c.init.source, InitConfig::Source::kStaticAlignment);
  EXPECT_FALSE(c.init.state.has_value());
  EXPECT_EQ(c.mag.mode, MagConfig::Mode::kOff);
  EXPECT_EQ(c.filter.gate_probability, d.filter.gate_probability);
  EXPECT_EQ(c.batch.max_state_interval_s, d.batch.max_state_interval_s);
  EXPECT_EQ(c.imu_noise.correlation_time_s, d.imu_noise.correlation_time_s);
  EXPECT_TRUE(std::isnan(c.outages.start_s));
  EXPECT_EQ(c.output_rate_hz, 0.0);
}

// Zero or negative sigmas: InputError with the file, the line and the key path.
TEST(GnssInsConfig, NonPositiveSigmaNamesFileLineAndKey) {
  const std::string head = R"(imu_noise:
  gyro_arw_deg_sqrt_h: 0.1
  accel_vrw_m_s_sqrt_h: 0.1
  gyro_bias_std_deg_h: 1
  accel_bias_std_ug: 100
init: {source: static}
)";
  const std::string zero = WriteTempFile("zero.yaml", head + "gnss:\n  default_pos_std_m: 0\n");
  ExpectInputError([&] { LoadGnssInsConfig(zero); },
                   {zero, "line 8", "gnss.default_pos_std_m", "> 0"});
  const std::string negative = WriteTempFile(
      "neg.yaml", "imu_noise:\n  gyro_arw_deg_sqrt_h: -0.1\n  accel_vrw_m_s_sqrt_h: 0.1\n"
                  "  gyro_bias_std_deg_h: 1\n  accel_bias_std_ug: 100\n");
  ExpectInputError([&] { LoadGnssInsConfig(negative); },
                   {negative, "line 2", "imu_noise.gyro_arw_deg_sqrt_h"});
  const std::string vec = WriteTempFile("vec.yaml", head + "mag:\n  noise_uT: 0.0\n");
  ExpectInputError([&] { LoadGnssInsConfig(vec); }, {vec, "line 8", "mag.noise_uT"});
  const std::string init = WriteTempFile(
      "init.yaml", "imu_noise:\n  gyro_arw_deg_sqrt_h: 0.1\n  accel_vrw_m_s_sqrt_h: 0.1\n"
                   "  gyro_bias_std_deg_h: 1\n  accel_bias_std_ug: 100\n"
                   "init:\n  source: static\n  position_std_m: [1, 0, 1]\n");
  ExpectInputError([&] { LoadGnssInsConfig(init); }, {init, "line 8", "init.position_std_m"});
}

// An empty or missing init.nav_file names the configuration, line and key (it once gave
// "navtwin navigate: : cannot open the file").
TEST(GnssInsConfig, EmptyOrMissingNavFileNamesTheKey) {
  const std::string head = "imu_noise:\n  gyro_arw_deg_sqrt_h: 0.1\n  accel_vrw_m_s_sqrt_h: 0.1\n"
                           "  gyro_bias_std_deg_h: 1\n  accel_bias_std_ug: 100\ninit:\n  source: given\n";
  const std::string empty = WriteTempFile("empty_nav.yaml", head + "  nav_file: \"\"\n");
  ExpectInputError([&] { LoadGnssInsConfig(empty); }, {empty, "line 8", "init.nav_file", "empty"});
  const std::string missing = WriteTempFile("missing_nav.yaml", head + "  nav_file: nowhere.nav\n");
  ExpectInputError([&] { LoadGnssInsConfig(missing); }, {missing, "line 8", "init.nav_file", "no such file"});
}

// The GNSS installation keys (docs/gnss-ins.md "GNSS installation parameters"): defaults off,
// 0.5 m, 0 s and 0.2 s; the lever arm's std a scalar or per axis; the offset within +-1 s.
TEST(GnssInsConfig, GnssInstallationKeys) {
  const std::string head = R"(imu_noise:
  gyro_arw_deg_sqrt_h: 0.1
  accel_vrw_m_s_sqrt_h: 0.1
  gyro_bias_std_deg_h: 1
  accel_bias_std_ug: 100
init: {source: static}
)";
  const GnssInsConfig d = LoadGnssInsConfig(WriteTempFile("d.yaml", head));
  EXPECT_FALSE(d.gnss.estimate_lever_arm);
  EXPECT_FALSE(d.gnss.estimate_time_offset);
  EXPECT_EQ(d.gnss.lever_arm_std_m, Eigen::Vector3d::Constant(0.5));
  EXPECT_EQ(d.gnss.time_offset_s, 0.0);
  EXPECT_EQ(d.gnss.time_offset_std_s, 0.2);
  const GnssInsConfig c = LoadGnssInsConfig(WriteTempFile(
      "c.yaml", head + "gnss: {estimate_lever_arm: true, lever_arm_std_m: [0.2, 0.3, 1.0], estimate_time_offset: "
                       "true, time_offset_s: 0.1, time_offset_std_s: 0.05}\n"));
  EXPECT_TRUE(c.gnss.estimate_lever_arm);
  EXPECT_TRUE(c.gnss.estimate_time_offset);
  EXPECT_EQ(c.gnss.lever_arm_std_m, Eigen::Vector3d(0.2, 0.3, 1.0));
  EXPECT_EQ(c.gnss.time_offset_s, 0.1);
  EXPECT_EQ(c.gnss.time_offset_std_s, 0.05);
  const std::string scalar = WriteTempFile("s.yaml", head + "gnss: {lever_arm_std_m: 0.1}\n");
  EXPECT_EQ(LoadGnssInsConfig(scalar).gnss.lever_arm_std_m, Eigen::Vector3d::Constant(0.1));
  const std::string far = WriteTempFile("far.yaml", head + "gnss:\n  time_offset_s: 1.5\n");
  ExpectInputError([&] { LoadGnssInsConfig(far); }, {far, "line 8", "gnss.time_offset_s"});
  const std::string zero = WriteTempFile("z.yaml", head + "gnss:\n  lever_arm_std_m: [0.1, 0, 0.1]\n");
  ExpectInputError([&] { LoadGnssInsConfig(zero); }, {zero, "line 8", "gnss.lever_arm_std_m"});
  const std::string zero_t = WriteTempFile("zt.yaml", head + "gnss:\n  time_offset_std_s: 0\n");
  ExpectInputError([&] { LoadGnssInsConfig(zero_t); }, {zero_t, "line 8", "gnss.time_offset_std_s"});
}

TEST(GnssInsConfig, UnknownAndMissingKeys) {
  const std::string typo = WriteTempFile(
      "typo.yaml", "imu_noise:\n  gyro_arw_deg_sqrt_hr: 0.1\n");
  ExpectInputError([&] { LoadGnssInsConfig(typo); },
                   {typo, "line 2", "imu_noise.gyro_arw_deg_sqrt_hr", "unknown key"});
  const std::string missing = WriteTempFile(
      "missing.yaml", "imu_noise:\n  gyro_arw_deg_sqrt_h: 0.1\n  accel_vrw_m_s_sqrt_h: 0.1\n"
                      "  gyro_bias_std_deg_h: 1\n");
  ExpectInputError([&] { LoadGnssInsConfig(missing); }, {"imu_noise.accel_bias_std_ug", "required"});
  const std::string scale = WriteTempFile(
      "scale.yaml", "imu_noise:\n  gyro_arw_deg_sqrt_h: 0.1\n  accel_vrw_m_s_sqrt_h: 0.1\n"
                    "  gyro_bias_std_deg_h: 1\n  accel_bias_std_ug: 100\n"
                    "filter: {scale_factors: true}\n");
  ExpectInputError([&] { LoadGnssInsConfig(scale); }, {"imu_noise.gyro_scale_std_ppm", "required"});
  const std::string given = WriteTempFile(
      "given.yaml", "imu_noise:\n  gyro_arw_deg_sqrt_h: 0.1\n  accel_vrw_m_s_sqrt_h: 0.1\n"
                    "  gyro_bias_std_deg_h: 1\n  accel_bias_std_ug: 100\n");
  ExpectInputError([&] { LoadGnssInsConfig(given); }, {"init.source", "nav_file"});
}

TEST(GnssInsConfig, StaticAlignmentHeading) {
  const std::string noise =
      "imu_noise:\n  gyro_arw_deg_sqrt_h: 0.1\n  accel_vrw_m_s_sqrt_h: 0.1\n"
      "  gyro_bias_std_deg_h: 1\n  accel_bias_std_ug: 100\n";
  const InitConfig d;
  const GnssInsConfig plain = LoadGnssInsConfig(WriteTempFile("p.yaml", noise + "init: {source: static}\n"));
  EXPECT_EQ(plain.init.heading, InitConfig::Heading::kAuto);  // today's behaviour
  const GnssInsConfig search = LoadGnssInsConfig(WriteTempFile(
      "s.yaml", noise + "init: {source: static, heading: search, heading_hypotheses: 12, heading_search_s: 20}\n"));
  EXPECT_EQ(search.init.heading, InitConfig::Heading::kSearch);
  EXPECT_EQ(search.init.heading_hypotheses, 12);
  EXPECT_EQ(search.init.heading_search_s, 20.0);
  const GnssInsConfig defaults =
      LoadGnssInsConfig(WriteTempFile("d.yaml", noise + "init: {source: static, heading: search}\n"));
  EXPECT_EQ(defaults.init.heading_hypotheses, d.heading_hypotheses);
  EXPECT_EQ(defaults.init.heading_search_s, d.heading_search_s);
  EXPECT_EQ(LoadGnssInsConfig(WriteTempFile("g.yaml", noise + "init: {source: static, heading: gyrocompass}\n"))
                .init.heading,
            InitConfig::Heading::kGyrocompass);
  const std::string bad = WriteTempFile("b.yaml", noise + "init: {source: static, heading: north}\n");
  ExpectInputError([&] { LoadGnssInsConfig(bad); }, {"line 6", "init.heading", "north"});
  const std::string mag = WriteTempFile("m.yaml", noise + "init: {source: static, heading: magnetometer}\n");
  ExpectInputError([&] { LoadGnssInsConfig(mag); }, {"init.heading", "mag.mode"});
  const std::string given = WriteTempFile(
      "gv.yaml", noise + "init: {source: given, position_deg_m: [0, 0, 0], velocity_mps: [0, 0, 0], "
                         "attitude_deg: [0, 0, 0], heading: search}\n");
  ExpectInputError([&] { LoadGnssInsConfig(given); }, {"init.heading", "source: static"});
  const std::string orphan = WriteTempFile("o.yaml", noise + "init: {source: static, heading_hypotheses: 4}\n");
  ExpectInputError([&] { LoadGnssInsConfig(orphan); }, {"init.heading_hypotheses", "heading: search"});
  const std::string one = WriteTempFile("1.yaml", noise + "init: {source: static, heading: search, heading_hypotheses: 1}\n");
  ExpectInputError([&] { LoadGnssInsConfig(one); }, {"init.heading_hypotheses"});
}

TEST(GnssInsConfig, MagnetometerNeedsItsField) {
  const std::string head =
      "imu_noise:\n  gyro_arw_deg_sqrt_h: 0.1\n  accel_vrw_m_s_sqrt_h: 0.1\n"
      "  gyro_bias_std_deg_h: 1\n  accel_bias_std_ug: 100\ninit: {source: static}\n";
  const std::string vector_mode = WriteTempFile("v.yaml", head + "mag: {mode: vector}\n");
  ExpectInputError([&] { LoadGnssInsConfig(vector_mode); }, {"mag.field", "mode: vector"});
  const std::string heading = WriteTempFile("h.yaml", head + "mag: {mode: heading}\n");
  ExpectInputError([&] { LoadGnssInsConfig(heading); }, {"mag.field", "declination_deg"});
  // field_ned_uT gives the declination D = atan2(B_E, B_N).
  const GnssInsConfig c = LoadGnssInsConfig(
      WriteTempFile("n.yaml", head + "mag: {mode: heading_2axis, field: {field_ned_uT: [20, -20, 40]}}\n"));
  EXPECT_EQ(c.mag.mode, MagConfig::Mode::kHeading2Axis);
  EXPECT_NEAR(c.mag.declination_rad, -M_PI / 4, 1e-15);
  const std::string mode = WriteTempFile("m.yaml", head + "mag: {mode: compass}\n");
  ExpectInputError([&] { LoadGnssInsConfig(mode); }, {"line 7", "mag.mode", "compass"});
}

// init.nav_file: relative to the configuration's folder; the first record (or the record
// at start_s) is the initial state.
TEST(GnssInsConfig, InitialStateFromNavFile) {
  const std::string dir = MakeTempDir();
  WriteFile(dir + "/init.nav",
            "2200 100.0 30.0 114.0 20.0 1.0 2.0 0.5 0.5 -1.0 185.0\n"
            "2200 101.0 30.1 114.1 21.0 1.0 2.0 0.5 0.5 -1.0 186.0\n");
  const std::string yaml = "imu_noise:\n  gyro_arw_deg_sqrt_h: 0.1\n  accel_vrw_m_s_sqrt_h: 0.1\n"
                           "  gyro_bias_std_deg_h: 1\n  accel_bias_std_ug: 100\n"
                           "init: {source: given, nav_file: init.nav}\n";
  const GnssInsConfig c = LoadGnssInsConfig(WriteFile(dir + "/c.yaml", yaml));
  ASSERT_TRUE(c.init.state.has_value());
  EXPECT_EQ(c.init.state->nav.t_s, 100.0);
  EXPECT_EQ(c.init.state->nav.gps_week, 2200);
  EXPECT_NEAR(c.init.state->nav.lat_rad, 30.0 * kDegToRad, kRel);
  EXPECT_NEAR(EulerFromQuat(c.init.state->nav.q_n_b)[2], WrapPi(185.0 * kDegToRad), 1e-12);
  const GnssInsConfig at = LoadGnssInsConfig(WriteFile(dir + "/c2.yaml", yaml + "start_s: 101\n"));
  EXPECT_EQ(at.init.state->nav.t_s, 101.0);
  EXPECT_EQ(at.init.state->nav.h_m, 21.0);
}

// A KF-GINS configuration in KF-GINS' own layout and units.
/// `text` with the first `from` replaced by `to`.
std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

const char* const kKfgins = R"(# KF-GINS configuration file
imupath: "./no-such-imu.txt"
gnsspath: "./no-such-gnss.txt"
outputpath: "./out"
imudatalen: 7
imudatarate: 200
starttime: 456300
endtime: -1
initpos: [ 30.4447873701, 114.4718632047, 20.899 ]
initvel: [ 0.0, 0.0, 0.0 ]
initatt: [ 0.85421502, -2.03480295, 185.70235133 ]
initgyrbias: [ 0, 0, 36 ]    # [deg/h]
initaccbias: [ 0, 100, 0 ]    # [mGal]
initgyrscale: [ 0, 0, 0 ]   # [ppm]
initaccscale: [ 0, 0, 0 ]   # [ppm]
initposstd: [ 0.005, 0.004, 0.008 ]
initvelstd: [ 0.003, 0.004, 0.004 ]
initattstd: [ 0.003, 0.003, 0.023 ]
imunoise:
  arw: [0.003, 0.003, 0.003]          # [deg/sqrt(hr)]
  vrw: [0.03, 0.03, 0.03]          # [m/s/sqrt(hr)]
  gbstd: [0.027, 0.027, 0.027]        # [deg/hr]
  abstd: [15.0, 15.0, 15.0]     # [mGal]
  gsstd: [300.0, 300.0, 300.0]  # [ppm]
  asstd: [300.0, 300.0, 300.0]  # [ppm]
  corrtime: 4.0                    # [hr]
antlever:  [ 0.136, -0.301, -0.184 ]
)";

TEST(KfginsConfig, ReadsUnitsOfKfgins) {
  const GnssInsConfig c = LoadKfginsConfig(WriteTempFile("kf.yaml", kKfgins));
  EXPECT_EQ(c.imu_path, "./no-such-imu.txt");
  EXPECT_EQ(c.gnss_path, "./no-such-gnss.txt");
  EXPECT_EQ(c.output_path, "./out");
  EXPECT_EQ(c.start_time_s, 456300.0);
  EXPECT_TRUE(std::isinf(c.end_time_s));
  ASSERT_TRUE(c.init.state.has_value());
  EXPECT_EQ(c.init.source, InitConfig::Source::kGiven);
  EXPECT_EQ(c.init.state->nav.t_s, 456300.0);
  EXPECT_NEAR(c.init.state->nav.lat_rad, 30.4447873701 * kDegToRad, kRel);
  EXPECT_EQ(c.init.state->nav.h_m, 20.899);
  EXPECT_NEAR(EulerFromQuat(c.init.state->nav.q_n_b)[2], WrapPi(185.70235133 * kDegToRad), 1e-12);
  // deg/sqrt(h) -> rad/sqrt(s): / 60; m/s/sqrt(h) -> m/s/sqrt(s): / 60; mGal = 1e-5 m/s^2.
  EXPECT_NEAR(c.imu_noise.gyro_arw_rad_per_sqrt_s, 0.003 * kDegToRad / 60.0, 1e-20);
  EXPECT_NEAR(c.imu_noise.accel_vrw_mps_per_sqrt_s, 0.03 / 60.0, 1e-18);
  EXPECT_NEAR(c.imu_noise.gyro_bias_std_radps, 0.027 * kDegToRad / 3600.0, 1e-20);
  EXPECT_NEAR(c.imu_noise.accel_bias_std_mps2, 15e-5, 1e-18);
  EXPECT_NEAR(c.imu_noise.gyro_scale_std, 300e-6, 1e-18);
  EXPECT_EQ(c.imu_noise.correlation_time_s, 4.0 * 3600.0);
  EXPECT_TRUE(c.filter.scale_factors);  // KF-GINS estimates 21 states
  EXPECT_NEAR(c.init.imu_errors.bg_radps.z(), 36.0 * kDegToRad / 3600.0, kRel);
  EXPECT_NEAR(c.init.imu_errors.ba_mps2.y(), 100e-5, 1e-18);
  EXPECT_EQ(c.init.std.pos_ned_m, Eigen::Vector3d(0.005, 0.004, 0.008));
  EXPECT_NEAR(c.init.std.att_rad.z(), 0.023 * kDegToRad, 1e-18);
  EXPECT_EQ(c.init.std.bg_radps, Eigen::Vector3d::Zero());  // absent: the imunoise value
  EXPECT_EQ(c.installation.antenna_lever_arm_b_m, Eigen::Vector3d(0.136, -0.301, -0.184));
  EXPECT_EQ(c.installation.imu_mounting_rpy_rad, Eigen::Vector3d::Zero());
  EXPECT_EQ(c.mag.mode, MagConfig::Mode::kOff);
}

TEST(KfginsConfig, ExtraKeysAreListedInAWarning) {
  const std::string path = WriteTempFile(
      "kf.yaml", std::string(kKfgins) + "odo: true\nodonoise: [0.1]\nendtime2: 3\n");
  ::testing::internal::CaptureStderr();
  const GnssInsConfig c = LoadKfginsConfig(path);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("odo (line 28)"), std::string::npos) << err;
  EXPECT_NE(err.find("odonoise (line 29)"), std::string::npos) << err;
  EXPECT_NE(err.find("endtime2"), std::string::npos) << err;
  EXPECT_EQ(c.start_time_s, 456300.0);
}

// An OB_GINS configuration (its keys and units as OB_GINS writes them).
const char* const kObgins = R"(imufile: "./imu_odo.txt"
gnssfile: "./GNSS_RTK.pos"
outputpath: "./ob_out"
windows: 20
starttime: 357900
endtime: 359090
initvel: [ 0, 0, 0 ]
initatt: [ 0.5, -1.0, 185.0 ]
initgb: [ 0, 0, 36 ]
initab: [ 0, 100, 0 ]
imudatalen: 8
imudatarate: 200
isearth: true
antlever: [ -0.073, 0.302, 0.087 ]
odolever: [ -0.522, -0.47, 1.797 ]
bodyangle: [ 0, -0.2, 1.2 ]
odometer:
    isuseodo: true
    std: [ 0.05, 0.1, 0.2 ]
    srw: 100
imumodel:
    arw: 0.24
    vrw: 0.24
    gbstd: 50.0
    abstd: 250.0
    corrtime: 1.0
isuseoutage: true
outagetime: 358000
outagelen: 60
outageperiod: 180
gnssthreshold: 20.0
)";

TEST(ObginsConfig, ReadsUnitsOfObgins) {
  ::testing::internal::CaptureStderr();
  const GnssInsConfig c = LoadObginsConfig(WriteTempFile("ob.yaml", kObgins));
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("windows (line 4)"), std::string::npos) << err;
  EXPECT_NE(err.find("gnssthreshold (line 31)"), std::string::npos) << err;
  EXPECT_EQ(c.imu_path, "./imu_odo.txt");
  EXPECT_EQ(c.start_time_s, 357900.0);
  EXPECT_EQ(c.end_time_s, 359090.0);
  ASSERT_TRUE(c.init.state.has_value());
  EXPECT_TRUE(c.init.position_from_gnss);  // OB_GINS takes the position from GNSS
  EXPECT_NEAR(EulerFromQuat(c.init.state->nav.q_n_b)[1], -1.0 * kDegToRad, 1e-12);
  EXPECT_NEAR(c.init.imu_errors.bg_radps.z(), 36.0 * kDegToRad / 3600.0, kRel);
  EXPECT_NEAR(c.init.imu_errors.ba_mps2.y(), 100e-5, 1e-18);
  EXPECT_NEAR(c.imu_noise.gyro_arw_rad_per_sqrt_s, 0.24 * kDegToRad / 60.0, 1e-20);
  EXPECT_NEAR(c.imu_noise.accel_bias_std_mps2, 250e-5, 1e-18);
  EXPECT_EQ(c.imu_noise.correlation_time_s, 3600.0);
  EXPECT_FALSE(c.filter.scale_factors);
  EXPECT_EQ(c.installation.antenna_lever_arm_b_m, Eigen::Vector3d(-0.073, 0.302, 0.087));
  // The odometer is the IMU file's column, with the NHC; the vehicle from odolever/bodyangle.
  EXPECT_EQ(c.odometer.file, "./imu_odo.txt");
  EXPECT_EQ(c.odometer.std_mps, 0.05);
  EXPECT_NEAR(c.odometer.scale_std, 100e-6, 1e-18);
  EXPECT_TRUE(c.nhc.enabled);
  EXPECT_EQ(c.nhc.std_mps, 0.2);
  EXPECT_EQ(c.vehicle.lever_arm_b_m, Eigen::Vector3d(-0.522, -0.47, 1.797));
  EXPECT_NEAR(c.vehicle.mounting_rpy_rad.z(), 1.2 * kDegToRad, 1e-15);
  // Outages: OB_GINS' GPS time of the first one, counted from the start here.
  EXPECT_EQ(c.outages.start_s, 100.0);
  EXPECT_EQ(c.outages.len_s, 60.0);
  EXPECT_EQ(c.outages.period_s, 180.0);
}

TEST(ObginsConfig, BadValues) {
  const std::string seven = WriteTempFile("seven.yaml", Replace(kObgins, "imudatalen: 8", "imudatalen: 7"));
  ExpectInputError([&] { LoadObginsConfig(seven); }, {seven, "imudatalen", "odometer column"});
  const std::string no_model = WriteTempFile("no_model.yaml", Replace(kObgins, "    corrtime: 1.0", ""));
  ExpectInputError([&] { LoadObginsConfig(no_model); }, {no_model, "imumodel.corrtime", "required"});
  const std::string zero_std =
      WriteTempFile("zero_std.yaml", Replace(kObgins, "std: [ 0.05, 0.1, 0.2 ]", "std: [ 0, 0.1, 0.2 ]"));
  ExpectInputError([&] { LoadObginsConfig(zero_std); }, {zero_std, "odometer.std", "> 0"});
}

TEST(KfginsConfig, BadValues) {
  std::string zero = kKfgins;
  zero = Replace(zero, "initposstd: [ 0.005", "initposstd: [ 0.000");
  const std::string z = WriteTempFile("zero.yaml", zero);
  ExpectInputError([&] { LoadKfginsConfig(z); }, {z, "line 16", "initposstd", "> 0"});
  std::string missing = kKfgins;
  missing = Replace(missing, "  corrtime", "  #corrtime");
  const std::string m = WriteTempFile("missing.yaml", missing);
  ExpectInputError([&] { LoadKfginsConfig(m); }, {m, "imunoise.corrtime", "required"});
  std::string negative = kKfgins;
  negative = Replace(negative, "arw: [0.003", "arw: [-.003");
  const std::string n = WriteTempFile("neg.yaml", negative);
  ExpectInputError([&] { LoadKfginsConfig(n); }, {n, "line 20", "imunoise.arw"});
}

TEST(KfginsConfig, RepeatedKeyNamesFileLineAndKey) {
  const std::string top = WriteTempFile("top.yaml", std::string(kKfgins) + "starttime: 1\n");
  ExpectInputError([&] { LoadKfginsConfig(top); }, {top, "line 28", "field 'starttime'", "repeated"});
  const std::string nested = WriteTempFile(
      "nested.yaml", Replace(kKfgins, "  corrtime: 4.0", "  corrtime: 4.0\n  arw: [1, 1, 1]"));
  ExpectInputError([&] { LoadKfginsConfig(nested); },
                   {nested, "line 27", "field 'imunoise.arw'", "repeated"});
}

TEST(KfginsConfig, ZeroScaleStdTurnsScaleFactorsOff) {
  std::string text = kKfgins;
  text = Replace(text, "gsstd: [300.0, 300.0, 300.0]", "gsstd: [0.0, 0.0, 0.0]");
  text = Replace(text, "asstd: [300.0, 300.0, 300.0]", "asstd: [0.0, 0.0, 0.0]");
  const GnssInsConfig c = LoadKfginsConfig(WriteTempFile("kf.yaml", text));
  EXPECT_FALSE(c.filter.scale_factors);
}

TEST(KfginsConfig, DifferentAxesTakeTheLargestWithAWarning) {
  std::string text = kKfgins;
  text = Replace(text, "gbstd: [0.027, 0.027, 0.027]", "gbstd: [0.027, 0.05, 0.027]");
  ::testing::internal::CaptureStderr();
  const GnssInsConfig c = LoadKfginsConfig(WriteTempFile("kf.yaml", text));
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NEAR(c.imu_noise.gyro_bias_std_radps, 0.05 * kDegToRad / 3600.0, 1e-20);
  EXPECT_NE(err.find("imunoise.gbstd"), std::string::npos) << err;
}

// imudatarate is only cross-checked against the IMU file (navtwin takes every interval
// from the time tags): a 100 Hz file with imudatarate 200 gives a warning.
TEST(KfginsConfig, DataRateCrossCheckedAgainstTheImuFile) {
  const std::string dir = MakeTempDir();
  std::string imu;
  for (int k = 1; k <= 50; ++k) imu += std::to_string(456300.0 + 0.01 * k) + " 0 0 0 0 0 0.098\n";
  WriteFile(dir + "/imu.txt", imu);
  std::string text = kKfgins;
  text = Replace(text, "./no-such-imu.txt", dir + "/imu.txt");
  ::testing::internal::CaptureStderr();
  LoadKfginsConfig(WriteFile(dir + "/kf.yaml", text));
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("imudatarate 200"), std::string::npos) << err;
  EXPECT_NE(err.find("line 6"), std::string::npos) << err;
}

}  // namespace gnss_ins_config_test
}  // namespace navtwin::gnss_ins
