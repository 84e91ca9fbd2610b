// navtwin CSV IMU files: increments round trip, rate columns with units, bad input.
#include "core/io/csv_imu.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "core/rotation.h"
#include "tests/core/io/io_test_util.h"

namespace navtwin {
namespace io_csv_imu_test {

using testing::ExpectInputError;
using testing::ReadAllSamples;
using testing::TempFilePath;
using testing::WriteTempFile;

TEST(CsvImuTest, IncrementRoundTripIsExact) {
  std::mt19937 rng(99);
  std::normal_distribution<double> inc(0.0, 2e-3);
  std::vector<ImuSample> in(300);
  double t = 12.5;
  for (std::size_t k = 0; k < in.size(); ++k) {
    in[k].t_s = t;
    in[k].dtheta_b_rad = Eigen::Vector3d(inc(rng), inc(rng), inc(rng));
    in[k].dv_b_mps = Eigen::Vector3d(inc(rng), inc(rng), inc(rng));
    t += 0.01 + inc(rng) * 0.1;
  }
  for (std::size_t k = 1; k < in.size(); ++k) in[k].dt_s = in[k].t_s - in[k - 1].t_s;
  in[0].dt_s = in[1].dt_s;
  const std::string path = TempFilePath("roundtrip.csv");
  CsvImuWriter w(path);
  for (const ImuSample& s : in) w.Write(s);
  w.Commit();
  const std::vector<ImuSample> out = ReadAllSamples(*OpenCsvImu(path));
  ASSERT_EQ(out.size(), in.size());
  for (std::size_t k = 0; k < in.size(); ++k) {  // 17 digits: exact
    EXPECT_EQ(out[k].t_s, in[k].t_s);
    EXPECT_EQ(out[k].dt_s, in[k].dt_s);
    EXPECT_EQ(out[k].dtheta_b_rad, in[k].dtheta_b_rad);
    EXPECT_EQ(out[k].dv_b_mps, in[k].dv_b_mps);
  }
}

TEST(CsvImuTest, RatesWithPeopleUnitsInAnyOrderAndExtraColumns) {
  // Constant rates: the trapezoid gives rate * dt exactly up to rounding (1e-15).
  const std::string path =
      WriteTempFile("rates.csv",
                    "# recorded on the bench\n"
                    "note,acc_z_g,t_ms,gyro_x_dps,acc_x_mps2,gyro_y_rad_s,gyro_z_dps,acc_y_g\n"
                    "a,1,1000,90,0.5,0.1,-45,0\n"
                    "b,1,1010,90,0.5,0.1,-45,0\n"
                    "c,1,1030,90,0.5,0.1,-45,0\n");
  const std::vector<ImuSample> out = ReadAllSamples(*OpenCsvImu(path));
  ASSERT_EQ(out.size(), 2u);  // the first rate row only starts the series
  EXPECT_NEAR(out[0].t_s, 1.010, 1e-15);
  EXPECT_NEAR(out[0].dt_s, 0.010, 1e-15);
  EXPECT_NEAR(out[1].dt_s, 0.020, 1e-15);
  const double dt = out[1].dt_s;
  EXPECT_NEAR(out[1].dtheta_b_rad.x(), 90 * kDegToRad * dt, 1e-15);
  EXPECT_NEAR(out[1].dtheta_b_rad.y(), 0.1 * dt, 1e-15);
  EXPECT_NEAR(out[1].dtheta_b_rad.z(), -45 * kDegToRad * dt, 1e-15);
  EXPECT_NEAR(out[1].dv_b_mps.x(), 0.5 * dt, 1e-15);
  EXPECT_NEAR(out[1].dv_b_mps.z(), kStandardGravity_mps2 * dt, 1e-15);
}

TEST(CsvImuTest, MissingColumnIsNamed) {
  const std::string rates =
      WriteTempFile("missing_gyro.csv",
                    "t_s,gyro_x_rad_s,gyro_z_rad_s,acc_x_mps2,acc_y_mps2,acc_z_mps2\n"
                    "0,0,0,0,0,0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(rates)); },
                   {rates, "line 1", "missing column 'gyro_y_rad_s' or 'gyro_y_dps'"});
  const std::string inc =
      WriteTempFile("missing_dv.csv",
                    "t_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps\n"
                    "0,0,0,0,0,0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(inc)); }, {"missing column 'dv_z_mps'"});
  const std::string time = WriteTempFile("missing_t.csv", "time,dtheta_x_rad\n0,0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(time)); }, {"missing column 't_s' or 't_ms'"});
}

TEST(CsvImuTest, BadRowsNameLineAndField) {
  const std::string head =
      "t_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps\n";
  const std::string nan = WriteTempFile("nan.csv", head + "0,0,0,0,0,0,0\n0.01,0,NaN,0,0,0,0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(nan)); },
                   {"line 3", "field 'dtheta_y_rad'", "not a finite"});
  const std::string back = WriteTempFile("back.csv", head + "0,0,0,0,0,0,0\n-0.01,0,0,0,0,0,0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(back)); },
                   {"line 3", "field 't_s'", "does not increase"});
  const std::string cols = WriteTempFile("cols.csv", head + "0,0,0,0,0,0\n");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(cols)); },
                   {"line 2", "expected 7 columns, found 6"});
  const std::string empty = WriteTempFile("empty.csv", "");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(empty)); }, {empty, "empty"});
  const std::string header_only = WriteTempFile("header_only.csv", head);
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(header_only)); }, {"no samples"});
}

TEST(CsvImuTest, ValuesThatOverflowInSiUnitsAreRefused) {
  // 1e308 g is finite, 1e308 g * 9.80665 m/s^2 per g is not: checked after the scaling.
  const std::string head = "t_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,acc_x_g,acc_y_g,acc_z_g\n";
  const std::string g = WriteTempFile("g.csv", head + "0,0,0,0,0,0,1\n0.01,0,0,0,1e308,0,1\n0.02,0,0,0,0,0,1\n");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(g)); }, {g, "line 3", "field 'acc_x_g'", "finite"});
  const std::string ms = WriteTempFile("ms.csv", "t_ms,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps\n"
                                                 "0,0,0,0,0,0,0\n1,0,0,0,0,0,0\n");
  EXPECT_EQ(ReadAllSamples(*OpenCsvImu(ms)).size(), 2u);
}

TEST(CsvImuTest, ImplausibleRatesAndIncrementsAreRefused) {
  const std::string rates = "t_s,gyro_x_dps,gyro_y_dps,gyro_z_dps,acc_x_mps2,acc_y_mps2,acc_z_mps2\n";
  const std::string gyro = WriteTempFile("gyro.csv", rates + "0,0,0,0,0,0,9.8\n0.01,0,2e4,0,0,0,9.8\n");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(gyro)); },
                   {gyro, "line 3", "field 'gyro_y_dps'", "implausible angular rate"});
  const std::string acc = WriteTempFile("acc.csv", rates + "0,0,0,0,0,0,9.8\n0.01,0,0,0,0,-1e16,9.8\n");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(acc)); },
                   {acc, "line 3", "field 'acc_y_mps2'", "implausible specific force"});
  const std::string inc = "t_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps\n";
  const std::string dv = WriteTempFile("dv.csv", inc + "0,0,0,0,0,0,0.098\n0.01,0,0,0,0,0,1e16\n");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(dv)); },
                   {dv, "line 3", "field 'dv_z_mps'", "implausible velocity increment"});
  const std::string t = WriteTempFile("t.csv", inc + "0,0,0,0,0,0,0.098\n1e16,0,0,0,0,0,0.098\n");
  ExpectInputError([&] { ReadAllSamples(*OpenCsvImu(t)); }, {t, "line 3", "field 't_s'", "implausible time"});
}

}  // namespace io_csv_imu_test
}  // namespace navtwin
