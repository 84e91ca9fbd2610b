// The calibration file (core/calibration_file.h): exact round trip, compensation of
// simulated increments against the forward model of core/imu_error_model.h, temperature
// terms, every bad-input case (the message names the key and the line), and the readers.
#include "core/calibration_file.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "core/io/csv_imu.h"
#include "core/io/csv_mag_baro.h"
#include "core/io/input_error.h"
#include "core/io/open.h"
#include "tests/scratch_dir.h"

namespace navtwin {
namespace core_calibration_file_test {

using Triad = Eigen::Matrix<double, kTriadParameters, 1>;
using GSens = Eigen::Matrix<double, kGSensitivityParameters, 1>;

class CalibrationFileTest : public testing::ScratchDirTest {};

/// A triad of errors of a tactical IMU: scale factors and misalignments of ~1e-3, bias `b`.
Triad RandomTriad(std::mt19937& rng, double b) {
  std::normal_distribution<double> n(0.0, 1.0);
  Triad t;
  for (int i = 0; i < 9; ++i) t[i] = 1e-3 * n(rng);
  for (int i = 9; i < 12; ++i) t[i] = b * n(rng);
  return t;
}

ImuCalibration RandomCalibration(std::mt19937& rng) {
  ImuCalibration c;
  c.gyro = RandomTriad(rng, 1e-4);
  c.accel = RandomTriad(rng, 1e-2);
  std::normal_distribution<double> n(0.0, 1e-5);
  for (int i = 0; i < kGSensitivityParameters; ++i) c.g_sensitivity[i] = n(rng);
  return c;
}

void ExpectBitwiseEqual(const Triad& a, const Triad& b, const std::string& what) {
  for (int i = 0; i < kTriadParameters; ++i) {
    if (std::isnan(a[i])) {
      EXPECT_TRUE(std::isnan(b[i])) << what << "[" << i << "]";
    } else {
      EXPECT_EQ(a[i], b[i]) << what << "[" << i << "]";
    }
  }
}

TEST_F(CalibrationFileTest, WriteReadRoundTripIsExact) {
  std::mt19937 rng(7);
  CalibrationFile f;
  f.created_by = "navtwin calibrate-imu --rig multiposition --data \"a b.txt\": test";
  ImuCalibration c = RandomCalibration(rng);
  Triad gyro_sigma = Triad::Constant(1e-6);
  gyro_sigma[MisalignmentIndex(0, 1)] = std::numeric_limits<double>::quiet_NaN();  // not estimated
  c.gyro_sigma = gyro_sigma;
  c.accel_sigma = Triad::Constant(2e-5);
  c.g_sensitivity_sigma = GSens::Constant(3e-7);
  TemperatureTerms t;
  t.reference_degC = 21.5;
  t.gyro_bias_rad_per_s = {Eigen::Vector3d(1e-7, -2e-7, 3e-7), Eigen::Vector3d(1e-9, 2e-9, -3e-9)};
  t.accel_scale_factor = {Eigen::Vector3d(1e-5, 2e-5, 3e-5)};
  c.temperature = t;
  f.imu = c;
  MagCorrection m;
  m.hard_iron_uT = Eigen::Vector3d(12.25, -3.5, 0.1);
  m.correction << 1.02, 0.01, -0.003, 0.01, 0.97, 0.002, -0.003, 0.002, 1.01;
  m.field_uT = 49.87;
  f.mag = m;

  const std::string path = dir_ + "/cal.yaml";
  WriteCalibrationFile(path, f);
  const CalibrationFile r = ReadCalibrationFile(path);
  EXPECT_EQ(r.created_by, f.created_by);
  ASSERT_TRUE(r.imu && r.mag);
  ExpectBitwiseEqual(r.imu->gyro, c.gyro, "gyro");
  ExpectBitwiseEqual(r.imu->accel, c.accel, "accel");
  EXPECT_EQ(r.imu->g_sensitivity, c.g_sensitivity);
  ASSERT_TRUE(r.imu->gyro_sigma && r.imu->accel_sigma && r.imu->g_sensitivity_sigma);
  ExpectBitwiseEqual(*r.imu->gyro_sigma, gyro_sigma, "gyro sigma");
  ExpectBitwiseEqual(*r.imu->accel_sigma, *c.accel_sigma, "accel sigma");
  EXPECT_EQ(*r.imu->g_sensitivity_sigma, *c.g_sensitivity_sigma);
  ASSERT_TRUE(r.imu->temperature);
  EXPECT_EQ(r.imu->temperature->reference_degC, 21.5);
  EXPECT_EQ(r.imu->temperature->gyro_bias_rad_per_s, t.gyro_bias_rad_per_s);
  EXPECT_EQ(r.imu->temperature->accel_scale_factor, t.accel_scale_factor);
  EXPECT_TRUE(r.imu->temperature->gyro_scale_factor.empty());
  EXPECT_TRUE(r.imu->temperature->accel_bias_mps2.empty());
  EXPECT_EQ(r.mag->hard_iron_uT, m.hard_iron_uT);
  EXPECT_EQ(r.mag->correction, m.correction);
  EXPECT_EQ(r.mag->field_uT, m.field_uT);
  // Sections are optional: a mag-only file reads back without an imu.
  CalibrationFile mag_only;
  mag_only.mag = m;
  WriteCalibrationFile(path, mag_only);
  EXPECT_FALSE(ReadCalibrationFile(path).imu);
  // No temporary left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir_)) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 1);
}

TEST_F(CalibrationFileTest, NonFiniteValueIsNotWrittenAndLeavesNoFile) {
  CalibrationFile f;
  f.mag = MagCorrection();
  f.mag->hard_iron_uT.x() = std::numeric_limits<double>::quiet_NaN();
  const std::string path = dir_ + "/cal.yaml";
  EXPECT_THROW(WriteCalibrationFile(path, f), std::invalid_argument);
  EXPECT_TRUE(std::filesystem::is_empty(dir_));
}

// Forward model (the truth increments through core/imu_error_model.h) then the
// compensation gives back the truth.
TEST(CalibrationCompensation, RecoversSimulatedIncrements) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  double worst_dv = 0.0, worst_dtheta = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const ImuCalibration c = RandomCalibration(rng);
    const Eigen::Vector3d omega(0.5 * n(rng), 0.5 * n(rng), 0.5 * n(rng));        // rad/s
    const Eigen::Vector3d f(3.0 * n(rng), 3.0 * n(rng), -9.8 + 3.0 * n(rng));       // m/s^2
    const double dt = 0.005 * (1.0 + 0.1 * n(rng));
    ImuSample s;
    s.t_s = 1.0;
    s.dt_s = dt;
    s.dv_b_mps = MeasuredSpecificForce(c.accel.data(), f) * dt;
    s.dtheta_b_rad = MeasuredRate(c.gyro.data(), c.g_sensitivity.data(), omega, f) * dt;
    const ImuSample out = ApplyImuCalibration(c, s);
    EXPECT_EQ(out.t_s, s.t_s);
    EXPECT_EQ(out.dt_s, s.dt_s);
    worst_dv = std::max(worst_dv, (out.dv_b_mps - f * dt).norm() / (f * dt).norm());
    worst_dtheta = std::max(worst_dtheta, (out.dtheta_b_rad - omega * dt).norm() / (omega * dt).norm());
  }
  // Exact algebra in double precision: a 3x3 inverse and a few products, ~1e-15 relative.
  EXPECT_LT(worst_dv, 1e-12);
  EXPECT_LT(worst_dtheta, 1e-12);
}

TEST(CalibrationTemperature, PolynomialTermsAddAtTheGivenTemperature) {
  ImuCalibration c;
  c.gyro[9] = 1e-4;   // b_gx
  c.accel[2] = 2e-3;  // s_az
  TemperatureTerms t;
  t.reference_degC = 20.0;
  t.gyro_bias_rad_per_s = {Eigen::Vector3d(1e-6, 0, 0), Eigen::Vector3d(2e-8, 0, 0)};
  t.accel_scale_factor = {Eigen::Vector3d(0, 0, 1e-5)};
  t.accel_bias_mps2 = {Eigen::Vector3d(0, 3e-4, 0)};
  t.gyro_scale_factor = {Eigen::Vector3d(0, 5e-6, 0)};
  c.temperature = t;
  const ImuCalibration at = c.At(30.0);  // dT = 10
  EXPECT_FALSE(at.temperature);
  // Tolerances: a few ulps of the sums.
  EXPECT_NEAR(at.gyro[9], 1e-4 + 1e-6 * 10 + 2e-8 * 100, 1e-18);
  EXPECT_NEAR(at.gyro[1], 5e-6 * 10, 1e-18);
  EXPECT_NEAR(at.accel[2], 2e-3 + 1e-5 * 10, 1e-17);
  EXPECT_NEAR(at.accel[10], 3e-4 * 10, 1e-17);
  EXPECT_EQ(c.At(20.0).gyro, c.gyro);  // the reference: the constant blocks
  EXPECT_THROW(c.At(std::numeric_limits<double>::infinity()), std::invalid_argument);

  // The reader compensates with the terms at its temperature: increments made by the
  // forward model at 35 degC come back exactly; NaN is the reference temperature.
  class One : public ImuReader {
   public:
    explicit One(ImuSample s) : s_(s) {}
    bool Next(ImuSample* s) override {
      if (done_) return false;
      *s = s_;
      done_ = true;
      return true;
    }
    const std::string& path() const override { return path_; }

   private:
    ImuSample s_;
    bool done_ = false;
    std::string path_ = "one";
  };
  const ImuCalibration at35 = c.At(35.0);
  const Eigen::Vector3d omega(0.1, -0.2, 0.3), f(0.5, -0.4, -9.8);
  ImuSample s;
  s.t_s = 0.01;
  s.dt_s = 0.01;
  s.dv_b_mps = MeasuredSpecificForce(at35.accel.data(), f) * s.dt_s;
  s.dtheta_b_rad = MeasuredRate(at35.gyro.data(), at35.g_sensitivity.data(), omega, f) * s.dt_s;
  ImuSample out;
  ASSERT_TRUE(CalibratedImuReader(std::make_unique<One>(s), c, 35.0)->Next(&out));
  EXPECT_LT((out.dv_b_mps - f * s.dt_s).norm(), 1e-15);  // ~1e-17 rounding on 0.1 m/s
  EXPECT_LT((out.dtheta_b_rad - omega * s.dt_s).norm(), 1e-16);
  ASSERT_TRUE(CalibratedImuReader(std::make_unique<One>(s), c, NAN)->Next(&out));
  EXPECT_EQ(out.dv_b_mps, ApplyImuCalibration(c, s).dv_b_mps);
  // A temperature at which K becomes singular is refused.
  ImuCalibration bad = c;
  bad.temperature->accel_scale_factor = {Eigen::Vector3d(0, 0, -0.1)};  // 1 + s_az = 0 at dT = 10.02
  EXPECT_THROW(CalibratedImuReader(std::make_unique<One>(s), bad, 30.02), std::invalid_argument);
}

struct BadCase {
  const char* what;
  std::string yaml;
  long line;
  const char* key;  ///< the key path the message must name
};

TEST_F(CalibrationFileTest, BadInputNamesFileLineAndKey) {
  const std::string head = "navtwin_calibration: 1\ncreated_by: test\n";
  const BadCase cases[] = {
      {"missing version", "created_by: x\nmag: {field_uT: 50}\n", 1, "navtwin_calibration"},
      {"unknown version", "navtwin_calibration: 2\n", 1, "navtwin_calibration"},
      {"unknown top key", head + "magnetometer: {}\n", 3, "magnetometer"},
      {"unknown imu key", head + "imu:\n  gyro:\n    bias_deg_h: [1, 2, 3]\n", 5, "imu.gyro.bias_deg_h"},
      {"wrong size", head + "imu:\n  accel:\n    scale_factor: [1e-3, 2e-3]\n", 5, "imu.accel.scale_factor"},
      {"wrong row size", head + "mag:\n  soft_iron: [[1, 0, 0],\n    [0, 1],\n    [0, 0, 1]]\n", 5,
       "mag.soft_iron"},
      {"NaN", head + "imu:\n  gyro:\n    bias_rad_per_s: [0, .nan, 0]\n", 5, "imu.gyro.bias_rad_per_s"},
      {"infinity", head + "mag:\n  hard_iron_uT: [1, 2, .inf]\n", 4, "mag.hard_iron_uT"},
      {"text", head + "mag:\n  field_uT: fifty\n", 4, "mag.field_uT"},
      {"singular K", head + "imu:\n  gyro:\n    scale_factor: [-1, 0, 0]\n", 5, "imu.gyro.scale_factor"},
      {"singular soft iron", head + "mag:\n  soft_iron: [[1, 0, 0], [1, 0, 0], [0, 0, 1]]\n", 4, "mag.soft_iron"},
      {"diagonal misalignment",
       head + "imu:\n  accel:\n    misalignment_rad: [[0, 1e-3, 0], [0, 1e-4, 0], [0, 0, 0]]\n", 5,
       "imu.accel.misalignment_rad"},
      {"temperature row", head + "imu:\n  temperature:\n    reference_degC: 20\n    gyro_bias_rad_per_s: [[1, 2]]\n",
       6, "imu.temperature.gyro_bias_rad_per_s"},
      {"sigma unknown key", head + "imu:\n  sigma:\n    gyro: {bias: [1, 2, 3]}\n", 5, "imu.sigma.gyro.bias"},
      {"not a mapping", head + "imu: [1, 2]\n", 3, "imu"},
      {"repeated key", head + "mag:\n  field_uT: 50\n  hard_iron_uT: [1, 2, 3]\n  field_uT: 48\n",
       6, "mag.field_uT"},
      {"repeated top key", head + "created_by: again\n", 3, "created_by"},
  };
  for (const BadCase& c : cases) {
    const std::string path = Write("bad.yaml", c.yaml);
    try {
      ReadCalibrationFile(path);
      ADD_FAILURE() << c.what << ": accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path) << c.what;
      EXPECT_EQ(e.line(), c.line) << c.what << ": " << e.what();
      EXPECT_EQ(e.field(), c.key) << c.what << ": " << e.what();
      const std::string message = e.what();
      EXPECT_NE(message.find(c.key), std::string::npos) << message;
      EXPECT_NE(message.find("line " + std::to_string(c.line)), std::string::npos) << message;
    }
  }
  EXPECT_THROW(ReadCalibrationFile(dir_ + "/missing.yaml"), InputError);
  EXPECT_THROW(ReadCalibrationFile(Write("empty.yaml", "")), InputError);
}

TEST_F(CalibrationFileTest, OpenOverloadsApplyTheFile) {
  const std::string imu_path = dir_ + "/imu.csv", mag_path = dir_ + "/mag.csv";
  {
    CsvImuWriter imu(imu_path);
    CsvMagWriter mag(mag_path);
    for (int k = 1; k <= 20; ++k) {
      ImuSample s;
      s.t_s = 0.01 * k;
      s.dt_s = 0.01;
      s.dtheta_b_rad = Eigen::Vector3d(1e-3, -2e-3, 3e-3 * k);
      s.dv_b_mps = Eigen::Vector3d(0.01, 0.02, -0.098);
      imu.Write(s);
      mag.Write(MagSample{0.05 * k, Eigen::Vector3d(20.0 + k, -5.0, 40.0)});
    }
    imu.Commit();
    mag.Commit();
  }
  std::mt19937 rng(3);
  CalibrationFile file;
  file.imu = RandomCalibration(rng);
  TemperatureTerms t;
  t.reference_degC = 25.0;
  t.accel_bias_mps2 = {Eigen::Vector3d(1e-3, 2e-3, 3e-3)};
  file.imu->temperature = t;
  file.mag = MagCorrection();
  file.mag->hard_iron_uT = Eigen::Vector3d(3, -2, 1);
  file.mag->correction = Eigen::Vector3d(1.1, 0.9, 1.0).asDiagonal();
  const std::string cal = dir_ + "/cal.yaml";
  WriteCalibrationFile(cal, file);

  const std::vector<ImuSample> raw = ReadAll<ImuSample>(*OpenImu(imu_path));
  const std::vector<ImuSample> same = ReadAll<ImuSample>(*OpenImu(imu_path, "", NAN));
  const std::vector<ImuSample> cooked = ReadAll<ImuSample>(*OpenImu(imu_path, cal, 15.0));
  ASSERT_EQ(raw.size(), 20u);
  ASSERT_EQ(cooked.size(), raw.size());
  const ImuCalibration at15 = file.imu->At(15.0);
  for (std::size_t k = 0; k < raw.size(); ++k) {
    EXPECT_EQ(same[k].dv_b_mps, raw[k].dv_b_mps);  // no calibration: the plain reader
    const ImuSample expected = ApplyImuCalibration(at15, raw[k]);
    EXPECT_EQ(cooked[k].dv_b_mps, expected.dv_b_mps);
    EXPECT_EQ(cooked[k].dtheta_b_rad, expected.dtheta_b_rad);
    EXPECT_NE(cooked[k].dv_b_mps, raw[k].dv_b_mps);
  }
  const std::vector<MagSample> mag = ReadAll<MagSample>(*OpenMag(mag_path, cal));
  ASSERT_EQ(mag.size(), 20u);
  EXPECT_EQ(mag[0].m_b_uT, Eigen::Vector3d(1.1 * (21.0 - 3.0), 0.9 * (-5.0 + 2.0), 40.0 - 1.0));
  EXPECT_EQ(OpenMag(mag_path, cal)->path(), mag_path);

  // A file without the section the reader needs names the file and the section.
  CalibrationFile mag_only;
  mag_only.mag = file.mag;
  WriteCalibrationFile(cal, mag_only);
  try {
    OpenImu(imu_path, cal, NAN);
    ADD_FAILURE() << "an IMU calibrated with a mag-only file";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), cal);
    EXPECT_EQ(e.field(), "imu");
  }
  CalibrationFile imu_only;
  imu_only.imu = file.imu;
  WriteCalibrationFile(cal, imu_only);
  EXPECT_THROW(OpenMag(mag_path, cal), InputError);
}

}  // namespace core_calibration_file_test
}  // namespace navtwin
