// The statistics of the in-flight alignment Monte Carlo: moments over the finite values in
// run order, per-method columns with failures counted, and the per-run CSV.
#include "problems/inflight_alignment/monte_carlo.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "core/sim/scenario.h"

namespace navtwin::inflight {
namespace inflight_alignment_monte_carlo_test {

constexpr double kNaN = McRunNumbers::kNaN;

TEST(InflightMonteCarlo, MomentsSkipNonFiniteValues) {
  const Moments none = MomentsOf({kNaN, INFINITY});
  EXPECT_EQ(none.count, 0);
  EXPECT_TRUE(std::isnan(none.mean) && std::isnan(none.sigma) && std::isnan(none.rms));
  const Moments one = MomentsOf({-2.0, kNaN});
  EXPECT_EQ(one.count, 1);
  EXPECT_DOUBLE_EQ(one.mean, -2.0);
  EXPECT_DOUBLE_EQ(one.rms, 2.0);
  EXPECT_TRUE(std::isnan(one.sigma));
  const Moments m = MomentsOf({1.0, kNaN, 2.0, 3.0, 6.0});
  EXPECT_EQ(m.count, 4);
  EXPECT_DOUBLE_EQ(m.mean, 3.0);
  EXPECT_NEAR(m.sigma, std::sqrt(14.0 / 3.0), 1e-12);  // sample standard deviation, n - 1
  EXPECT_NEAR(m.rms, std::sqrt(50.0 / 4.0), 1e-12);
}

McRunNumbers Numbers(double at10_rad, double at20_rad, double final_rad, const std::string& failure = "") {
  McRunNumbers n;
  n.error_at_km_rad = {at10_rad, at20_rad};
  n.final_error_rad = final_rad;
  n.final_sigma_rad = 0.5 * std::abs(final_rad);
  n.run_time_s = 0.25;
  n.failure = failure;
  return n;
}

TEST(InflightMonteCarlo, StatsArePerColumnWithFailuresCounted) {
  std::vector<McRunNumbers> runs = {Numbers(1e-3, 2e-3, -1e-3), Numbers(3e-3, kNaN, 3e-3),
                                    Numbers(kNaN, kNaN, kNaN, "seed 3: no fix"),
                                    Numbers(kNaN, kNaN, kNaN, "seed 4: diverged")};
  runs[2].final_sigma_rad = kNaN;
  runs[3].final_sigma_rad = kNaN;
  runs[2].run_time_s = kNaN;
  runs[3].run_time_s = kNaN;
  const McMethodStats s = StatsOf(Method::kBatch, runs);
  EXPECT_EQ(s.method, Method::kBatch);
  ASSERT_EQ(s.error_at_km_rad.size(), 2u);
  EXPECT_EQ(s.error_at_km_rad[0].count, 2);
  EXPECT_NEAR(s.error_at_km_rad[0].mean, 2e-3, 1e-15);
  EXPECT_EQ(s.error_at_km_rad[1].count, 1);  // the second run did not reach 20 km
  EXPECT_NEAR(s.final_error_rad.mean, 1e-3, 1e-15);
  EXPECT_NEAR(s.final_error_rad.rms, std::sqrt(5.0) * 1e-3, 1e-15);
  EXPECT_NEAR(s.final_sigma_rad.mean, 1e-3, 1e-15);
  EXPECT_DOUBLE_EQ(s.run_time_s.mean, 0.25);
  EXPECT_EQ(s.failures, 2);
  EXPECT_EQ(s.first_failure, "seed 3: no fix");
}

TEST(InflightMonteCarlo, NumbersOfAResultKeepRadiansAndSeconds) {
  MethodResult r;
  r.error_at_km_rad = {1e-3, kNaN};
  r.final_error_rad = -2e-3;
  r.final_sigma_rad = 4e-4;
  r.run_time_s = 1.5;
  const McRunNumbers n = NumbersOf(r);
  ASSERT_EQ(n.error_at_km_rad.size(), 2u);
  EXPECT_DOUBLE_EQ(n.error_at_km_rad[0], 1e-3);
  EXPECT_TRUE(std::isnan(n.error_at_km_rad[1]));
  EXPECT_DOUBLE_EQ(n.final_error_rad, -2e-3);
  EXPECT_DOUBLE_EQ(n.final_sigma_rad, 4e-4);
  EXPECT_DOUBLE_EQ(n.run_time_s, 1.5);
  EXPECT_TRUE(n.failure.empty());
}

TEST(InflightMonteCarlo, ErrorsCsvHasOneRowPerRunAndMethodInArcmin) {
  McResult mc;
  mc.options.seed = 7;
  mc.options.methods = {Method::kDistance, Method::kBatch};
  mc.options.at_km = {10.0, 20.0};
  const double arcmin = kDegToRad / 60.0;
  mc.runs = {{Numbers(1.0 * arcmin, 2.0 * arcmin, 3.0 * arcmin), Numbers(kNaN, kNaN, kNaN, "x")},
             {Numbers(4.0 * arcmin, 5.0 * arcmin, 6.0 * arcmin), Numbers(1.0 * arcmin, 1.0 * arcmin, 1.0 * arcmin)}};
  const std::string path = ::testing::TempDir() + "inflight_mc_errors.csv";
  WriteMcErrorsCsv(mc, path);
  std::ifstream f(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(f, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0],
            "run,seed,method,error_10km_arcmin,error_20km_arcmin,final_error_arcmin,final_sigma_arcmin,run_time_s");
  const auto fields = [](const std::string& line) {
    std::vector<std::string> out;
    std::stringstream ss(line);
    for (std::string field; std::getline(ss, field, ',');) out.push_back(field);
    return out;
  };
  const auto expect_row = [&](const std::string& line, const std::string& head, const std::vector<double>& values) {
    const std::vector<std::string> f = fields(line);
    ASSERT_EQ(f.size(), 3 + values.size()) << line;
    EXPECT_EQ(f[0] + "," + f[1] + "," + f[2], head) << line;
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (std::isnan(values[i])) {
        EXPECT_EQ(f[3 + i], "nan") << line;
      } else {
        EXPECT_NEAR(std::stod(f[3 + i]), values[i], 1e-12) << line;
      }
    }
  };
  expect_row(lines[1], "0,7,distance", {1.0, 2.0, 3.0, 1.5, 0.25});
  expect_row(lines[2], "0,7,batch", {kNaN, kNaN, kNaN, kNaN, 0.25});
  expect_row(lines[3], "1,8,distance", {4.0, 5.0, 6.0, 3.0, 0.25});
  expect_row(lines[4], "1,8,batch", {1.0, 1.0, 1.0, 0.5, 0.25});
}

TEST(InflightMonteCarlo, RejectsBadOptions) {
  const sim::Scenario scenario;
  McOptions options;
  options.runs = 0;
  EXPECT_THROW(RunInflightMonteCarlo(scenario, InflightConfig(), options), std::invalid_argument);
  options.runs = 1;
  options.threads = -1;
  EXPECT_THROW(RunInflightMonteCarlo(scenario, InflightConfig(), options), std::invalid_argument);
  options.threads = 1;
  options.methods.clear();
  EXPECT_THROW(RunInflightMonteCarlo(scenario, InflightConfig(), options), std::invalid_argument);
}

TEST(InflightMonteCarlo, TheBoundShrinksWithDistanceAndTheBatchReportsIt) {
  // The preset (about 105 km south at Mach 0.7): the bound, from noise-free fixes weighted
  // with the receiver's sigma, decreases with the distance flown; a run on noisy data
  // records every method at 10..100 km, and its batch reports sigma within 25 % of the
  // bound at 100 km (its GPS sigma is estimated from the fixes, not given).
  const sim::Scenario s = sim::LoadScenario("inflight-mach07-south");
  const std::vector<double> at_km = {10.0, 20.0, 50.0, 100.0};
  const mc::MethodRecord bound = InflightBound(s, InflightConfig(), at_km, 1);
  ASSERT_EQ(bound.quantities.size(), 2u);
  const mc::Quantity& b = bound.quantities[0];
  ASSERT_EQ(b.points(), 4);
  for (int p = 1; p < 4; ++p) EXPECT_LT(b.covariance[p], b.covariance[p - 1]) << at_km[p];
  const mc::RunRecord r = InflightMcRun(s, InflightConfig(), {Method::kKalman, Method::kBatch}, at_km, 1, 0);
  ASSERT_EQ(r.methods.size(), 2u);
  for (const mc::MethodRecord& m : r.methods) {
    ASSERT_TRUE(m.failure.empty()) << m.failure;
    EXPECT_EQ(m.quantities[0].axis, at_km);
    EXPECT_TRUE(std::isfinite(m.quantities[1].error[0])) << m.method;
  }
  EXPECT_NEAR(std::sqrt(r.methods[1].quantities[0].covariance[3] / b.covariance[3]), 1.0, 0.25);
}

}  // namespace inflight_alignment_monte_carlo_test
}  // namespace navtwin::inflight
