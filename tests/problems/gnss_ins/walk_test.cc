// The real handheld walk (../shared/data/rtklib-walk, see its README): the shipped
// configuration data/configs/rtklib-walk.yaml (static alignment with a heading search, no
// heading reference otherwise), 15 s GNSS outages every 45 s from 30 s, scored against the
// RTK solution (a GNSS reference: the antenna position). Filter, RTS and batch.
#include <stdlib.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "problems/gnss_ins/ins_vocabulary.h"
#include "problems/gnss_ins/batch.h"
#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/densify.h"
#include "problems/gnss_ins/filter.h"
#include "problems/gnss_ins/inputs.h"
#include "problems/gnss_ins/run.h"
#include "problems/gnss_ins/scoring.h"
#include "tests/test_data.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_walk_test {

using navtwin::testing::DataPath;

struct Figures {
  double drift_h_m, drift_v_m;      // RMS over the outages of each outage's max error
  double outside_h_m, outside_v_m;  // RMS outside the outages
  std::size_t outages;
};

Figures Summarise(const TrajectoryScorer& scorer) {
  const ScoreReport r = scorer.Report();
  return {r.outage_horizontal_rms_m, r.outage_vertical_rms_m, r.outside.HorizontalRms_m(), r.outside.Rms(2),
          r.outages.size()};
}

void Print(const char* method, const Figures& f) {
  std::cout << method << ": outage drift RMS H " << f.drift_h_m << " m, V " << f.drift_v_m
            << " m; RMS outside outages H " << f.outside_h_m << " m, V " << f.outside_v_m << " m\n";
}

TEST(RtklibWalk, HeadingSearchThenFilterRtsAndBatchBridgeOutages) {
  const std::string imu = DataPath("rtklib-walk/imu_1730.csv");
  const std::string gnss = DataPath("rtklib-walk/gnss_1730_sf.pos");
  NAVTWIN_REQUIRE_DATA(imu);
  NAVTWIN_REQUIRE_DATA(imu + ".tag");  // RTKLIB time tags: device ticks -> GPS time
  NAVTWIN_REQUIRE_DATA(gnss);

  GnssInsConfig config = LoadGnssInsConfig(std::string(NAVTWIN_SOURCE_DIR) + "/data/configs/rtklib-walk.yaml");
  ASSERT_EQ(config.init.source, InitConfig::Source::kStaticAlignment);
  ASSERT_EQ(config.init.heading, InitConfig::Heading::kSearch);
  config.outages.start_s = 30.0;
  config.outages.len_s = 15.0;
  config.outages.period_s = 45.0;
  const Inputs inputs = LoadInputs({imu, gnss, "", "", "", NAN}, config);
  ASSERT_EQ(inputs.outages.size(), 3u);  // 30-45, 75-90, 120-135 s of a 134 s record

  // The heading search (its table of scores goes to the test log). A sweep of given
  // headings (lead, same data, yaw std 30 deg) converged from 135, 180 and -135 deg and
  // diverged from 0, +-45 and +-90 deg: the search must pick one of the first three.
  std::ostringstream search_log;
  const FilterStart start = InitialFilterState(inputs, config, &search_log);
  std::cout << search_log.str();
  const double yaw_rad = EulerFromQuat<double>(start.state.nav.q_n_b).z();
  EXPECT_LE(std::abs(WrapPi(yaw_rad - M_PI)), M_PI / 4 + 1e-9) << "chosen yaw " << yaw_rad * kRadToDeg << " deg";

  const Eigen::Vector3d& lever = config.installation.antenna_lever_arm_b_m;
  std::unique_ptr<TrajectoryScorer> filter_score = OpenReference(gnss, inputs.outages, lever);
  const FilterResult fr =
      RunFilter(inputs, config, true, [&](const NavEpoch& e) { filter_score->Add(e); }, nullptr);
  ASSERT_TRUE(fr.rts.has_value());
  std::unique_ptr<TrajectoryScorer> rts_score = OpenReference(gnss, inputs.outages, lever);
  Densify(*fr.rts, inputs, [&](const NavEpoch& e) { rts_score->Add(e); });
  const Solution batch = RunBatch(inputs, config, *fr.rts, nullptr);
  std::unique_ptr<TrajectoryScorer> batch_score = OpenReference(gnss, inputs.outages, lever);
  Densify(batch, inputs, [&](const NavEpoch& e) { batch_score->Add(e); });

  const Figures f = Summarise(*filter_score);
  const Figures s = Summarise(*rts_score);
  const Figures b = Summarise(*batch_score);
  Print("filter", f);
  Print("rts", s);
  Print("batch", b);
  ASSERT_EQ(f.outages, 3u);

  // Filter: a consumer MEMS IMU coasting 15 s in tight turns drifts metres (the issue:
  // about 4-10 m); below 1 m the outages would not have been applied, above 15 m the
  // heading or the biases were not found. Measured 2.0 m H.
  EXPECT_GT(f.drift_h_m, 1.0);
  EXPECT_LT(f.drift_h_m, 15.0);
  // Outside the outages the filter follows 1-cm RTK fixes, except for the seconds after
  // each outage it takes to pull back: 0.5 m (measured 0.10 m H, 0.05 m V).
  EXPECT_LT(f.outside_h_m, 0.5);
  EXPECT_LT(f.outside_v_m, 0.5);
  // RTS: the fixes on both sides of an outage tie the drift down to decimetres: < 1 m
  // (measured 0.12 m H, 0.25 m V). Outside the outages 10 cm, ten RTK sigmas (measured
  // 2.3 cm, 2.2 cm).
  EXPECT_LT(s.drift_h_m, 1.0);
  EXPECT_LT(s.drift_v_m, 1.0);
  EXPECT_LT(s.outside_h_m, 0.1);
  EXPECT_LT(s.outside_v_m, 0.1);
  // Batch, started from the RTS: the same bounds (measured 0.10 m H, 0.26 m V drift).
  EXPECT_LT(b.drift_h_m, 1.0);
  EXPECT_LT(b.drift_v_m, 1.0);
  EXPECT_LT(b.outside_h_m, 0.1);
  EXPECT_LT(b.outside_v_m, 0.1);
}

// The same record through the run the `smooth` command makes, with the default chi-square
// gate (0.9999): the batch's variance components find the handheld's noise far above the
// configured one (its unmodelled errors in tight turns), and with it the sigmas inside the
// outages are honest where they were 1.5 to 8 times too small. The goals: RMS err/sigma of
// each position axis inside the outages within 0.35-1.5 for the batch and the adapted RTS
// (measured 0.49-0.79; the upper bound is the issue's, the lower one allows the
// conservative side by the factor that the 171 correlated epochs of three outages leave
// uncertain), at most 2 for the adapted filter (measured 0.75-1.12); the adapted filter
// passes the gate (measured 1 of 328 positions rejected, where the configured noise had 105
// and 9 resets).
TEST(RtklibWalk, VarianceComponentsMakeTheSigmasHonestInsideTheOutages) {
  const std::string imu = DataPath("rtklib-walk/imu_1730.csv");
  const std::string gnss = DataPath("rtklib-walk/gnss_1730_sf.pos");
  NAVTWIN_REQUIRE_DATA(imu);
  NAVTWIN_REQUIRE_DATA(gnss);
  GnssInsConfig config = LoadGnssInsConfig(std::string(NAVTWIN_SOURCE_DIR) + "/data/configs/rtklib-walk.yaml");
  config.outages.start_s = 30.0;
  config.outages.len_s = 15.0;
  config.outages.period_s = 45.0;
  config.filter.gate_probability = 0.9999;
  RunOptions options;
  options.paths = {imu, gnss, "", "", "", NAN};
  options.truth = gnss;
  std::string out = ::testing::TempDir() + "navtwin_walk_XXXXXX";
  ASSERT_NE(::mkdtemp(out.data()), nullptr);
  options.out_dir = out;
  options.command = "smooth";
  options.methods = RunMethods::kAll;
  const GnssInsRun run = RunGnssIns(options, config);
  ASSERT_EQ(run.methods.size(), 5u);
  for (const MethodRun& m : run.methods) {
    ASSERT_TRUE(m.errors.has_value());
    const ConsistencyStats& c = m.errors->consistency_inside;
    std::cout << m.name << ": err/sigma inside the outages N " << c.RmsRatio(0) << " E " << c.RmsRatio(1) << " D "
              << c.RmsRatio(2) << ", NEES " << c.PosNeesMean() << "\n";
    const bool adapted = m.name == "batch" || m.name == "rts_adapted" || m.name == "filter_adapted";
    if (!adapted) continue;
    for (int k = 0; k < 3; ++k) {
      EXPECT_LE(c.RmsRatio(k), m.name == "filter_adapted" ? 2.0 : 1.5) << m.name << " axis " << k;
      EXPECT_GE(c.RmsRatio(k), 0.35) << m.name << " axis " << k;
    }
  }
  const ResidualStats& imu_rows = run.methods[2].solution.residuals.at("imu_velocity_position");
  EXPECT_TRUE(imu_rows.adapted);
  EXPECT_GT(imu_rows.sigma_scale, 3.0);  // measured 13.6 over the configured (4 x data sheet) VRW
  const Solution& adapted_filter = run.methods[3].solution;
  const MeasurementCount& fixes = adapted_filter.counts.at("gnss_position");
  EXPECT_LE(fixes.rejected, 7u);  // 2 % of 328
  EXPECT_EQ(adapted_filter.counts.at("gnss_reset").used, 0u);
  EXPECT_LT(adapted_filter.residuals.at("gnss_position").ChiSquarePerDof(), 1.5);  // measured 1.05
}

}  // namespace gnss_ins_walk_test
}  // namespace navtwin::gnss_ins
