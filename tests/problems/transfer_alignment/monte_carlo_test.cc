// Transfer alignment under `navtwin mc`: one run's record (quantities on the whole-second
// grid, the final joint covariance the method reported) and the Cramér-Rao bound from the
// batch at noise-free data.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/sim/scenario.h"
#include "problems/transfer_alignment/monte_carlo.h"
#include "tests/problems/transfer_alignment/short_scenario.h"

namespace navtwin::transfer {
namespace transfer_monte_carlo_test {

/// 8 s of the short flight (6 s of wing rock) with a 0.2 s delay.
sim::Scenario McScenario() { return test_scenarios::ShortTransferScenario(6.0, 0.2); }

const mc::Quantity& Find(const mc::MethodRecord& m, const std::string& name) {
  for (const mc::Quantity& q : m.quantities) {
    if (q.name == name) return q;
  }
  throw std::runtime_error("no quantity " + name);
}

TEST(TransferMcTest, ARunRecordsEveryMethodOnTheGridWithItsFinalCovariance) {
  const mc::RunRecord r = TransferMcRun(McScenario(), TransferConfig(), {Method::kHistory, Method::kBatch}, 3, 2);
  EXPECT_EQ(r.run, 2);
  EXPECT_EQ(r.seed, 3u);
  ASSERT_EQ(r.methods.size(), 2u);
  for (const mc::MethodRecord& m : r.methods) {
    ASSERT_TRUE(m.failure.empty()) << m.method << ": " << m.failure;
    const mc::Quantity& mis = Find(m, "misalignment");
    EXPECT_EQ(mis.axis, (std::vector<double>{1, 2, 3, 4, 5, 6, 7, 8})) << m.method;
    const mc::Quantity& joint = Find(m, "misalignment_delay");
    ASSERT_EQ(joint.points(), 1);
    // The final point of misalignment carries the joint covariance's 3 x 3 block, and the
    // same error: one estimate, one covariance.
    const int last = mis.points() - 1;
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(mis.error[last * 3 + i], joint.error[i]) << m.method;
      for (int j = 0; j < 3; ++j) EXPECT_EQ(mis.covariance[last * 9 + i * 3 + j], joint.covariance[i * 4 + j]);
    }
    // Converged: the misalignment within 1 mrad of the truth (tens of 0.01 mrad sigma) and
    // the delay within 1 ms (its sigma: 0.01-0.1 ms).
    EXPECT_LT(std::hypot(joint.error[0], joint.error[1], joint.error[2]), 1e-3) << m.method;
    EXPECT_LT(std::abs(joint.error[3]), 1e-3) << m.method;
    const mc::Quantity& attitude = Find(m, "attitude");
    EXPECT_TRUE(std::isnan(attitude.covariance[last * 9]));  // no sigma reported for it
    EXPECT_TRUE(std::isfinite(attitude.error[last * 3]));
  }
  // The batch reports one estimate: the same at every grid point.
  const mc::Quantity& batch_mis = Find(r.methods[1], "misalignment");
  EXPECT_EQ(batch_mis.error[0], batch_mis.error[3 * 3]);
}

TEST(TransferMcTest, TheBoundIsTheBatchCovarianceAtTheTruth) {
  const sim::Scenario s = McScenario();
  const mc::MethodRecord bound = TransferBound(s, TransferConfig(), 3);
  const mc::Quantity& joint = Find(bound, "misalignment_delay");
  // Noise-free data: the batch sits on the truth (to 0.01 mrad and 1 us: the priors, centred
  // on the initial guesses, pull it by ~1 urad), and its covariance is the bound; a batch on
  // noisy data (linearised elsewhere, by 0.1 mrad) reports sigma within 5 % of it (the
  // information hardly depends on where it is evaluated).
  EXPECT_LT(std::hypot(joint.error[0], joint.error[1], joint.error[2]), 1e-5);
  EXPECT_LT(std::abs(joint.error[3]), 1e-6);
  const mc::RunRecord noisy = TransferMcRun(s, TransferConfig(), {Method::kBatch}, 3, 0);
  const mc::Quantity& reported = Find(noisy.methods[0], "misalignment_delay");
  for (int i = 0; i < 4; ++i) {
    const double bound_sigma = std::sqrt(joint.covariance[i * 4 + i]);
    EXPECT_GT(bound_sigma, 0.0);
    EXPECT_NEAR(std::sqrt(reported.covariance[i * 4 + i]) / bound_sigma, 1.0, 0.05) << i;
  }
}

}  // namespace transfer_monte_carlo_test
}  // namespace navtwin::transfer
