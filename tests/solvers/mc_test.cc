// The Monte Carlo engine of `navtwin mc`: run records as bytes, the run-order statistics
// (RMS, mean sigma, ANEES and its chi-square bounds, 3-sigma share, finals), the outputs,
// and the distribution of runs over threads (in run order, failures passed on).
#include <sys/stat.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "solvers/eskf.h"
#include "solvers/mc_distribute.h"
#include "solvers/mc_output.h"
#include "solvers/mc_record.h"
#include "solvers/mc_statistics.h"

namespace navtwin::mc {
namespace solvers_mc_test {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// A record of one method with a 2-component quantity on axis {1, 2}.
RunRecord TwoPointRecord(int run, const std::vector<double>& errors, const std::vector<double>& covariances) {
  RunRecord r;
  r.run = run;
  r.seed = 100 + run;
  MethodRecord m;
  m.method = "filter";
  m.run_time_s = 0.5;
  Quantity q = Quantity::Empty("position", "m", 1.0, "t_s", {"n", "e"}, {1.0, 2.0});
  q.Set(0, &errors[0], &covariances[0]);
  q.Set(1, &errors[2], &covariances[4]);
  m.quantities.push_back(q);
  r.methods.push_back(m);
  return r;
}

TEST(McRecordTest, BytesRoundTripKeepEveryBitAndRejectCorruptInput) {
  RunRecord r = TwoPointRecord(7, {0.1, -0.2, kNaN, 0.3}, {1, 0.2, 0.2, 2, 1, 0, 0, 1});
  r.methods.push_back(MethodRecord{"batch", "it threw", 1.25, {}});
  const std::string bytes = SerializeRunRecord(r);
  const RunRecord back = DeserializeRunRecord(bytes);
  EXPECT_EQ(SerializeRunRecord(back), bytes);
  ASSERT_EQ(back.methods.size(), 2u);
  EXPECT_EQ(back.run, 7);
  EXPECT_EQ(back.seed, 107u);
  EXPECT_EQ(back.methods[1].failure, "it threw");
  const Quantity& q = back.methods[0].quantities[0];
  EXPECT_EQ(q.components, (std::vector<std::string>{"n", "e"}));
  EXPECT_TRUE(std::isnan(q.error[2]));
  EXPECT_EQ(q.covariance[1], 0.2);
  EXPECT_THROW(DeserializeRunRecord(bytes.substr(0, bytes.size() - 3)), std::runtime_error);
  EXPECT_THROW(DeserializeRunRecord(bytes + "x"), std::runtime_error);
  EXPECT_THROW(DeserializeRunRecord("garbage"), std::runtime_error);
}

TEST(McStatisticsTest, PointStatisticsAreTheDefinitions) {
  // Three runs; point 0 has a correlated covariance, point 1 a missing error in run 2.
  const std::vector<std::vector<double>> e = {{0.1, -0.2, 1.0, 0.0}, {-0.3, 0.4, -1.0, 2.0}, {0.2, 0.1, kNaN, 0.0}};
  const std::vector<double> P = {0.04, 0.01, 0.01, 0.09, 1.0, 0.0, 0.0, 4.0};
  Accumulator acc;
  for (int run = 0; run < 3; ++run) acc.Add(TwoPointRecord(run, e[run], P));
  const std::vector<MethodStatistics> stats = acc.Finish();
  ASSERT_EQ(stats.size(), 1u);
  const QuantityStatistics& q = stats[0].quantities[0];
  const PointStatistics& p0 = q.points[0];
  EXPECT_EQ(p0.runs, 3);
  EXPECT_NEAR(p0.rms[0], std::sqrt((0.01 + 0.09 + 0.04) / 3.0), 1e-15);
  EXPECT_NEAR(p0.sigma_mean[1], 0.3, 1e-15);
  // |e| <= 3 sigma: n 0.1, 0.3, 0.2 against 0.6 (all); e 0.2, 0.4, 0.1 against 0.9 (all).
  EXPECT_EQ(p0.within_3sigma[0], 1.0);
  Eigen::Matrix2d cov;
  cov << 0.04, 0.01, 0.01, 0.09;
  double nees = 0.0;
  for (int run = 0; run < 3; ++run) {
    const Eigen::Vector2d v(e[run][0], e[run][1]);
    nees += v.dot(cov.llt().solve(v));
  }
  EXPECT_NEAR(p0.anees, nees / 6.0, 1e-12);
  EXPECT_NEAR(p0.anees_lo, ChiSquareQuantile(0.025, 6) / 6.0, 1e-12);
  EXPECT_NEAR(p0.anees_hi, ChiSquareQuantile(0.975, 6) / 6.0, 1e-12);
  const PointStatistics& p1 = q.points[1];
  EXPECT_EQ(p1.runs, 2);  // run 2's error is NaN there
  EXPECT_NEAR(p1.rms[1], std::sqrt(4.0 / 2.0), 1e-15);
  EXPECT_EQ(p1.within_3sigma[1], 1.0);
  // Finals: the last point of every run, in run order.
  ASSERT_EQ(q.final_error.size(), 6u);
  EXPECT_EQ(q.final_error[2], -1.0);
  EXPECT_TRUE(std::isnan(q.final_error[4]));
  EXPECT_EQ(q.final_sigma[1], 2.0);
}

TEST(McStatisticsTest, AFailedRunKeepsTheFinalsAlignedAndIsCounted) {
  Accumulator acc;
  RunRecord failed;
  failed.run = 0;
  failed.seed = 5;
  failed.methods.push_back(MethodRecord{"filter", "diverged", 0.0, {}});
  acc.Add(failed);
  acc.Add(TwoPointRecord(1, {1, 1, 1, 1}, {1, 0, 0, 1, 1, 0, 0, 1}));
  const std::vector<MethodStatistics> stats = acc.Finish();
  EXPECT_EQ(stats[0].failures, 1);
  EXPECT_EQ(stats[0].first_failure, "seed 5: diverged");
  const QuantityStatistics& q = stats[0].quantities[0];
  ASSERT_EQ(q.final_error.size(), 4u);
  EXPECT_TRUE(std::isnan(q.final_error[0]));
  EXPECT_EQ(q.final_error[2], 1.0);
  EXPECT_EQ(q.points[0].runs, 1);
}

TEST(McStatisticsTest, AnotherAxisForAQuantityIsAnError) {
  Accumulator acc;
  acc.Add(TwoPointRecord(0, {1, 1, 1, 1}, {1, 0, 0, 1, 1, 0, 0, 1}));
  RunRecord other = TwoPointRecord(1, {1, 1, 1, 1}, {1, 0, 0, 1, 1, 0, 0, 1});
  other.methods[0].quantities[0].axis[1] = 3.0;
  EXPECT_THROW(acc.Add(other), std::logic_error);
}

TEST(McStatisticsTest, ConsistentGaussianErrorsGiveAneesInsideTheBounds) {
  // 400 runs of e ~ N(0, P) with the P reported: ANEES within its 95 % bounds and the
  // RMS / sigma ratio near 1 (seeded; 400 runs: ratio within 10 %, 2.5 standard errors).
  Eigen::Matrix3d P;
  P << 4.0, 1.0, 0.5, 1.0, 2.0, 0.3, 0.5, 0.3, 1.0;
  const Eigen::Matrix3d L = P.llt().matrixL();
  std::mt19937_64 rng(42);
  std::normal_distribution<double> normal(0.0, 1.0);
  Accumulator acc;
  for (int run = 0; run < 400; ++run) {
    const Eigen::Vector3d e = L * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    RunRecord r;
    r.run = run;
    Quantity q = Quantity::Empty("x", "m", 1.0, "t_s", {"a", "b", "c"}, {0.0});
    const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> Pr = P;
    q.Set(0, e.data(), Pr.data());
    r.methods.push_back(MethodRecord{"m", "", 0.0, {q}});
    acc.Add(r);
  }
  const std::vector<MethodStatistics> stats = acc.Finish();
  const PointStatistics& p = stats[0].quantities[0].points[0];
  EXPECT_GE(p.anees, p.anees_lo);
  EXPECT_LE(p.anees, p.anees_hi);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(p.rms[i] / p.sigma_mean[i], 1.0, 0.1) << i;
}

TEST(McStatisticsTest, TheBoundIsMatchedByQuantityAndAxisPoint) {
  Accumulator acc;
  acc.Add(TwoPointRecord(0, {1, 1, 1, 1}, {1, 0, 0, 1, 1, 0, 0, 1}));
  MethodRecord bound;
  bound.method = "bound";
  Quantity q = Quantity::Empty("position", "m", 1.0, "t_s", {"n", "e"}, {2.0});
  const double zero[2] = {0.0, 0.0}, sigma[2] = {0.5, 0.25};
  q.SetDiagonal(0, zero, sigma);
  bound.quantities.push_back(q);
  const QuantityStatistics s = acc.Finish(&bound)[0].quantities[0];
  EXPECT_TRUE(std::isnan(s.points[0].bound_sigma[0]));  // no bound at t = 1
  EXPECT_EQ(s.points[1].bound_sigma[0], 0.5);
  EXPECT_EQ(s.points[1].bound_sigma[1], 0.25);
}

TEST(McOutputTest, HistogramCountsEveryFiniteValueOnce) {
  const Histogram h = ErrorHistogram({-5.0, -1.0, 0.0, 0.99, 1.0, 3.9, 4.0, kNaN}, 4.0);
  int total = h.below + h.above;
  for (const int c : h.counts) total += c;
  EXPECT_EQ(total, 7);
  EXPECT_EQ(h.below, 1);
  EXPECT_EQ(h.above, 1);  // 4.0 is the upper edge, outside [lo, hi)
  EXPECT_EQ(h.counts[10], 1);  // [0, 0.4): 0.0
  EXPECT_EQ(h.counts[12], 2);  // [0.8, 1.2): 0.99, 1.0
}

TEST(McOutputTest, TheFolderHoldsEveryFileAndTheSummaryNamesTheRuns) {
  Accumulator acc;
  for (int run = 0; run < 2; ++run) acc.Add(TwoPointRecord(run, {0.1, 0.2, 0.3, 0.4}, {1, 0, 0, 1, 1, 0, 0, 1}));
  ExperimentInfo info;
  info.problem = "test";
  info.scenario = "none";
  info.seed = 100;
  info.runs = 2;
  const std::string dir = ::testing::TempDir() + "navtwin_mc_output";
  WriteExperimentFolder(dir, info, acc.Finish(), nullptr);
  for (const char* f : {"/summary.json", "/finals.csv", "/histograms.csv", "/filter/position.csv"}) {
    struct stat st;
    EXPECT_EQ(::stat((dir + f).c_str(), &st), 0) << f;
  }
  std::ifstream finals(dir + "/finals.csv");
  std::stringstream text;
  text << finals.rdbuf();
  EXPECT_NE(text.str().find("1,101,filter,position,e,m,0.4,1\n"), std::string::npos) << text.str();
  const std::string json = SummaryJson(info, acc.Finish(), nullptr);
  EXPECT_NE(json.find("\"runs\":2"), std::string::npos) << json;
  EXPECT_NE(json.find("\"rms\":[0.3,0.4]"), std::string::npos) << json;
}

TEST(McDistributeTest, RecordsArriveInRunOrderWhateverTheThreads) {
  const RankSession session(false);
  for (const int threads : {1, 3}) {
    std::vector<int> order;
    int last_done = 0;
    DistributeRuns(
        session, 257, threads, [](int run) { return std::to_string(run * run); },
        [&](int run, const std::string& bytes) {
          EXPECT_EQ(bytes, std::to_string(run * run));
          order.push_back(run);
        },
        [&](int done, int runs) {
          EXPECT_EQ(runs, 257);
          EXPECT_EQ(done, last_done + 1);
          last_done = done;
        });
    ASSERT_EQ(order.size(), 257u) << threads;
    for (int i = 0; i < 257; ++i) EXPECT_EQ(order[i], i);
  }
}

TEST(McDistributeTest, AFailingRunStopsTheRestAndIsRethrown) {
  const RankSession session(false);
  std::atomic<int> computed{0};
  const auto compute = [&](int run) -> std::string {
    ++computed;
    if (run == 5) throw std::runtime_error("run 5 failed");
    return "ok";
  };
  EXPECT_THROW(DistributeRuns(session, 10000, 1, compute, [](int, const std::string&) {}, nullptr), std::runtime_error);
  EXPECT_EQ(computed.load(), 6);  // one worker: runs 0..5, then nothing
  EXPECT_THROW(DistributeRuns(session, 10000, 2, compute, [](int, const std::string&) {}, nullptr), std::runtime_error);
}

}  // namespace solvers_mc_test
}  // namespace navtwin::mc
