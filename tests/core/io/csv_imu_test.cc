// navtwin CSV IMU files: increments round trip, rate columns with units, bad input.
#include "core/io/csv_imu.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "core/io/input_error.h"
#include "core/rotation.h"

namespace navtwin {
namespace {

std::string WriteTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "navtwin_csv_imu_" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

template <typename F>
void ExpectInputError(F f, std::initializer_list<std::string> parts) {
  try {
    f();
  } catch (const InputError& e) {
    for (const std::string& p : parts) {
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what() << " lacks: " << p;
    }
    return;
  }
  ADD_FAILURE() << "no InputError";
}

std::vector<ImuSample> ReadAll(const std::string& path) {
  auto reader = OpenCsvImu(path);
  std::vector<ImuSample> out;
  ImuSample s;
  while (reader->Next(&s)) out.push_back(s);
  return out;
}

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
  const std::string path = ::testing::TempDir() + "navtwin_csv_imu_roundtrip.csv";
  CsvImuWriter w(path);
  for (const ImuSample& s : in) w.Write(s);
  w.Commit();
  const std::vector<ImuSample> out = ReadAll(path);
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
      WriteTemp("rates.csv",
                "# recorded on the bench\n"
                "note,acc_z_g,t_ms,gyro_x_dps,acc_x_mps2,gyro_y_rad_s,gyro_z_dps,acc_y_g\n"
                "a,1,1000,90,0.5,0.1,-45,0\n"
                "b,1,1010,90,0.5,0.1,-45,0\n"
                "c,1,1030,90,0.5,0.1,-45,0\n");
  const std::vector<ImuSample> out = ReadAll(path);
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
      WriteTemp("missing_gyro.csv",
                "t_s,gyro_x_rad_s,gyro_z_rad_s,acc_x_mps2,acc_y_mps2,acc_z_mps2\n"
                "0,0,0,0,0,0\n");
  ExpectInputError([&] { ReadAll(rates); },
                   {rates, "line 1", "missing column 'gyro_y_rad_s' or 'gyro_y_dps'"});
  const std::string inc = WriteTemp("missing_dv.csv",
                                    "t_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps\n"
                                    "0,0,0,0,0,0\n");
  ExpectInputError([&] { ReadAll(inc); }, {"missing column 'dv_z_mps'"});
  const std::string time = WriteTemp("missing_t.csv", "time,dtheta_x_rad\n0,0\n");
  ExpectInputError([&] { ReadAll(time); }, {"missing column 't_s' or 't_ms'"});
}

TEST(CsvImuTest, BadRowsNameLineAndField) {
  const std::string head =
      "t_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps\n";
  const std::string nan = WriteTemp("nan.csv", head + "0,0,0,0,0,0,0\n0.01,0,NaN,0,0,0,0\n");
  ExpectInputError([&] { ReadAll(nan); }, {"line 3", "field 'dtheta_y_rad'", "not a finite"});
  const std::string back = WriteTemp("back.csv", head + "0,0,0,0,0,0,0\n-0.01,0,0,0,0,0,0\n");
  ExpectInputError([&] { ReadAll(back); }, {"line 3", "field 't_s'", "does not increase"});
  const std::string cols = WriteTemp("cols.csv", head + "0,0,0,0,0,0\n");
  ExpectInputError([&] { ReadAll(cols); }, {"line 2", "expected 7 columns, found 6"});
  const std::string empty = WriteTemp("empty.csv", "");
  ExpectInputError([&] { ReadAll(empty); }, {empty, "empty"});
  const std::string header_only = WriteTemp("header_only.csv", head);
  ExpectInputError([&] { ReadAll(header_only); }, {"no samples"});
}

}  // namespace
}  // namespace navtwin
