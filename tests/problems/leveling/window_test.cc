#include "problems/leveling/window.h"

#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/csv_imu.h"
#include "core/io/input_error.h"
#include "core/sim/random.h"
#include "problems/leveling/leveling.h"
#include "core/leveling_model.h"
#include "core/units.h"

namespace navtwin::leveling {
namespace leveling_window_test {

constexpr double kG = kStandardGravity_mps2;

using VectorOfTime = std::function<Eigen::Vector3d(double t_s)>;

/// Synthetic IMU files in a temporary folder, removed after each test.
class WindowFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = ::testing::TempDir() + "navtwin_window_XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }

  /// n samples at rate_hz from time t_first: increments f dt and omega dt over
  /// (t - dt, t], so that dv/dt and dtheta/dt give back f(t) and omega(t).
  std::string WriteImu(const std::string& name, double rate_hz, int n, double t_first, const VectorOfTime& f,
                       const VectorOfTime& omega) {
    const std::string path = dir_ + "/" + name;
    CsvImuWriter writer(path);
    const double dt = 1.0 / rate_hz;
    for (int k = 0; k < n; ++k) {
      ImuSample s;
      s.t_s = t_first + k * dt;
      s.dt_s = dt;
      s.dv_b_mps = f(s.t_s) * dt;
      s.dtheta_b_rad = omega(s.t_s) * dt;
      writer.Write(s);
    }
    writer.Commit();
    return path;
  }

  std::string dir_;
};

Eigen::Vector3d Level(double) { return Eigen::Vector3d(0.0, 0.0, -kG); }
Eigen::Vector3d NoRotation(double) { return Eigen::Vector3d::Zero(); }

TEST_F(WindowFileTest, ReadsTheSamplesOfTheWindowCountedFromTheFirstSample) {
  // f_x encodes the time so that the selected samples can be told apart.
  const auto f = [](double t) { return Eigen::Vector3d(0.01 * (t - 1000.0), 0.2, -kG); };
  const auto omega = [](double t) { return Eigen::Vector3d(0.001, -0.002, 0.003 * (t - 1000.0)); };
  const std::string path = WriteImu("ramp.csv", 100.0, 300, 1000.0, f, omega);
  const AccelWindow w = ReadAccelWindow(path, 1.0, 0.5);
  // [1.0, 1.5) s after the first sample at 100 Hz: samples 100..149.
  ASSERT_EQ(w.size(), 50);
  ASSERT_EQ(w.t_s.size(), 50u);
  ASSERT_EQ(w.omega_b_radps.size(), 50u);
  EXPECT_EQ(w.source, path);
  // 17-digit text and a division by dt: rounding only.
  EXPECT_NEAR(w.t_s.front(), 1001.0, 1e-9);
  EXPECT_NEAR(w.t_s.back(), 1001.49, 1e-9);
  EXPECT_NEAR(w.rate_hz, 100.0, 1e-6);
  for (int k = 0; k < w.size(); ++k) {
    EXPECT_NEAR((w.f_b_mps2[k] - f(w.t_s[k])).norm(), 0.0, 1e-9);
    EXPECT_NEAR((w.omega_b_radps[k] - omega(w.t_s[k])).norm(), 0.0, 1e-9);
  }
}

TEST_F(WindowFileTest, StartZeroTakesTheFirstSampleAndAWindowMayEndWithTheRecord) {
  const std::string path = WriteImu("level.csv", 100.0, 300, 5.0, Level, NoRotation);
  const AccelWindow first = ReadAccelWindow(path, 0.0, 0.2);
  ASSERT_EQ(first.size(), 20);
  EXPECT_NEAR(first.t_s.front(), 5.0, 1e-12);
  // The record spans 2.99 s between its first and last samples; a window to 3.0 s ends
  // where the next sample would be, so it still holds only recorded samples.
  const AccelWindow last = ReadAccelWindow(path, 2.5, 0.5);
  ASSERT_EQ(last.size(), 50);
  EXPECT_NEAR(last.t_s.back(), 7.99, 1e-9);
}

TEST_F(WindowFileTest, RateIsTheMedianIntervalDespiteAGap) {
  // 200 Hz with samples 50..59 missing: one 55 ms interval among 5 ms ones.
  const std::string path = dir_ + "/gap.csv";
  CsvImuWriter writer(path);
  for (int k = 0; k < 200; ++k) {
    if (k >= 50 && k < 60) continue;
    ImuSample s;
    s.t_s = k * 0.005;
    s.dt_s = k == 60 ? 0.055 : 0.005;
    s.dv_b_mps = Level(0.0) * s.dt_s;
    writer.Write(s);
  }
  writer.Commit();
  const AccelWindow w = ReadAccelWindow(path, 0.0, 0.9);
  EXPECT_EQ(w.size(), 170);
  EXPECT_NEAR(w.rate_hz, 200.0, 1e-6);  // rounding of the text times only
  // f = dv/dt across the gap: the increment covers the whole 55 ms.
  for (const Eigen::Vector3d& f : w.f_b_mps2) EXPECT_NEAR((f - Level(0.0)).norm(), 0.0, 1e-9);
}

TEST_F(WindowFileTest, AWindowBeyondTheEndNamesTheRecordLength) {
  const std::string path = WriteImu("short.csv", 100.0, 300, 0.0, Level, NoRotation);
  try {
    ReadAccelWindow(path, 2.9, 0.2);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.field(), "t_s");
    const std::string what = e.what();
    EXPECT_NE(what.find("beyond the end of the record"), std::string::npos) << what;
    EXPECT_NE(what.find("2.9900 s long"), std::string::npos) << what;
  }
  EXPECT_THROW(ReadAccelWindow(path, 10.0, 0.2), InputError);
}

TEST_F(WindowFileTest, TooFewSamplesAndBadArgumentsAreRefused) {
  const std::string path = WriteImu("few.csv", 100.0, 300, 0.0, Level, NoRotation);
  try {
    ReadAccelWindow(path, 1.0, 0.05);  // 5 samples
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("holds 5 IMU samples, at least 8"), std::string::npos) << what;
  }
  EXPECT_NO_THROW(ReadAccelWindow(path, 1.0, 0.08));  // exactly 8
  EXPECT_THROW(ReadAccelWindow(path, 0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(ReadAccelWindow(path, 0.0, -0.2), std::invalid_argument);
  EXPECT_THROW(ReadAccelWindow(path, -0.1, 0.2), std::invalid_argument);
  EXPECT_THROW(ReadAccelWindow(path, NAN, 0.2), std::invalid_argument);
  EXPECT_THROW(ReadAccelWindow(dir_ + "/missing.csv", 0.0, 0.2), InputError);
}

// ---- CheckWindow on windows built in memory -------------------------------------------

/// A resting window at 600 Hz: gravity at roll/pitch, a body-x tone, white noise.
AccelWindow RestingWindow(sim::Rng& rng, int n, double amplitude_mps2, double freq_hz = 23.3,
                          double noise_mps2 = 0.05 * kG) {
  AccelWindow w;
  w.rate_hz = 600.0;
  w.source = "test";
  const Eigen::Vector3d f0 = SpecificForceAtRest(0.02, -0.03, kG);
  for (int k = 0; k < n; ++k) {
    const double t = k / w.rate_hz;
    Eigen::Vector3d f = f0 + rng.Normal3(noise_mps2);
    f.x() += amplitude_mps2 * std::sin(2.0 * kPi * freq_hz * t + 0.7);
    w.t_s.push_back(t);
    w.f_b_mps2.push_back(f);
    w.omega_b_radps.push_back(rng.Normal3(0.02));  // gyro noise, zero mean
  }
  return w;
}

TEST(CheckWindowTest, AVibratingWindowAtRestPasses) {
  sim::Rng rng(7);
  // 2 g of vibration over 4.66 periods: the plain mean keeps up to ~1.3 m/s^2 of it, the
  // whole-period mean the check uses does not, so |f| stays at g.
  const AccelWindow w = RestingWindow(rng, 120, 2.0 * kG);
  const WindowCheck check = CheckWindow(w, LevelingOptions());
  EXPECT_EQ(check.saturated_samples, 0);
  EXPECT_FALSE(check.moving);
  EXPECT_EQ(check.message, "");
}

TEST(CheckWindowTest, SamplesAtTheRangeLimitAreCountedWithAxisAndTime) {
  sim::Rng rng(8);
  AccelWindow w = RestingWindow(rng, 120, 0.5 * kG);
  LevelingOptions options;
  options.accel_range_mps2 = 8.0 * kG;
  w.f_b_mps2[40].y() = -8.0 * kG;          // at the limit
  w.f_b_mps2[41].y() = 0.996 * 8.0 * kG;   // beyond 99.5 %
  w.f_b_mps2[42].y() = 0.99 * 8.0 * kG;    // below 99.5 %: not saturated
  w.f_b_mps2[90].z() = 9.0 * kG;
  const WindowCheck check = CheckWindow(w, options);
  EXPECT_EQ(check.saturated_samples, 3);
  EXPECT_NE(check.message.find("3 of 120 samples saturated on axis y, z"), std::string::npos) << check.message;
  EXPECT_NE(check.message.find("t = 0.0667 and 0.1500 s"), std::string::npos) << check.message;
}

TEST(CheckWindowTest, ClippingIsFoundBelowTheNominalRange) {
  sim::Rng rng(9);
  AccelWindow w = RestingWindow(rng, 240, 3.0 * kG, 23.3, 0.0);
  // An accelerometer that clips at +-2.5 g on x (a range smaller than the configured one).
  int clipped = 0;
  for (Eigen::Vector3d& f : w.f_b_mps2) {
    if (std::abs(f.x()) >= 2.5 * kG) {
      f.x() = std::copysign(2.5 * kG, f.x());
      ++clipped;
    }
  }
  ASSERT_GT(clipped, 30);  // each half period with |sin| > 5/6 clips ~4 samples in a row
  const WindowCheck check = CheckWindow(w, LevelingOptions());
  EXPECT_EQ(check.saturated_samples, clipped);
  EXPECT_NE(check.message.find("on axis x"), std::string::npos) << check.message;
  EXPECT_NE(check.message.find("clipping"), std::string::npos) << check.message;
}

TEST(CheckWindowTest, QuietQuantisedOrConstantAxesAreNotClipping) {
  // A resting accelerometer with a 0.01 m/s^2 quantum and 0.003 m/s^2 noise repeats its
  // extreme values in runs, but they lie within a quantum of the median.
  sim::Rng rng(10);
  AccelWindow w = RestingWindow(rng, 240, 0.0, 23.3, 0.003);
  for (Eigen::Vector3d& f : w.f_b_mps2) f = (f / 0.01).array().round() * 0.01;
  const WindowCheck quantised = CheckWindow(w, LevelingOptions());
  EXPECT_EQ(quantised.saturated_samples, 0) << quantised.message;
  // Noise-free data (a simulation with --perfect): every value is its axis' extreme.
  for (Eigen::Vector3d& f : w.f_b_mps2) f = SpecificForceAtRest(0.02, -0.03, kG);
  const WindowCheck constant = CheckWindow(w, LevelingOptions());
  EXPECT_EQ(constant.saturated_samples, 0) << constant.message;
  EXPECT_EQ(constant.message, "");
}

TEST(CheckWindowTest, RotationIsMotion) {
  sim::Rng rng(11);
  AccelWindow w = RestingWindow(rng, 120, 0.5 * kG);
  for (Eigen::Vector3d& omega : w.omega_b_radps) omega.z() += 0.1;  // a 5.7 deg/s turn
  const WindowCheck check = CheckWindow(w, LevelingOptions());
  EXPECT_TRUE(check.moving);
  EXPECT_NE(check.message.find("moving: mean angular rate"), std::string::npos) << check.message;
}

TEST(CheckWindowTest, SpecificForceAwayFromGravityIsMotionEvenWithoutGyros) {
  sim::Rng rng(12);
  AccelWindow w = RestingWindow(rng, 120, 0.5 * kG);
  w.omega_b_radps.clear();  // gyros unknown
  // Accelerating forward at 5 m/s^2: |f| = 10.87 m/s^2. (A horizontal acceleration a
  // changes |f| by only about a^2 / 2g, so the 0.5 m/s^2 limit catches a >~ 3.2 m/s^2.)
  for (Eigen::Vector3d& f : w.f_b_mps2) f.x() += 5.0;
  const WindowCheck check = CheckWindow(w, LevelingOptions());
  EXPECT_TRUE(check.moving);
  EXPECT_NE(check.message.find("mean |f| = 10.8"), std::string::npos) << check.message;
  EXPECT_EQ(check.message.find("angular rate"), std::string::npos) << check.message;
}

TEST(CheckWindowTest, GravityOptionSetsTheReferenceAndZeroMeansStandardGravity) {
  sim::Rng rng(13);
  AccelWindow w = RestingWindow(rng, 120, 0.0);
  for (Eigen::Vector3d& f : w.f_b_mps2) f *= 9.0 / kG;  // |f| = 9.0 m/s^2
  LevelingOptions options;
  options.gravity_mps2 = 9.1;
  EXPECT_FALSE(CheckWindow(w, options).moving);
  options.gravity_mps2 = 0.0;  // standard gravity: 0.81 m/s^2 away
  EXPECT_TRUE(CheckWindow(w, options).moving);
}

}  // namespace leveling_window_test
}  // namespace navtwin::leveling
