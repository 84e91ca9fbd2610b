// LoadInputs: installation, time cut, IMU gap bridging, outage injection and the bad-input
// checks (each an InputError naming the file and the line or time).
#include "problems/gnss_ins/inputs.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "tests/core/io/io_test_util.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_inputs_test {

using navtwin::testing::ExpectInputError;
using navtwin::testing::MakeTempDir;
using navtwin::testing::WriteFile;

std::string Fmt(const char* format, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, a);
  return buf;
}

/// KF-GINS IMU lines at 100 Hz, t = 0.01 .. n/100 s, skipping the samples in `missing`
/// (their increments are lost, as when a logger drops them). Increments: dtheta =
/// (0.001, 0, 0) rad, dv = (0.01, 0, -0.098) m/s per sample.
std::string ImuText(int n, const std::set<int>& missing = {}) {
  std::string text;
  for (int k = 1; k <= n; ++k) {
    if (missing.count(k)) continue;
    text += Fmt("%.2f", 0.01 * k) + " 0.001 0 0 0.01 0 -0.098\n";
  }
  return text;
}

/// KF-GINS GNSS lines (7 columns) at the given times.
std::string GnssText(const std::vector<double>& times) {
  std::string text;
  for (double t : times) text += Fmt("%.3f", t) + " 30.0 114.0 20.0 1.0 1.0 2.0\n";
  return text;
}

struct Files {
  std::string dir;
  InputPaths paths;
};

Files Write(const std::string& imu, const std::string& gnss) {
  Files f;
  f.dir = MakeTempDir();
  f.paths.imu = WriteFile(f.dir + "/imu.txt", imu);
  f.paths.gnss = WriteFile(f.dir + "/gnss.txt", gnss);
  return f;
}

std::vector<double> Times(double t0, double t1, double dt) {
  std::vector<double> t;
  for (int k = 0; t0 + k * dt <= t1 + 1e-9; ++k) t.push_back(t0 + k * dt);
  return t;
}

TEST(LoadInputs, AppliesMountingAndTimeOffset) {
  const Files f = Write(ImuText(200), GnssText(Times(0.0, 3.0, 0.5)));
  GnssInsConfig c;
  c.installation.imu_mounting_rpy_rad = Eigen::Vector3d(0, 0, 90 * kDegToRad);
  c.installation.imu_time_offset_s = 0.5;
  const Inputs in = LoadInputs(f.paths, c);
  ASSERT_EQ(in.imu.size(), 200u);
  // v_b = Rz(90 deg) v_imu: the IMU x axis is the body y axis. 1e-18: rounding of cos(pi/2).
  EXPECT_NEAR(in.imu[5].dtheta_b_rad.x(), 0.0, 1e-18);
  EXPECT_NEAR(in.imu[5].dtheta_b_rad.y(), 0.001, 1e-18);
  EXPECT_NEAR(in.imu[5].dv_b_mps.y(), 0.01, 1e-17);
  EXPECT_NEAR(in.imu[5].dv_b_mps.z(), -0.098, 1e-17);
  EXPECT_NEAR(in.imu[0].t_s, 0.51, 1e-12);  // time tags shifted by the offset
  EXPECT_NEAR(in.imu.back().t_s, 2.5, 1e-12);
  // GNSS cut to the IMU span [0.5, 2.5] s.
  ASSERT_EQ(in.gnss.size(), 5u);
  EXPECT_EQ(in.gnss.front().t_s, 0.5);
  EXPECT_EQ(in.gnss.back().t_s, 2.5);
  EXPECT_EQ(in.imu.bridged_gaps(), 0u);
}

TEST(LoadInputs, CutsToStartAndEnd) {
  const Files f = Write(ImuText(300), GnssText(Times(0.0, 3.0, 0.2)));
  GnssInsConfig c;
  c.start_time_s = 1.0;
  c.end_time_s = 2.0;
  const Inputs in = LoadInputs(f.paths, c);
  // Samples whose interval (t - dt, t] lies inside [1, 2]: t = 1.01 .. 2.00.
  ASSERT_EQ(in.imu.size(), 100u);
  EXPECT_NEAR(in.imu.front().t_s, 1.01, 1e-12);
  EXPECT_NEAR(in.imu.back().t_s, 2.0, 1e-12);
  EXPECT_NEAR(in.gnss.front().t_s, 1.0, 1e-12);
  EXPECT_NEAR(in.gnss.back().t_s, 2.0, 1e-12);
}

// A gap of 3 nominal intervals (2 samples missing) is bridged: the sample after it is split
// into 3 nominal intervals with a third of its increments each.
TEST(LoadInputs, BridgesShortImuGaps) {
  const Files f = Write(ImuText(200, {50, 51}), GnssText({0.5, 1.0}));
  GnssInsConfig c;
  c.filter.max_bridge_gap_s = 0.05;
  const Inputs in = LoadInputs(f.paths, c);
  EXPECT_EQ(in.imu.bridged_gaps(), 1u);
  ASSERT_EQ(in.imu.size(), 200u);
  for (std::size_t k = 0; k < in.imu.size(); ++k) {
    EXPECT_NEAR(in.imu[k].dt_s, 0.01, 1e-12) << k;
    if (k > 0) {
      EXPECT_NEAR(in.imu[k].t_s - in.imu[k - 1].t_s, 0.01, 1e-12) << k;
    }
  }
  // Samples 50..52 (indices 49..51) share the one recorded increment.
  EXPECT_NEAR(in.imu[49].dtheta_b_rad.x(), 0.001 / 3, 1e-18);
  EXPECT_NEAR(in.imu[51].dv_b_mps.z(), -0.098 / 3, 1e-17);
  EXPECT_NEAR(in.imu[52].dtheta_b_rad.x(), 0.001, 1e-18);
}

TEST(LoadInputs, LongImuGapNamesFileAndTime) {
  const Files f = Write(ImuText(200, {100, 101, 102, 103, 104, 105, 106, 107, 108, 109, 110}),
                        GnssText({0.5, 1.0}));
  GnssInsConfig c;
  c.filter.max_bridge_gap_s = 0.1;
  ExpectInputError([&] { LoadInputs(f.paths, c); },
                   {f.paths.imu, "IMU gap of 0.12 s", "t = 0.99 s", "t = 1.11 s", "max_bridge_gap_s"});
}

TEST(LoadInputs, GnssOutOfOrderOrDuplicatedNamesFileAndLine) {
  const Files dup = Write(ImuText(200), GnssText({0.5, 1.0, 1.0, 1.5}));
  ExpectInputError([&] { LoadInputs(dup.paths, GnssInsConfig()); }, {dup.paths.gnss, "line 3"});
  const Files order = Write(ImuText(200), GnssText({0.5, 1.0, 0.8, 1.5}));
  ExpectInputError([&] { LoadInputs(order.paths, GnssInsConfig()); }, {order.paths.gnss, "line 3"});
}

TEST(LoadInputs, NanAndBadSigmaNameFileAndLine) {
  std::string imu = ImuText(200);
  imu.replace(imu.find("0.30 0.001"), 10, "0.30 nan");
  const Files nan_imu = Write(imu, GnssText({0.5, 1.0}));
  ExpectInputError([&] { LoadInputs(nan_imu.paths, GnssInsConfig()); }, {nan_imu.paths.imu, "line 30"});
  const Files zero_sigma = Write(ImuText(200), "0.5 30.0 114.0 20.0 1.0 1.0 2.0\n"
                                               "1.0 30.0 114.0 20.0 0.0 1.0 2.0\n");
  ExpectInputError([&] { LoadInputs(zero_sigma.paths, GnssInsConfig()); },
                   {zero_sigma.paths.gnss, "line 2", "sigma_n"});
  const Files nan_gnss = Write(ImuText(200), "0.5 30.0 114.0 20.0 1.0 1.0 2.0\n"
                                             "1.0 30.0 nan 20.0 1.0 1.0 2.0\n");
  ExpectInputError([&] { LoadInputs(nan_gnss.paths, GnssInsConfig()); }, {nan_gnss.paths.gnss, "line 2"});
}

TEST(LoadInputs, NoGnssInsideTheImuSpan) {
  // GNSS in GPS seconds of week, IMU in relative time: a common mistake.
  const Files f = Write(ImuText(200), GnssText({456300.0, 456301.0}));
  ExpectInputError([&] { LoadInputs(f.paths, GnssInsConfig()); },
                   {f.paths.gnss, "no GNSS epoch inside the IMU span"});
}

// Outages relative to the first IMU time (0 here): [0.5 + 1.5 k, 0.5 + 1.5 k + 0.5).
TEST(LoadInputs, InjectsOutages) {
  const Files f = Write(ImuText(400), GnssText(Times(0.0, 4.0, 0.1)));
  GnssInsConfig c;
  c.outages.start_s = 0.5;
  c.outages.len_s = 0.5;
  c.outages.period_s = 1.5;
  const Inputs in = LoadInputs(f.paths, c);
  ASSERT_EQ(in.outages.size(), 3u);  // starting at 0.5, 2.0, 3.5 (< the IMU end, 4.0)
  EXPECT_NEAR(in.outages[1].first, 2.0, 1e-12);
  EXPECT_NEAR(in.outages[1].second, 2.5, 1e-12);
  // Removed: 0.5..0.9, 2.0..2.4, 3.5..3.9 (5 epochs each; the end is excluded).
  EXPECT_EQ(in.gnss_removed_by_outages, 15u);
  EXPECT_EQ(in.gnss.size(), 41u - 15u);
  for (const GnssSample& g : in.gnss) {
    for (const auto& o : in.outages) {
      EXPECT_FALSE(g.t_s >= o.first && g.t_s < o.second) << g.t_s;
    }
  }
}

TEST(LoadInputs, BarometerAltitudeFromPressure) {
  Files f = Write(ImuText(200), GnssText({0.5, 1.0}));
  f.paths.baro = WriteFile(f.dir + "/baro.csv",
                           "t_s,pressure_pa\n0.5,101325\n1.0,89874.6\n");
  f.paths.mag = WriteFile(f.dir + "/mag.csv", "t_s,mx_uT,my_uT,mz_uT\n0.5,20,1,40\n5.0,20,1,40\n");
  const Inputs in = LoadInputs(f.paths, GnssInsConfig());
  ASSERT_EQ(in.baro.size(), 2u);
  EXPECT_NEAR(in.baro[0].altitude_m, 0.0, 1e-9);
  // ISA: 89874.6 Pa at 1000 m geopotential (tables give 89874.6; 0.1 m covers the rounding).
  EXPECT_NEAR(in.baro[1].altitude_m, 1000.0, 0.1);
  ASSERT_EQ(in.mag.size(), 1u);  // the sample at 5 s is after the IMU span
}

// A streamed IMU record: until a pass has reached its end the other records run on past
// it; after CutToImuEnd the inputs are those of the record in memory.
TEST(LoadInputs, StreamedRecordCutAfterItsFirstPass) {
  Files f = Write(ImuText(400, {200, 201}), GnssText(Times(0.0, 6.0, 0.1)));
  f.paths.mag = WriteFile(f.dir + "/mag.csv", "t_s,mx_uT,my_uT,mz_uT\n0.5,20,1,40\n5.0,20,1,40\n");
  GnssInsConfig c;
  c.filter.max_bridge_gap_s = 0.05;
  c.outages.start_s = 0.5;
  c.outages.len_s = 0.5;
  c.outages.period_s = 1.5;
  const Inputs memory = LoadInputs(f.paths, c);
  Inputs streamed = LoadInputs(f.paths, c, ImuStorage::kStreamed);
  ASSERT_TRUE(streamed.imu.streamed());
  EXPECT_FALSE(streamed.imu.end_known());
  EXPECT_EQ(streamed.gnss.size() + streamed.gnss_removed.size(), 61u);  // every epoch after the IMU start
  EXPECT_EQ(streamed.mag.size(), 2u);
  const std::unique_ptr<ImuReader> pass = streamed.imu.Read();
  const std::vector<ImuSample> samples = ReadAll(*pass);
  CutToImuEnd(&streamed);
  ASSERT_EQ(samples.size(), memory.imu.size());
  for (std::size_t k = 0; k < samples.size(); ++k) {
    ASSERT_EQ(samples[k].t_s, memory.imu[k].t_s) << k;
    ASSERT_EQ(samples[k].dtheta_b_rad, memory.imu[k].dtheta_b_rad) << k;
  }
  EXPECT_EQ(streamed.imu.bridged_gaps(), 1u);
  EXPECT_EQ(streamed.imu.bridged_gaps(), memory.imu.bridged_gaps());
  EXPECT_EQ(streamed.gnss.size(), memory.gnss.size());
  EXPECT_EQ(streamed.gnss_removed.size(), memory.gnss_removed.size());
  EXPECT_EQ(streamed.gnss_removed_by_outages, memory.gnss_removed_by_outages);
  EXPECT_EQ(streamed.outages, memory.outages);
  EXPECT_EQ(streamed.mag.size(), 1u);
  EXPECT_EQ(memory.mag.size(), 1u);
}

TEST(LoadInputs, StreamedRecordWithTheGnssAfterItsEnd) {
  const Files f = Write(ImuText(200), GnssText({2.5, 3.0}));
  Inputs in = LoadInputs(f.paths, GnssInsConfig(), ImuStorage::kStreamed);  // the IMU end is not known yet
  const std::unique_ptr<ImuReader> pass = in.imu.Read();
  EXPECT_EQ(ReadAll(*pass).size(), 200u);
  ExpectInputError([&] { CutToImuEnd(&in); }, {f.paths.gnss, "no GNSS epoch inside the IMU span"});
}

}  // namespace gnss_ins_inputs_test
}  // namespace navtwin::gnss_ins
