// RTKLIB .pos solution files: header-driven columns, time systems, refusals, real file.
#include "core/io/rtklib_pos.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/rotation.h"
#include "tests/core/io/io_test_util.h"
#include "tests/test_data.h"

namespace navtwin {
namespace io_rtklib_pos_test {

using testing::ExpectInputError;
using testing::ReadAllSamples;
using testing::WriteTempFile;

const char kHeader[] =
    "% program   : RTKLIB ver.demo5\n"
    "%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   "
    "sde(m)   sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio  vn(m/s)   ve(m/s)    vu(m/s)  "
    "  sdvn      sdve     sdvu       sdvne    sdveu      sdvun\n";
const char kTail[] =
    "   1601.4350   1  25   0.0100   0.0200   0.0300   0.0000   0.0000   "
    "0.0000   0.00    0.0   0.1 0.2 0.3  0.04 0.05 0.06 0 0 0\n";

TEST(RtklibPosTest, CalendarTimeLlhAndVelocity) {
  const std::string path = WriteTempFile(
      "good.pos", std::string(kHeader) + "2025/08/28 17:30:39.749   40.096691600 -105.147166500" +
                      kTail + "2025/08/28 17:30:39.999   40.096691600 -105.147166500" + kTail);
  const std::vector<GnssSample> g = ReadAllSamples(*OpenRtklibPos(path));
  ASSERT_EQ(g.size(), 2u);
  // 2025-08-28 is a Thursday of GPS week 2381: 4 days + 17:30:39.749.
  EXPECT_EQ(g[0].gps_week, 2381);
  EXPECT_NEAR(g[0].t_s, 4 * 86400 + 17 * 3600 + 30 * 60 + 39.749, 1e-9);
  EXPECT_NEAR(g[1].t_s - g[0].t_s, 0.25, 1e-9);
  EXPECT_NEAR(g[0].lat_rad, 40.0966916 * kDegToRad, 1e-15);
  EXPECT_NEAR(g[0].lon_rad, -105.1471665 * kDegToRad, 1e-15);
  EXPECT_EQ(g[0].h_m, 1601.435);
  EXPECT_EQ(g[0].quality, 1);
  EXPECT_EQ(g[0].num_sats, 25);
  EXPECT_EQ(g[0].pos_std_ned_m, Eigen::Vector3d(0.01, 0.02, 0.03));
  ASSERT_TRUE(g[0].has_velocity);
  EXPECT_EQ(g[0].v_n_mps, Eigen::Vector3d(0.1, 0.2, -0.3));  // down = -up
  EXPECT_EQ(g[0].vel_std_ned_mps, Eigen::Vector3d(0.04, 0.05, 0.06));
}

TEST(RtklibPosTest, ImplausibleValuesAreRefused) {
  const std::string good = std::string(kHeader) + "2025/08/28 17:30:39.749   40.096691600 -105.147166500" + kTail;
  const std::string height = WriteTempFile(
      "height.pos", good + "2025/08/28 17:30:39.999   40.096691600 -105.147166500   1e16   1   25   0.0100   "
                           "0.0200   0.0300   0.0000   0.0000   0.0000   0.00    0.0   0.1 0.2 0.3  0.04 0.05 0.06 0 0 0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(height)); }, {height, "line 4", "field 'height'", "implausible height"});
  const std::string sigma = WriteTempFile(
      "sigma.pos", good + "2025/08/28 17:30:39.999   40.096691600 -105.147166500   1601.4   1   25   0.0100   "
                          "0.0200   1e9   0.0000   0.0000   0.0000   0.00    0.0   0.1 0.2 0.3  0.04 0.05 0.06 0 0 0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(sigma)); }, {"line 4", "field 'sdu'", "implausible standard deviation"});
  const std::string vel = WriteTempFile(
      "vel.pos", good + "2025/08/28 17:30:39.999   40.096691600 -105.147166500   1601.4   1   25   0.0100   "
                        "0.0200   0.03   0.0000   0.0000   0.0000   0.00    0.0   0.1 -1e16 0.3  0.04 0.05 0.06 0 0 0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(vel)); }, {"line 4", "field 've'", "implausible velocity"});
}

TEST(RtklibPosTest, WeekTowTimeAndNoVelocityColumns) {
  const std::string path = WriteTempFile(
      "weektow.pos",
      "%  GPST          latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   "
      "sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio\n"
      "2381 604799.500 40.1 -105.1 1601.4 5 9 1.5 1.5 3.0 0 0 0 0 0\n"
      "2382      0.500 40.1 -105.1 1601.4 5 9 1.5 1.5 3.0 0 0 0 0 0\n");
  const std::vector<GnssSample> g = ReadAllSamples(*OpenRtklibPos(path));
  ASSERT_EQ(g.size(), 2u);
  EXPECT_FALSE(g[0].has_velocity);
  // Times count from the first epoch's week, so they keep increasing across the week.
  EXPECT_EQ(g[1].gps_week, 2381);
  EXPECT_EQ(g[1].t_s, 604800.5);
  EXPECT_EQ(g[0].quality, 5);
}

TEST(RtklibPosTest, UtcNeedsTheLeapSecondsFromTheHeader) {
  const std::string utc_header =
      "%  UTC                   latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   "
      "sde(m)   sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio\n";
  const std::string line = "2025/08/28 17:30:21.749 40.1 -105.1 1601.4 1 9 0.1 0.1 0.2 0 0 0 0 0\n";
  const std::string refused = WriteTempFile("utc.pos", utc_header + line);
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(refused)); },
                   {refused, "line 1", "UTC", "leap seconds"});
  const std::string with_leap =
      WriteTempFile("utc_leap.pos", "% leap seconds: 18\n" + utc_header + line);
  const std::vector<GnssSample> g = ReadAllSamples(*OpenRtklibPos(with_leap));
  ASSERT_EQ(g.size(), 1u);
  EXPECT_NEAR(g[0].t_s, 4 * 86400 + 17 * 3600 + 30 * 60 + 39.749, 1e-9);  // UTC + 18 s
}

TEST(RtklibPosTest, LeapSecondsHeaderMustBeAPlausibleNonNegativeCount) {
  const std::string utc_header =
      "%  UTC   latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)\n";
  const std::string line = "2025/08/28 17:30:21.749 40.1 -105.1 1601.4 1 9 0.1 0.1 0.2\n";
  const std::string negative =
      WriteTempFile("negative.pos", "% leap seconds: -18\n" + utc_header + line);
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(negative)); },
                   {negative, "line 1", "field 'leap seconds'", "-18"});
  const std::string huge =
      WriteTempFile("huge.pos", "% leap seconds: 99999999999999999999\n" + utc_header + line);
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(huge)); },
                   {huge, "line 1", "field 'leap seconds'"});
}

TEST(RtklibPosTest, WeekAndTowOutsideGpsLimitsAreRefused) {
  const std::string head =
      "%  GPST   latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)\n";
  const std::string rest = " 40.1 -105.1 1601.4 1 9 0.1 0.1 0.2\n";
  const struct {
    const char* name;
    std::string time;
    const char* field;
  } cases[] = {
      {"overflow", "99999999999999 1.0", "week"},  // week x 604800 beyond int64
      {"negative_week", "-1 100.0", "week"},
      {"far_week", "10001 100.0", "week"},
      {"negative_tow", "2381 -0.5", "tow"},
      {"full_week_tow", "2381 604800.0", "tow"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path =
        WriteTempFile(std::string(c.name) + ".pos", head + "2381 100.0" + rest + c.time + rest);
    ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(path)); },
                     {path, "line 3", std::string("field '") + c.field + "'"});
  }
  // A negative first week is an error too, not "week not set yet".
  const std::string first = WriteTempFile("first.pos", head + "-5 100.0" + rest);
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(first)); }, {"line 2", "field 'week'"});
}

TEST(RtklibPosTest, ImpossibleCalendarDatesAndTimesAreRefused) {
  const std::string head =
      "%  GPST   latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)\n";
  const std::string rest = " 40.1 -105.1 1601.4 1 9 0.1 0.1 0.2\n";
  const struct {
    const char* name;
    const char* time;
    const char* field;
  } cases[] = {
      {"feb30", "2024/02/30 00:00:00.000", "date"},
      {"apr31", "2024/04/31 00:00:00.000", "date"},
      {"feb29_2023", "2023/02/29 00:00:00.000", "date"},
      {"month13", "2024/13/01 00:00:00.000", "date"},
      {"before_gps", "1979/12/31 00:00:00.000", "date"},
      {"far_year", "99999999999/01/01 00:00:00.000", "date"},
      {"hour25", "2024/03/01 25:00:00.000", "time"},
      {"minute60", "2024/03/01 10:60:00.000", "time"},
      {"second61", "2024/03/01 10:00:61.000", "time"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path =
        WriteTempFile(std::string(c.name) + ".pos", head + std::string(c.time) + rest);
    ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(path)); },
                     {path, "line 2", std::string("field '") + c.field + "'"});
  }
  // A leap day that exists is read.
  const std::string leap_day =
      WriteTempFile("leap_day.pos", head + "2024/02/29 12:00:00.000" + rest);
  EXPECT_EQ(ReadAllSamples(*OpenRtklibPos(leap_day)).size(), 1u);
}

TEST(RtklibPosTest, RefusesOtherSolutionFormats) {
  const std::string xyz = WriteTempFile(
      "xyz.pos",
      "%  GPST                   x-ecef(m)      y-ecef(m)      z-ecef(m)   Q  ns   sdx(m)   "
      "sdy(m)   sdz(m)\n2025/08/28 17:30:39.749 -1 2 3 1 9 0.1 0.1 0.1\n");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(xyz)); },
                   {"x-ecef", "latitude/longitude/height"});
  const std::string enu = WriteTempFile(
      "enu.pos",
      "%  GPST   e-baseline(m)  n-baseline(m)  u-baseline(m)   Q  ns   sde(m)   sdn(m)   "
      "sdu(m)\n2025/08/28 17:30:39.749 1 2 3 1 9 0.1 0.1 0.1\n");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(enu)); },
                   {"baseline", "latitude/longitude/height"});
  const std::string dms = WriteTempFile(
      "dms.pos",
      "%  GPST   latitude(d'\")  longitude(d'\")  height(m)   Q  ns   sdn(m)   sde(m)   "
      "sdu(m)\n2025/08/28 17:30:39.749 40 5 48.09 -105 8 49.8 1601 1 9 0.1 0.1 0.1\n");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(dms)); }, {"deg-min-sec"});
  const std::string no_header =
      WriteTempFile("noheader.pos", "2025/08/28 17:30:39.749 40 -105 1601 1 9\n");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(no_header)); }, {"column-name header"});
}

TEST(RtklibPosTest, BadLinesNameLineAndField) {
  const std::string head =
      "%  GPST   latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)\n";
  const std::string ok = "2025/08/28 17:30:39.749 40.1 -105.1 1601.4 1 9 0.1 0.1 0.2\n";
  const std::string zero = WriteTempFile(
      "zero.pos", head + ok + "2025/08/28 17:30:39.999 40.1 -105.1 1601.4 1 9 0 0.1 0.2\n");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(zero)); },
                   {"line 3", "field 'sdn'", "must be > 0"});
  const std::string back = WriteTempFile(
      "back.pos", head + ok + "2025/08/28 17:30:39.499 40.1 -105.1 1601.4 1 9 0.1 0.1 0.2\n");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(back)); }, {"line 3", "does not increase"});
  const std::string shortline = WriteTempFile(
      "short.pos", head + ok + "2025/08/28 17:30:39.999 40.1 -105.1 1601.4 1 9 0.1\n");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(shortline)); },
                   {"line 3", "expected 10 columns, found 8"});
  const std::string nan = WriteTempFile(
      "nan.pos", head + "2025/08/28 17:30:39.749 nan -105.1 1601.4 1 9 0.1 0.1 0.2\n");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(nan)); },
                   {"line 2", "field 'latitude'", "not a finite number"});
  const std::string missing = WriteTempFile(
      "missing.pos",
      "%  GPST   latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)\n" + ok);
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(missing)); },
                   {"line 1", "missing column 'sdu'"});
  const std::string header_only = WriteTempFile("header_only.pos", head);
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(header_only)); },
                   {header_only, "no solution epochs"});
  const std::string empty = WriteTempFile("empty.pos", "");
  ExpectInputError([&] { ReadAllSamples(*OpenRtklibPos(empty)); }, {empty, "column-name header"});
}

TEST(RtklibPosTest, GpsTimeHelpers) {
  EXPECT_EQ(DaysFromCivil(1970, 1, 1), 0);
  EXPECT_EQ(DaysFromCivil(1980, 1, 6) * 86400, 315964800);  // the GPS epoch in Unix-like seconds
  EXPECT_EQ(DaysFromCivil(2000, 3, 1) - DaysFromCivil(2000, 2, 28), 2);  // 2000 was a leap year
  const GpsWeekTime t = GpsTimeFromGpst1970(1756402240, 0.961);  // the rtklib-walk tag header
  EXPECT_EQ(t.week, 2381);
  EXPECT_NEAR(t.sow_s, 408640.961, 1e-9);
}

TEST(RtklibPosTest, RealWalkSolutionFile) {
  const std::string path = testing::DataPath("rtklib-walk/gnss_1730_sf.pos");
  NAVTWIN_REQUIRE_DATA(path);
  const std::vector<GnssSample> g = ReadAllSamples(*OpenRtklibPos(path));
  // 536 epochs at 4 Hz (counted with grep; every interval is 0.25 s), RTK fix or float.
  ASSERT_EQ(g.size(), 536u);
  EXPECT_EQ(g.front().gps_week, 2381);
  EXPECT_NEAR(g.front().t_s, 408639.749, 1e-6);
  EXPECT_NEAR(g.back().t_s, 408773.499, 1e-6);
  int fix = 0, flt = 0;
  for (std::size_t k = 0; k < g.size(); ++k) {
    EXPECT_TRUE(g[k].has_velocity);
    EXPECT_GT(g[k].vel_std_ned_mps.minCoeff(), 0.0);
    fix += g[k].quality == 1;
    flt += g[k].quality == 2;
    if (k > 0) {
      EXPECT_NEAR(g[k].t_s - g[k - 1].t_s, 0.25, 1e-6);  // ms-rounded times
    }
  }
  EXPECT_EQ(fix, 349);
  EXPECT_EQ(flt, 187);
  EXPECT_NEAR(g.front().lat_rad * kRadToDeg, 40.0966916, 1e-9);
}

}  // namespace io_rtklib_pos_test
}  // namespace navtwin
