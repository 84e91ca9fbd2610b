// rtklib-walk raw IMU with its RTKLIB time tags, and the converted file: synthetic
// recordings with a known clock mapping, bad input, and the real walk.
#include "core/io/rtklib_walk.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "tests/core/io/io_test_util.h"
#include "tests/test_data.h"

namespace navtwin {
namespace io_rtklib_walk_test {

using testing::ExpectInputError;
using testing::MakeTempDir;
using testing::ReadAllSamples;

void PutU32(std::string* b, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b->push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

/// A simulated recording: device clock t (ms) at 5 ms steps; the host sees sample k at
/// ((t - t0)(1 + drift) + offset + delay) ms after opening the file, delay uniform in
/// [3, 7] ms, and its tick is floored to 16 ms (a coarse Windows-like tick).
struct Recording {
  int lines = 2000;
  double drift = 50e-6;
  double offset_ms = 40.0;
  bool crlf_positions = true;               ///< tags count CRLF ends, the file is stored with LF
  std::uint32_t gpst_seconds = 1756402240;  ///< GPS week 2381, 408640 s of week
  double fraction = 0.25;
  static constexpr double kT0 = 5000.0;
  static constexpr double kTickMs = 16.0;

  double TrueMs(double device_ms) const { return (device_ms - kT0) * (1.0 + drift) + offset_ms; }

  std::string Write(const std::string& dir) const {
    std::mt19937 rng(2024);
    std::uniform_real_distribution<double> delay(3.0, 7.0);
    std::string raw = "0.007,1.011,0.038,-0.160,0.160,3326339\n";  // cut by the start
    std::string tags(60, '\0');
    std::memcpy(&tags[0], "TIMETAG RTKLIB EX 2.5.0", 23);
    PutU32(&tags, 123456);  // tick_f, unused
    PutU32(&tags, gpst_seconds);
    std::uint64_t bits;
    std::memcpy(&bits, &fraction, 8);
    for (int i = 0; i < 8; ++i) tags.push_back(static_cast<char>((bits >> (8 * i)) & 0xff));
    std::uint64_t breaks = 1;
    std::uint32_t tick = 0;
    for (int k = 0; k < lines; ++k) {
      const double t = kT0 + 5.0 * k;
      raw += "0.010,-0.020,1.000,0.500,-0.250,9.000," + std::to_string(static_cast<long>(t)) + "\n";
      ++breaks;
      tick = static_cast<std::uint32_t>(std::floor((TrueMs(t) + delay(rng)) / kTickMs) * kTickMs);
      PutU32(&tags, tick);
      PutU32(&tags, static_cast<std::uint32_t>(raw.size() + (crlf_positions ? breaks : 0)));
    }
    raw += "0.012,-0.042,";  // cut by the end: no line break
    PutU32(&tags, tick);
    PutU32(&tags, static_cast<std::uint32_t>(raw.size() + (crlf_positions ? breaks : 0)));
    const std::string path = dir + "/imu.csv";
    std::ofstream(path, std::ios::binary) << raw;
    std::ofstream(path + ".tag", std::ios::binary) << tags;
    return path;
  }
};

TEST(RtklibWalkTest, RecoversTheSimulatedClockMapping) {
  for (bool crlf : {true, false}) {
    Recording rec;
    rec.crlf_positions = crlf;
    rec.lines = crlf ? 20000 : 3000;
    const std::string path = rec.Write(MakeTempDir());
    const RtklibWalkClock c = FitRtklibWalkClock(path);
    EXPECT_EQ(c.crlf_positions, crlf);
    EXPECT_EQ(c.gps_week, 2381);
    EXPECT_NEAR(c.open_sow_s, 408640.25, 1e-9);
    EXPECT_NEAR(c.tick_period_ms, Recording::kTickMs, 1e-9);
    EXPECT_EQ(c.paired_lines, static_cast<std::size_t>(rec.lines));
    if (crlf) {
      // 100 s of receipts floored to 16 ms pin the drift to a few ppm.
      EXPECT_NEAR(c.drift, rec.drift, 5e-6);
    }
    const std::vector<ImuSample> s = ReadAllSamples(*OpenRtklibWalkImu(path));
    ASSERT_EQ(s.size(), static_cast<std::size_t>(rec.lines - 1));
    // Mapped minus true time: the simulation's 3 ms smallest delay (the mapping gives the
    // latest time consistent with the tags) plus up to ~2 ms from the finite sample of
    // delays and tick phases that shapes the envelope.
    for (std::size_t k : {std::size_t{0}, s.size() / 2, s.size() - 1}) {
      const double device_ms = Recording::kT0 + 5.0 * static_cast<double>(k + 1);
      const double truth_s = 408640.25 + rec.TrueMs(device_ms) * 1e-3;
      const double error_ms = (s[k].t_s - truth_s) * 1e3;
      EXPECT_GT(error_ms, 1.0) << k;
      EXPECT_LT(error_ms, 5.0) << k;
    }
    // Constant rates: 9 deg/s and 1 g on z, times the mapped interval.
    EXPECT_NEAR(s[5].dtheta_b_rad.z() / s[5].dt_s, 9.0 * M_PI / 180.0, 1e-12);
    EXPECT_NEAR(s[5].dv_b_mps.z() / s[5].dt_s, 9.80665, 1e-12);
  }
}

TEST(RtklibWalkTest, MalformedLinesOtherThanTheCutEndsAreErrors) {
  const std::string dir = MakeTempDir();
  Recording rec;
  rec.lines = 50;
  const std::string path = rec.Write(dir);
  std::string text;
  {
    std::ifstream in(path, std::ios::binary);
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  // Cut the fields of line 10 short (the tags then no longer match: refused first).
  std::size_t pos = 0;
  for (int k = 0; k < 9; ++k) pos = text.find('\n', pos) + 1;
  const std::size_t end = text.find('\n', pos);
  const std::string broken = text.substr(0, pos) + "0.1,0.2,0.3" + text.substr(end);
  std::ofstream(path, std::ios::binary) << broken;
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibWalkImu(path)); },
                   {"imu.csv.tag", "matches neither"});
  // With tags that match (the broken line's length kept), the line itself is reported.
  std::string same_length =
      text.substr(0, pos) + "0.1,0.2,0.3" + std::string(end - pos - 11, ' ') + text.substr(end);
  std::ofstream(path, std::ios::binary) << same_length;
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibWalkImu(path)); },
                   {path, "line 10", "expected 7 columns, found 3"});
}

TEST(RtklibWalkTest, ValuesThatOverflowInSiUnitsAreRefused) {
  const std::string dir = MakeTempDir();
  Recording rec;
  rec.lines = 50;
  const std::string path = rec.Write(dir);
  std::string text;
  {
    std::ifstream in(path, std::ios::binary);
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  // Line 10's ax "0.010" becomes "1e308" (g; the same length keeps the tags valid): inf in m/s^2.
  std::size_t pos = 0;
  for (int k = 0; k < 9; ++k) pos = text.find('\n', pos) + 1;
  std::ofstream(path, std::ios::binary) << text.substr(0, pos) + "1e308" + text.substr(pos + 5);
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibWalkImu(path)); }, {path, "line 10", "field 'ax'", "finite"});
  const std::string sf = dir + "/overflow_sf.csv";
  std::ofstream(sf) << "1756402240.9610000,0,0,1,0,0,0.5,0,0,0,0\n"
                       "1756402240.9670007,0,0,1e308,0,0,0.5,0,0,0,0\n"
                       "1756402240.9730017,0,0,1,0,0,0.5,0,0,0,0\n";
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibWalkImuSf(sf)); }, {sf, "line 2", "field 'az'", "finite"});
}

TEST(RtklibWalkTest, ConvertedFileTimesOutsideTheGpsWeeksAreRefused) {
  // A time of 1.7e17 s (a lost decimal point) is GPS week 2.9e11: its week once overflowed
  // the int subtraction of week numbers (UBSan, found by fuzz_detect_format). Times before
  // the GPS epoch (1980-01-06, 315964800 s) have negative weeks.
  const std::string dir = MakeTempDir();
  const std::string far = dir + "/far_sf.csv";
  std::ofstream(far) << "175640224096100000,0,0,1,0,0,0.5,0,0,0,0\n"
                        "1756402240.9670007,0,0,1,0,0,0.5,0,0,0,0\n";
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibWalkImuSf(far)); },
                   {far, "line 1", "field 'time'", "GPS week 290410422916"});
  const std::string early = dir + "/early_sf.csv";
  std::ofstream(early) << "1756402240.9610000,0,0,1,0,0,0.5,0,0,0,0\n"
                          "315964799.5,0,0,1,0,0,0.5,0,0,0,0\n";
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibWalkImuSf(early)); },
                   {early, "line 2", "field 'time'", "GPS week -1 outside 0..10000"});
}

TEST(RtklibWalkTest, BadTagFilesAreRefused) {
  const std::string dir = MakeTempDir();
  Recording rec;
  rec.lines = 20;
  const std::string path = rec.Write(dir);
  std::string tags;
  {
    std::ifstream in(path + ".tag", std::ios::binary);
    tags.assign(std::istreambuf_iterator<char>(in), {});
  }
  std::ofstream(path + ".tag", std::ios::binary) << tags.substr(0, tags.size() - 3);
  ExpectInputError([&] { FitRtklibWalkClock(path); }, {"imu.csv.tag", "truncated time-tag record"});
  std::string bad_magic = tags;
  bad_magic[0] = 'X';
  std::ofstream(path + ".tag", std::ios::binary) << bad_magic;
  ExpectInputError([&] { FitRtklibWalkClock(path); }, {"byte 0", "TIMETAG RTKLIB"});
  std::remove((path + ".tag").c_str());
  ExpectInputError([&] { FitRtklibWalkClock(path); }, {"imu.csv.tag", "cannot open"});
}

TEST(RtklibWalkTest, ConvertedFileTimeAndUnits) {
  const std::string dir = MakeTempDir();
  const std::string path = dir + "/imu_sf.csv";
  std::ofstream(path) << "1756402240.9610000,0,0,1,0,0,0.5,0,0,0,0\n"
                         "1756402240.9670007,0,0,1,0,0,0.5,0,0,0,0\n"
                         "1756402240.9730017,0,0,1,0,0,0.5,0,0,0,0\n";
  const std::vector<ImuSample> s = ReadAllSamples(*OpenRtklibWalkImuSf(path));
  ASSERT_EQ(s.size(), 2u);
  // Whole seconds and fraction parsed apart: the 1e-7 s digits survive.
  EXPECT_NEAR(s[0].t_s, 408640.9670007, 1e-9);
  EXPECT_NEAR(s[0].dt_s, 0.0060007, 1e-9);
  EXPECT_NEAR(s[0].dv_b_mps.z() / s[0].dt_s, 9.80665, 1e-9);
  EXPECT_NEAR(s[0].dtheta_b_rad.z() / s[0].dt_s, 0.5, 1e-9);  // rad/s as given
  const std::string bad = dir + "/bad_sf.csv";
  std::ofstream(bad) << "1756402240.9610000,0,0,1,0,0,0.5,0,0,0,0\n1756402240.9670007,0,0,1,0,0\n";
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibWalkImuSf(bad)); },
                   {"line 2", "expected 11 columns, found 6"});
}

TEST(RtklibWalkRealDataTest, RawImuWithTagsLoads) {
  const std::string path = testing::DataPath("rtklib-walk/imu_1730.csv");
  NAVTWIN_REQUIRE_DATA(path);
  const RtklibWalkClock c = FitRtklibWalkClock(path);
  EXPECT_TRUE(c.crlf_positions);  // the file was converted to LF after recording
  EXPECT_EQ(c.gps_week, 2381);
  EXPECT_NEAR(c.open_sow_s, 408640.961, 1e-6);
  EXPECT_EQ(c.paired_lines, 20455u);         // every complete line has a receipt tick
  EXPECT_NEAR(c.tick_period_ms, 15.6, 0.2);  // Windows' 64 Hz tick
  EXPECT_LT(std::fabs(c.drift), 100e-6);     // crystals: tens of ppm
  const std::vector<ImuSample> s = ReadAllSamples(*OpenRtklibWalkImu(path));
  // 20457 lines: a cut first, 20455 complete, a cut last; the first complete one only
  // starts the series.
  ASSERT_EQ(s.size(), 20454u);
  std::vector<double> dt;
  for (const ImuSample& x : s) dt.push_back(x.dt_s);
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  const double median_rate = 1.0 / dt[dt.size() / 2];
  const double mean_rate =
      static_cast<double>(s.size()) / (s.back().t_s - s.front().t_s + s.front().dt_s);
  // Device ticks step 6 ms (166.7 Hz) most of the time, and 7-9 ms otherwise: mean 152.4 Hz
  // (not the 100 Hz of the README). Tolerances: the 14 ppm drift and rounding.
  EXPECT_NEAR(median_rate, 166.66, 0.05);
  EXPECT_NEAR(mean_rate, 152.4, 0.1);
  EXPECT_NEAR(s.front().t_s, 408640.994, 0.001);
}

TEST(RtklibWalkRealDataTest, ConvertedFileTimeScaleAgainstTheTags) {
  const std::string raw_path = testing::DataPath("rtklib-walk/imu_1730.csv");
  const std::string sf_path = testing::DataPath("rtklib-walk/imu_1730_sf.csv");
  NAVTWIN_REQUIRE_DATA(sf_path);
  NAVTWIN_REQUIRE_DATA(raw_path);
  const std::vector<ImuSample> sf = ReadAllSamples(*OpenRtklibWalkImuSf(sf_path));
  const std::vector<ImuSample> raw = ReadAllSamples(*OpenRtklibWalkImu(raw_path));
  ASSERT_EQ(sf.size(), 20454u);  // one row per complete raw line
  ASSERT_EQ(sf.size(), raw.size());
  // The converted time starts at the tag file's open time and ends at the last tag tick
  // (134.271 s later): the device clock stretched between those two host times.
  EXPECT_NEAR(sf.front().t_s - sf.front().dt_s, 408640.961, 1e-6);
  EXPECT_NEAR(sf.back().t_s, 408640.961 + 134.271, 1e-6);
  // Against the envelope mapping: the converted times are 27 ms earlier at the start and
  // 10 ms earlier at the end (1 ms: the tick period estimate and rounding).
  EXPECT_NEAR((raw.front().t_s - sf.front().t_s) * 1e3, 27.0, 1.0);
  EXPECT_NEAR((raw.back().t_s - sf.back().t_s) * 1e3, 9.9, 1.0);
}

}  // namespace io_rtklib_walk_test
}  // namespace navtwin
