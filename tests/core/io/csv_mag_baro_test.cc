// navtwin CSV magnetometer and barometer files: round trips, units, optional columns,
// every class of bad input, and dispatch through open.h.
#include "core/io/csv_mag_baro.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/io/open.h"
#include "tests/core/io/io_test_util.h"
#include "tests/test_data.h"

namespace navtwin {
namespace io_csv_mag_baro_test {

using testing::ExpectInputError;
using testing::MakeTempDir;
using testing::ReadAllSamples;
using testing::TempFilePath;
using testing::WriteTempFile;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(CsvMagBaroTest, MagRoundTripIsExact) {
  std::mt19937 rng(17);
  std::normal_distribution<double> field(0.0, 40.0);
  std::vector<MagSample> in(200);
  for (std::size_t k = 0; k < in.size(); ++k) {
    in[k].t_s = 100.0 + 0.0137 * static_cast<double>(k);
    in[k].m_b_uT = Eigen::Vector3d(field(rng), field(rng), field(rng));
  }
  const std::string path = TempFilePath("mag.csv");
  CsvMagWriter w(path);
  for (const MagSample& s : in) w.Write(s);
  w.Commit();
  const std::vector<MagSample> out = ReadAllSamples(*OpenCsvMag(path));
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t k = 0; k < in.size(); ++k) {  // 17 digits: exact
    EXPECT_EQ(out[k].t_s, in[k].t_s);
    EXPECT_EQ(out[k].m_b_uT, in[k].m_b_uT);
  }
}

TEST(CsvMagBaroTest, MagUnitsInAnyOrderWithExtraColumns) {
  const std::string path = WriteTempFile("units.csv",
                                         "# bench record\n"
                                         "\n"
                                         "note,mz_nT,t_ms,my_G,mx_ga\n"
                                         "a,45000,1000,0.25,-0.1\n"
                                         "\n"
                                         "b,-500,1020.5,-0.003,1e-2\n");
  const std::vector<MagSample> out = ReadAllSamples(*OpenCsvMag(path));
  ASSERT_EQ(out.size(), 2u);
  // 1 G = 1 ga = 100 uT, 1 nT = 1e-3 uT; products of decimals: 1e-12 relative.
  EXPECT_NEAR(out[0].t_s, 1.0, 1e-15);
  EXPECT_NEAR(out[1].t_s, 1.0205, 1e-15);
  EXPECT_NEAR(out[0].m_b_uT.x(), -10.0, 1e-12);
  EXPECT_NEAR(out[0].m_b_uT.y(), 25.0, 1e-12);
  EXPECT_NEAR(out[0].m_b_uT.z(), 45.0, 1e-12);
  EXPECT_NEAR(out[1].m_b_uT.x(), 1.0, 1e-12);
  EXPECT_NEAR(out[1].m_b_uT.y(), -0.3, 1e-12);
  EXPECT_NEAR(out[1].m_b_uT.z(), -0.5, 1e-12);
}

TEST(CsvMagBaroTest, BaroRoundTripKeepsAbsentValuesAbsent) {
  std::vector<BaroSample> in(4);
  for (std::size_t k = 0; k < in.size(); ++k) in[k].t_s = 0.1 * static_cast<double>(k + 1);
  in[0].pressure_pa = 101325.0 / 3.0;
  in[0].altitude_m = 123.456789012345678;
  in[0].temperature_degC = -56.5;
  in[1].altitude_m = -12.5;  // no pressure, no temperature
  in[2].pressure_pa = 95000.125;
  in[3].pressure_pa = 1.0 / 7.0;
  in[3].temperature_degC = 21.0;
  const std::string path = TempFilePath("baro.csv");
  CsvBaroWriter w(path);
  for (const BaroSample& s : in) w.Write(s);
  w.Commit();
  const std::vector<BaroSample> out = ReadAllSamples(*OpenCsvBaro(path));
  ASSERT_EQ(out.size(), in.size());
  const auto same = [](double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; };
  for (std::size_t k = 0; k < in.size(); ++k) {
    EXPECT_EQ(out[k].t_s, in[k].t_s);
    EXPECT_TRUE(same(out[k].pressure_pa, in[k].pressure_pa)) << k;
    EXPECT_TRUE(same(out[k].altitude_m, in[k].altitude_m)) << k;
    EXPECT_TRUE(same(out[k].temperature_degC, in[k].temperature_degC)) << k;
  }
}

TEST(CsvMagBaroTest, BaroMissingOptionalColumnsReadAsNaN) {
  const std::string path = WriteTempFile("alt.csv", "altitude_m,t_s\n10.5,0.0\n11.0,0.04\n");
  const std::vector<BaroSample> out = ReadAllSamples(*OpenCsvBaro(path));
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].altitude_m, 11.0);
  EXPECT_TRUE(std::isnan(out[1].pressure_pa));
  EXPECT_TRUE(std::isnan(out[1].temperature_degC));
}

TEST(CsvMagBaroTest, BadMagInputNamesFileLineAndField) {
  const std::string header = "t_s,mx_uT,my_uT,mz_uT\n";
  const auto bad = [](const std::string& name, const std::string& text,
                      std::initializer_list<std::string> parts) {
    const std::string path = WriteTempFile(name, text);
    ExpectInputError([&] { ReadAllSamples(*OpenCsvMag(path)); }, parts);
  };
  bad("empty.csv", "", {"empty"});
  bad("header_only.csv", header, {"no samples (only a header)"});
  bad("no_y.csv", "t_s,mx_uT,mz_uT\n0,1,2\n",
      {"line 1", "missing column 'my_uT' or 'my_G' or 'my_ga' or 'my_nT'"});
  bad("no_time.csv", "time,mx_uT,my_uT,mz_uT\n0,1,2,3\n", {"missing column 't_s' or 't_ms'"});
  bad("count.csv", header + "0,1,2,3\n0.1,1,2\n", {"line 3", "expected 4 columns, found 3"});
  bad("text.csv", header + "0,1,2,3\n0.1,1,x,3\n", {"line 3", "my_uT", "not a number"});
  bad("nan.csv", header + "0,nan,2,3\n", {"line 2", "mx_uT", "not a finite number"});
  bad("back.csv", header + "0,1,2,3\n0.2,1,2,3\n0.1,1,2,3\n",
      {"line 4", "t_s", "does not increase"});
  // Finite in gauss, infinite in uT (x 100): checked after the scaling.
  bad("gauss_overflow.csv", "t_s,mx_G,my_G,mz_G\n0,0.2,0,0.4\n0.1,0.2,1e307,0.4\n",
      {"gauss_overflow.csv", "line 3", "field 'my_G'", "finite"});
  bad("huge_field.csv", header + "0,20,0,40\n0.1,20,1e16,40\n",
      {"line 3", "field 'my_uT'", "implausible magnetic field"});
}

TEST(CsvMagBaroTest, ImplausibleBaroValuesAreRefused) {
  const std::string header = "t_s,pressure_pa,altitude_m,temperature_degC\n";
  const auto bad = [](const std::string& name, const std::string& text, std::initializer_list<std::string> parts) {
    const std::string path = WriteTempFile(name, text);
    ExpectInputError([&] { ReadAllSamples(*OpenCsvBaro(path)); }, parts);
  };
  bad("pressure.csv", header + "0,101325,,20\n0.1,1e16,,20\n", {"line 3", "field 'pressure_pa'", "implausible pressure"});
  bad("altitude.csv", header + "0,,100,20\n0.1,,1e16,20\n", {"line 3", "field 'altitude_m'", "implausible height"});
  bad("time.csv", header + "0,101325,,20\n1e16,101325,,20\n", {"line 3", "field 't_s'", "implausible time"});
}

TEST(CsvMagBaroTest, BadBaroInputNamesFileLineAndField) {
  const std::string header = "t_s,pressure_pa,altitude_m,temperature_degC\n";
  const auto bad = [](const std::string& name, const std::string& text,
                      std::initializer_list<std::string> parts) {
    const std::string path = WriteTempFile(name, text);
    ExpectInputError([&] { ReadAllSamples(*OpenCsvBaro(path)); }, parts);
  };
  bad("empty.csv", "\n\n", {"empty"});
  bad("header_only.csv", header, {"only a header"});
  bad("neither.csv", "t_s,temperature_degC\n0,15\n",
      {"line 1", "missing column 'pressure_pa' or 'altitude_m'"});
  bad("count.csv", header + "0,101325,0,15,9\n", {"line 2", "expected 4 columns, found 5"});
  bad("text.csv", header + "0,101325,ten,15\n", {"line 2", "altitude_m", "not a number"});
  bad("inf.csv", header + "0,inf,0,15\n", {"pressure_pa", "not a finite number"});
  bad("zero_p.csv", header + "0,0,0,15\n", {"line 2", "pressure_pa", "must be > 0"});
  bad("cold.csv", header + "0,101325,0,-300\n", {"temperature_degC", "below absolute zero"});
  bad("blank_row.csv", header + "0,101325,0,15\n1,,,15\n",
      {"line 3", "a row needs pressure_pa or altitude_m"});
  bad("same_time.csv", header + "0,101325,0,15\n0,101325,0,15\n", {"line 3", "does not increase"});
}

TEST(CsvMagBaroTest, WritersRejectBadSamplesAndLeaveNoPartialFile) {
  const std::string mag_path = TempFilePath("partial_mag.csv");
  {
    CsvMagWriter w(mag_path);
    MagSample s;
    s.m_b_uT.y() = kNaN;
    EXPECT_THROW(w.Write(s), std::invalid_argument);
  }  // destroyed without Commit
  EXPECT_FALSE(testing::FileExists(mag_path));
  const std::string baro_path = TempFilePath("partial_baro.csv");
  {
    CsvBaroWriter w(baro_path);
    BaroSample s;  // neither pressure nor altitude
    EXPECT_THROW(w.Write(s), std::invalid_argument);
    s.altitude_m = std::numeric_limits<double>::infinity();
    EXPECT_THROW(w.Write(s), std::invalid_argument);
  }
  EXPECT_FALSE(testing::FileExists(baro_path));
}

TEST(CsvMagBaroTest, OpenDetectsDispatchesAndDescribesBothKinds) {
  const std::string d = MakeTempDir();
  const std::string mag =
      testing::WriteFile(d + "/mag.csv", "t_s,mx_uT,my_uT,mz_uT\n0,1,2,3\n0.1,1,2,3\n0.2,1,2,3\n");
  const std::string gauss = testing::WriteFile(d + "/gauss.csv", "t_ms,mx_G,my_G,mz_G\n0,1,2,3\n");
  const std::string baro =
      testing::WriteFile(d + "/baro.csv", "t_s,pressure_pa\n0,101325\n0.5,101300\n");
  EXPECT_EQ(DetectFormat(mag), FileFormat::kCsvMag);
  EXPECT_EQ(DetectFormat(gauss), FileFormat::kCsvMag);
  EXPECT_EQ(DetectFormat(baro), FileFormat::kCsvBaro);
  EXPECT_EQ(FormatName(FileFormat::kCsvMag), "csv-mag");
  EXPECT_EQ(FormatName(FileFormat::kCsvBaro), "csv-baro");
  EXPECT_EQ(ReadAllSamples(*OpenMag(mag)).size(), 3u);
  EXPECT_EQ(ReadAllSamples(*OpenMag(gauss))[0].m_b_uT.z(), 300.0);
  EXPECT_EQ(ReadAllSamples(*OpenBaro(baro))[1].pressure_pa, 101300.0);
  ExpectInputError([&] { OpenImu(mag); }, {"cannot read IMU samples from a file of kind csv-mag"});
  ExpectInputError([&] { OpenMag(baro); }, {"of kind csv-baro"});
  const FileSummary fm = DescribeFile(mag);
  EXPECT_EQ(fm.kind, "csv-mag");
  ASSERT_EQ(fm.streams.size(), 1u);
  EXPECT_EQ(fm.streams[0].name, "mag");
  EXPECT_EQ(fm.streams[0].count, 3u);
  EXPECT_NEAR(fm.streams[0].rate_hz, 10.0, 1e-3);  // from float intervals (file_summary.h)
  const FileSummary fb = DescribeFile(baro);
  EXPECT_EQ(fb.streams[0].name, "baro");
  EXPECT_EQ(fb.streams[0].fields.size(), 2u);
}

}  // namespace io_csv_mag_baro_test
}  // namespace navtwin
