// Diagnose (problems/gnss_ins/diagnostics.h): which runs get which warnings.
#include <gtest/gtest.h>

#include "problems/gnss_ins/diagnostics.h"
#include "problems/gnss_ins/run.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_diagnostics_test {

MethodRun Method(const std::string& name) {
  MethodRun m;
  m.name = name;
  m.solution.method = name;
  return m;
}

bool Contains(const std::vector<std::string>& warnings, const std::string& text) {
  for (const std::string& w : warnings) {
    if (w.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST(GnssInsDiagnostics, CleanRunHasNoWarning) {
  GnssInsRun run;
  MethodRun filter = Method("filter");
  filter.solution.counts["gnss_position"] = {100, 10};  // exactly 10 % of 110: not over
  filter.solution.counts["gnss_reset"] = {0, 0};
  filter.solution.residuals["gnss_position"] = {300, 900.0, 300.0};  // chi2/dof 3.0: not over
  MethodRun batch = Method("batch");
  batch.solution.counts["gnss_position"] = {50, 60};  // the batch's rules are not a gate
  batch.solution.residuals["gyro_bias_process"] = {1000, 500.0, 0.5};  // too few dof to judge
  run.methods = {filter, batch};
  EXPECT_TRUE(Diagnose(run).empty());
}

TEST(GnssInsDiagnostics, RejectionsResetsAndMisfitsAreNamed) {
  GnssInsRun run;
  MethodRun filter = Method("filter");
  filter.solution.counts["gnss_velocity"] = {143, 253};
  filter.solution.counts["gnss_reset"] = {9, 0};
  MethodRun batch = Method("batch");
  ResidualStats misfit{300, 1200.0, 280.0};
  misfit.adapted = true;
  batch.solution.residuals["baro"] = misfit;
  ResidualStats runaway{600, 180.0, 200.0};
  runaway.adapted = true;
  runaway.sigma_scale = 0.027;
  batch.solution.residuals["gnss_position_h"] = runaway;
  run.methods = {filter, batch};
  const std::vector<std::string> w = Diagnose(run);
  ASSERT_EQ(w.size(), 4u);
  EXPECT_TRUE(Contains(w, "batch: gnss_position_h: the variance components scale its sigma by 0.027"));
  EXPECT_TRUE(Contains(w, "filter: gnss_velocity: 253 of 396 rejected by the chi-square gate (64 %)"));
  EXPECT_TRUE(Contains(w, "filter: 9 reset(s)"));
  EXPECT_TRUE(Contains(w, "batch: baro: chi2/dof 4.29 over 280 dof after variance components"));
}

}  // namespace gnss_ins_diagnostics_test
}  // namespace navtwin::gnss_ins
