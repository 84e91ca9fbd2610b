// Trapezoid increments from rates, and intervals of increment rows from time tags.
#include "core/io/rate_to_increment.h"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <vector>

namespace navtwin {
namespace io_rate_to_increment_test {

TEST(RateToIncrementTest, FirstSampleOnlyStartsTheSeries) {
  RateToIncrement r;
  ImuSample out;
  RateSample s;
  s.t_s = 10.0;
  EXPECT_FALSE(r.Add(s, &out));
  s.t_s = 10.01;
  EXPECT_TRUE(r.Add(s, &out));
  EXPECT_EQ(out.t_s, 10.01);
}

TEST(RateToIncrementTest, TrapezoidIsExactForRatesLinearInTime) {
  // omega(t) = a + b t and f(t) = c + d t integrate exactly by the trapezoid rule, so the
  // only error is rounding: 1e-12 relative to increments of order 1e-2.
  const Eigen::Vector3d a(0.1, -0.2, 0.3), b(0.05, 0.01, -0.02);
  const Eigen::Vector3d c(0.5, 0.0, -9.8), d(0.2, -0.1, 0.0);
  const auto ExpectIntegrals = [&](const ImuSample& out, double t0, double t1) {
    const Eigen::Vector3d dtheta = a * (t1 - t0) + b * 0.5 * (t1 * t1 - t0 * t0);
    const Eigen::Vector3d dv = c * (t1 - t0) + d * 0.5 * (t1 * t1 - t0 * t0);
    EXPECT_LT((out.dtheta_b_rad - dtheta).norm(), 1e-12);
    EXPECT_LT((out.dv_b_mps - dv).norm(), 1e-12);
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(0.004, 0.006);  // irregular intervals
  RateToIncrement r;
  ImuSample out;
  double t = 100.0;
  double t_prev = t;
  for (int k = 0; k < 50; ++k) {
    RateSample s;
    s.t_s = t;
    s.gyro_radps = a + b * t;
    s.acc_mps2 = c + d * t;
    if (k == 0) {
      ASSERT_FALSE(r.Add(s, &out));
    } else {
      ASSERT_TRUE(r.Add(s, &out));
      EXPECT_EQ(out.dt_s, s.t_s - t_prev);
      ExpectIntegrals(out, t_prev, s.t_s);
    }
    t_prev = t;
    t += jitter(rng);
  }
}

TEST(RateToIncrementTest, NonIncreasingTimeIsAProgrammingError) {
  RateToIncrement r;
  ImuSample out;
  RateSample s;
  s.t_s = 1.0;
  r.Add(s, &out);
  EXPECT_THROW(r.Add(s, &out), std::invalid_argument);
}

TEST(IncrementIntervalsTest, FirstIntervalIsTheSecondOnes) {
  IncrementIntervals iv;
  ImuSample row, out;
  const double times[] = {1.0, 1.1, 1.25};
  std::vector<ImuSample> got;
  for (double t : times) {
    row.t_s = t;
    row.dtheta_b_rad.x() = t;  // tag each row to check the pairing
    if (iv.Add(row, &out)) got.push_back(out);
  }
  while (iv.Flush(&out)) got.push_back(out);
  ASSERT_EQ(got.size(), 3u);
  // Differences of the tags above: exact to rounding of 1.1 - 1.0 etc (1e-15).
  EXPECT_NEAR(got[0].dt_s, 0.1, 1e-15);
  EXPECT_NEAR(got[1].dt_s, 0.1, 1e-15);
  EXPECT_NEAR(got[2].dt_s, 0.15, 1e-15);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(got[k].dtheta_b_rad.x(), times[k]);
}

TEST(IncrementIntervalsTest, SingleRowHasNoInterval) {
  IncrementIntervals iv;
  ImuSample row, out;
  EXPECT_FALSE(iv.Add(row, &out));
  EXPECT_THROW(iv.Flush(&out), std::logic_error);
}

}  // namespace io_rate_to_increment_test
}  // namespace navtwin
