#include "solvers/monte_carlo.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/sim/random.h"

namespace navtwin {
namespace solvers_monte_carlo_test {

// A run's result: a few normal draws from the run's own stream, like a simulated trial.
double RunValue(int run) {
  sim::Rng rng = sim::Rng(7).Stream("run " + std::to_string(run));
  double sum = 0.0;
  for (int i = 0; i < 50; ++i) sum += rng.Normal(1.0) * rng.Uniform();
  return sum;
}

// Per-run slots, reduced in run order after the runs.
double ParallelSum(int runs, int threads) {
  std::vector<double> value(runs, 0.0);
  RunParallel(runs, threads, [&](int run, int) { value[run] = RunValue(run); });
  double sum = 0.0;
  for (const double v : value) sum += v;
  return sum;
}

TEST(MonteCarloRunnerTest, ResultsDoNotDependOnTheThreadCount) {
  const double one = ParallelSum(2000, 1);
  // Same draws, same reduction order: bit-identical, hence EXPECT_EQ on doubles.
  EXPECT_EQ(one, ParallelSum(2000, 2));
  EXPECT_EQ(one, ParallelSum(2000, 3));
  EXPECT_EQ(one, ParallelSum(2000, 0));  // hardware concurrency
}

TEST(MonteCarloRunnerTest, EveryRunExecutesExactlyOnceOnAValidWorker) {
  const int runs = 5000, threads = 2;
  std::vector<std::atomic<int>> count(runs);
  std::vector<std::atomic<int>> by_worker(threads);
  std::atomic<bool> bad_worker{false};
  RunParallel(runs, threads, [&](int run, int worker) {
    ++count[run];
    if (worker < 0 || worker >= threads) {
      bad_worker = true;
      return;
    }
    ++by_worker[worker];
  });
  EXPECT_FALSE(bad_worker);
  for (int r = 0; r < runs; ++r) ASSERT_EQ(count[r].load(), 1) << "run " << r;
  EXPECT_EQ(by_worker[0] + by_worker[1], runs);
}

TEST(MonteCarloRunnerTest, ProgressCountsEveryRunInOrder) {
  std::vector<int> seen;
  RunParallel(300, 2, [](int, int) {}, [&](int done, int runs) {
    EXPECT_EQ(runs, 300);
    seen.push_back(done);
  });
  ASSERT_EQ(seen.size(), 300u);
  for (int i = 0; i < 300; ++i) EXPECT_EQ(seen[i], i + 1);
}

TEST(MonteCarloRunnerTest, WorkerCountIsClampedToTheRuns) {
  EXPECT_EQ(MonteCarloWorkers(10, 2), 2);
  EXPECT_EQ(MonteCarloWorkers(1, 8), 1);
  EXPECT_EQ(MonteCarloWorkers(0, 4), 1);
  EXPECT_GE(MonteCarloWorkers(100, 0), 1);
  EXPECT_GE(MonteCarloWorkers(100, -3), 1);
  int calls = 0;
  RunParallel(0, 2, [&](int, int) { ++calls; });
  EXPECT_EQ(calls, 0);
  EXPECT_THROW(RunParallel(-1, 2, [](int, int) {}), std::invalid_argument);
}

TEST(MonteCarloRunnerTest, AnExceptionInARunStopsTheRunsAndIsRethrown) {
  std::atomic<int> executed{0};
  // Every run but the failing one takes 20 us, so that all 100000 would take 2 s on the
  // other worker: the worker that draws run 10 throws after at most a few runs even when
  // it is descheduled for a while (with empty runs, the other worker could finish all of
  // them in a millisecond before run 10 even starts, which made this test flaky).
  EXPECT_THROW(RunParallel(100000, 2,
                           [&](int run, int) {
                             ++executed;
                             if (run == 10) throw std::runtime_error("run 10 failed");
                             std::this_thread::sleep_for(std::chrono::microseconds(20));
                           }),
               std::runtime_error);
  // The workers stop taking runs once run 10 fails: far fewer than all were executed
  // (the other worker may finish a handful meanwhile; 100000 would mean no stop at all).
  EXPECT_LT(executed.load(), 100000);
}

TEST(MonteCarloRunnerTest, ThreadCpuTimeGrowsWithWork) {
  const double t0 = ThreadCpuTime_s();
  volatile double x = 0.0;
  for (int i = 0; i < 2000000; ++i) x = x + 1e-9 * i;
  const double t1 = ThreadCpuTime_s();
  EXPECT_GT(t1, t0);
  // 2e6 additions take milliseconds, not seconds (a wrong unit would give 1e3-1e9 times more).
  EXPECT_LT(t1 - t0, 1.0);
}

}  // namespace solvers_monte_carlo_test
}  // namespace navtwin
