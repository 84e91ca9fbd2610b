// Wheel-odometer CSV: speeds read as written, distance increments as mean speeds at the
// interval middles, the writer's round trip, and bad input named by file, line and field.
#include "core/io/csv_odometer.h"

#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/core/io/io_test_util.h"

namespace navtwin {
namespace io_csv_odometer_test {

using testing::ExpectInputError;
using testing::TempFilePath;
using testing::WriteTempFile;

TEST(CsvOdometerTest, SpeedRowsAreReadAsWritten) {
  const std::string path = WriteTempFile("speed.csv", "# odometer\nt_s,speed_mps\n0.0,1.5\n0.1,-0.25\n");
  const std::vector<OdometerSample> s = ReadOdometerCsv(path);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].t_s, 0.0);
  EXPECT_EQ(s[0].speed_mps, 1.5);
  EXPECT_EQ(s[1].t_s, 0.1);
  EXPECT_EQ(s[1].speed_mps, -0.25);
}

TEST(CsvOdometerTest, DistanceIncrementsBecomeMeanSpeedsAtIntervalMiddles) {
  const std::string path = WriteTempFile("distance.csv", "t_ms,distance_m\n1000,0\n1200,2.0\n1300,0.5\n");
  const std::vector<OdometerSample> s = ReadOdometerCsv(path);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_DOUBLE_EQ(s[0].t_s, 1.1);
  // Times in ms scaled to s: the intervals carry rounding of ~1e-16 s, 1e-15 relative.
  EXPECT_NEAR(s[0].speed_mps, 10.0, 1e-12);  // 2 m over 0.2 s
  EXPECT_DOUBLE_EQ(s[1].t_s, 1.25);
  EXPECT_NEAR(s[1].speed_mps, 5.0, 1e-12);   // 0.5 m over 0.1 s
}

TEST(CsvOdometerTest, WriterRoundTripIsExact) {
  const std::string path = TempFilePath("round.csv");
  {
    CsvOdometerWriter w(path);
    w.Write({0.1, 1.0 / 3.0});
    w.Write({0.2, -2.0 / 7.0});
    w.Commit();
  }
  const std::vector<OdometerSample> s = ReadOdometerCsv(path);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].speed_mps, 1.0 / 3.0);
  EXPECT_EQ(s[1].speed_mps, -2.0 / 7.0);
  CsvOdometerWriter w(TempFilePath("bad.csv"));
  EXPECT_THROW(w.Write({0.0, std::nan("")}), std::invalid_argument);
}

TEST(CsvOdometerTest, BadInputNamesFileLineAndField) {
  const auto bad = [](const std::string& name, const std::string& text, std::initializer_list<std::string> parts) {
    const std::string path = WriteTempFile(name, text);
    ExpectInputError([&] { ReadOdometerCsv(path); }, parts);
  };
  bad("empty.csv", "", {"empty"});
  bad("header_only.csv", "t_s,speed_mps\n", {"no samples (only a header)"});
  bad("no_value.csv", "t_s,velocity\n0,1\n", {"line 1", "missing column 'speed_mps' or 'distance_m'"});
  bad("nan.csv", "t_s,speed_mps\n0,nan\n", {"line 2", "speed_mps", "not a finite number"});
  bad("back.csv", "t_s,speed_mps\n0,1\n0.2,1\n0.1,1\n", {"line 4", "t_s", "does not increase"});
  bad("fast.csv", "t_s,speed_mps\n0,1\n0.1,250\n", {"speed_mps", "beyond 200 m/s"});
  bad("one_distance.csv", "t_s,distance_m\n0,0\n", {"distance_m", "no interval"});
}

}  // namespace io_csv_odometer_test
}  // namespace navtwin
