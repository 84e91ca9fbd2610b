// Exports of a navigation solution (core/io/track_export.h): the RTKLIB .pos that navtwin's
// own reader reads back, UTC times across a leap second, the KML track and its sigma
// ellipses, the GPX points, and the refusals (no GPS week, a zero sigma, a bad std.csv).
#include "core/io/track_export.h"

#include <cmath>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/io/input_error.h"
#include "core/io/rtklib_pos.h"
#include "core/units.h"
#include "tests/scratch_dir.h"

namespace navtwin {
namespace core_io_track_export_test {

class TrackExportTest : public testing::ScratchDirTest {};

NavState State(double t_s, int week, double lat_deg, double lon_deg, double h_m) {
  NavState s;
  s.t_s = t_s;
  s.gps_week = week;
  s.lat_rad = lat_deg * kDegToRad;
  s.lon_rad = lon_deg * kDegToRad;
  s.h_m = h_m;
  s.v_n_mps = Eigen::Vector3d(1.25, -0.5, 0.2);
  return s;
}

std::size_t Count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::string ReadText(const std::string& path) {
  std::ifstream f(path);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

// What RTKLIB's format holds survives the trip through navtwin's reader: 1e-9 deg (the 9
// decimals written: 0.1 mm), 0.1 mm in height, 1e-5 m/s, the sigmas to their 4 / 5
// decimals, the time to the 0.1 ms written; the week carried, the epoch after the week's
// end written in the next week and read back past 604800 s (rtklib_pos.h).
TEST_F(TrackExportTest, RtklibPosRoundTripsThroughTheReader) {
  const std::string path = dir_ + "/track.pos";
  RtklibPosWriter w(path, "nav.nav");
  const std::vector<NavState> states = {State(604799.5, 2275, 40.0966918, -105.1471658, 1601.4519),
                                        State(604800.25, 2275, 40.0966925, -105.1471640, 1601.5)};
  const Eigen::Vector3d pos_std(0.012, 0.0135, 0.031), vel_std(0.004, 0.0045, 0.009);
  for (const NavState& s : states) w.Write(s, pos_std, vel_std);
  w.Commit();
  const auto reader = OpenRtklibPos(path);
  GnssSample g;
  for (const NavState& s : states) {
    ASSERT_TRUE(reader->Next(&g));
    EXPECT_EQ(g.gps_week, 2275);
    EXPECT_NEAR(g.t_s, s.t_s, 1e-4);
    EXPECT_NEAR(g.lat_rad * kRadToDeg, s.lat_rad * kRadToDeg, 1e-9);
    EXPECT_NEAR(g.lon_rad * kRadToDeg, s.lon_rad * kRadToDeg, 1e-9);
    EXPECT_NEAR(g.h_m, s.h_m, 1e-4);
    ASSERT_TRUE(g.has_velocity);
    EXPECT_LT((g.v_n_mps - s.v_n_mps).norm(), 2e-5);  // vu = -vd written, read back as v_D
    EXPECT_LT((g.pos_std_ned_m - pos_std).norm(), 1e-4);
    EXPECT_LT((g.vel_std_ned_mps - vel_std).norm(), 1e-5);
  }
  EXPECT_FALSE(reader->Next(&g));
}

TEST_F(TrackExportTest, RtklibPosRefusesWhatItCannotHold) {
  RtklibPosWriter w(dir_ + "/bad.pos", "x");
  const Eigen::Vector3d ok(0.1, 0.1, 0.1);
  EXPECT_THROW(w.Write(State(10.0, -1, 40, -105, 1600), ok, ok), std::invalid_argument);  // no week
  EXPECT_THROW(w.Write(State(10.0, 2275, 40, -105, 1600), Eigen::Vector3d(0.1, 0.0, 0.1), ok), std::invalid_argument);
  EXPECT_THROW(w.Write(State(10.0, 2275, 40, -105, 1600), ok, Eigen::Vector3d::Constant(NAN)), std::invalid_argument);
}

// GPS week 1930 starts on 2017-01-01 (13510 days after 1980-01-06); the leap second at the
// end of 2016 took GPS - UTC from 17 to 18 s: GPS 00:00:18 of that week is UTC midnight,
// GPS 00:00:16 still 2016 (UTC 23:59:59 with 17 s). Milliseconds round with a carry.
TEST(UtcIsoTimeFromGps, AppliesTheLeapSecondsOfTheDate) {
  EXPECT_EQ(UtcIsoTimeFromGps(0, 0.0), "1980-01-06T00:00:00.000Z");
  EXPECT_EQ(UtcIsoTimeFromGps(1930, 18.0), "2017-01-01T00:00:00.000Z");
  EXPECT_EQ(UtcIsoTimeFromGps(1930, 16.0), "2016-12-31T23:59:59.000Z");
  EXPECT_EQ(UtcIsoTimeFromGps(1930, 18.9996), "2017-01-01T00:00:01.000Z");
  EXPECT_EQ(UtcIsoTimeFromGps(1929, 604818.25), "2017-01-01T00:00:00.250Z");  // sow past the week
  EXPECT_THROW(UtcIsoTimeFromGps(-1, 0.0), std::invalid_argument);
}

// Three epochs with ellipses at least 1 s apart: two ellipses (t = 0 and 1.2 s, not 0.5),
// the track's three points after them; the ellipse's first point is K sigma_N north of the
// epoch (angle 0), the fourth-of-the-way point (90 deg) K sigma_E east, to the 9 decimals
// written (1e-9 deg = 0.1 mm).
TEST_F(TrackExportTest, KmlHasTheTrackAndTheSigmaEllipses) {
  const std::string path = dir_ + "/track.kml";
  KmlWriter w(path, "run <1> & co", 3.0, 1.0);
  const Eigen::Vector3d std(2.0, 1.0, 4.0);
  w.Write(State(0.0, -1, 45.0, 10.0, 100.0), &std);
  w.Write(State(0.5, -1, 45.00001, 10.00001, 100.0), &std);
  w.Write(State(1.2, -1, 45.00002, 10.00002, 100.0), &std);
  w.Commit();
  EXPECT_EQ(w.ellipses(), 2u);
  const std::string kml = ReadText(path);
  EXPECT_EQ(Count(kml, "<Polygon>"), 2u);
  EXPECT_EQ(Count(kml, "<LineString>"), 1u);
  EXPECT_NE(kml.find("run &lt;1&gt; &amp; co"), std::string::npos);
  EXPECT_LT(kml.find("<Polygon>"), kml.find("<LineString>"));
  const std::size_t first = kml.find("<coordinates>") + std::string("<coordinates>").size();
  double lon_deg = 0.0, lat_deg = 0.0;
  ASSERT_EQ(std::sscanf(kml.c_str() + first, "%lf,%lf", &lon_deg, &lat_deg), 2);
  const double lat = 45.0 * kDegToRad;
  EXPECT_NEAR(lon_deg, 10.0, 1e-9);
  EXPECT_NEAR((lat_deg - 45.0) * kDegToRad * (wgs84::MeridianRadius(lat) + 100.0), 6.0, 1e-4);
  std::size_t at = first;
  for (int k = 0; k < 9; ++k) at = kml.find(' ', at) + 1;  // the 10th point: 90 deg
  ASSERT_EQ(std::sscanf(kml.c_str() + at, "%lf,%lf", &lon_deg, &lat_deg), 2);
  EXPECT_NEAR(lat_deg, 45.0, 1e-9);
  EXPECT_NEAR((lon_deg - 10.0) * kDegToRad * (wgs84::PrimeVerticalRadius(lat) + 100.0) * std::cos(lat), 3.0, 1e-4);
  EXPECT_THROW(KmlWriter(dir_ + "/x.kml", "x", -1.0, 1.0), std::invalid_argument);
}

TEST_F(TrackExportTest, GpxHasEveryPointWithUtcWhenTheWeekIsKnown) {
  const std::string path = dir_ + "/track.gpx";
  GpxWriter w(path, "walk");
  w.Write(State(18.0, 1930, 40.0, -105.0, 1600.0));
  w.Write(State(18.5, -1, 40.0, -105.0, 1600.0));
  w.Commit();
  const std::string gpx = ReadText(path);
  EXPECT_EQ(Count(gpx, "<trkpt "), 2u);
  EXPECT_EQ(Count(gpx, "<time>"), 1u);
  EXPECT_NE(gpx.find("<trkpt lat=\"40.000000000\" lon=\"-105.000000000\"><ele>1600.0000</ele>"
                     "<time>2017-01-01T00:00:00.000Z</time></trkpt>"),
            std::string::npos)
      << gpx;
}

TEST_F(TrackExportTest, StdCsvIsReadAndCheckedWithFileLineAndField) {
  const std::string header = "t_s,pos_n_std_m,pos_e_std_m,pos_d_std_m,vel_n_std_mps,vel_e_std_mps,vel_d_std_mps\n";
  const NavStdSeries s = ReadNavStdCsv(Write("std.csv", header + "1.0,0.1,0.2,0.3,0.01,0.02,0.03\n"
                                                                 "2.0,0.4,0.5,0.6,0.04,0.05,0.06\n"));
  ASSERT_EQ(s.t_s.size(), 2u);
  EXPECT_EQ(s.pos_ned_m[1], Eigen::Vector3d(0.4, 0.5, 0.6));
  EXPECT_EQ(s.vel_ned_mps[0], Eigen::Vector3d(0.01, 0.02, 0.03));
  EXPECT_EQ(s.Find(2.0000004), 1);
  EXPECT_EQ(s.Find(1.5), -1);
  try {
    ReadNavStdCsv(Write("zero.csv", header + "1.0,0.1,0.2,0.3,0.01,0.02,0.03\n2.0,0.4,0.5,0.6,0.04,0,0.06\n"));
    FAIL() << "a zero sigma was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("zero.csv"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("3"), std::string::npos) << e.what();  // line 3
    EXPECT_NE(std::string(e.what()).find("vel_e_std_mps"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadNavStdCsv(Write("nocol.csv", "t_s,pos_n_std_m\n1.0,0.1\n")), InputError);
  EXPECT_THROW(ReadNavStdCsv(Write("nan.csv", header + "1.0,nan,0.2,0.3,0.01,0.02,0.03\n")), InputError);
}

}  // namespace core_io_track_export_test
}  // namespace navtwin
