// GNSS/INS under `navtwin mc`: one run of filter, RTS and batch on a short simulated flight
// (quantities on the whole-second grid with the reported covariances) and the Cramér-Rao
// bound from the batch at noise-free data.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "problems/gnss_ins/monte_carlo.h"

namespace navtwin::gnss_ins {
namespace gnss_ins_monte_carlo_test {

/// A 60 s flight with a turn and a climb, MEMS-like IMU, 5 Hz GNSS, magnetometer.
std::string ScenarioFile() {
  static const std::string path = [] {
    const std::string p = ::testing::TempDir() + "navtwin_mc_gnss_ins_" + std::to_string(::getpid()) + ".yaml";
    std::ofstream f(p);
    f << R"(name: mc-short-flight
start: {lat_deg: 37.45, lon_deg: 126.65, h_m: 300}
trajectory:
  initial: {speed_mps: 30, heading_deg: 45}
  segments:
    - {kind: cruise, duration_s: 15}
    - {kind: turn, duration_s: 20, heading_change_deg: 90}
    - {kind: climb, duration_s: 15, vertical_speed_mps: 3}
    - {kind: cruise, duration_s: 10}
imu:
  rate_hz: 100
  errors:
    gyro: {bias_deg_h: 100, arw_deg_sqrt_h: 1}
    accel: {bias_ug: 5000, vrw_m_s_sqrt_h: 0.2}
gnss: {rate_hz: 5, position_sigma_m: [1.5, 3.0], velocity_sigma_mps: 0.05}
mag: {rate_hz: 10, declination_deg: -8.0, noise_uT: 0.3}
)";
    return p;
  }();
  return path;
}

const mc::Quantity& Find(const mc::MethodRecord& m, const std::string& name) {
  for (const mc::Quantity& q : m.quantities) {
    if (q.name == name) return q;
  }
  throw std::runtime_error("no quantity " + name);
}

TEST(GnssInsMcTest, ARunHasEveryMethodsErrorsAndPositiveDefiniteCovariances) {
  // Every method, the adapted filter and RTS included (the batch's variance components
  // rescale the noise on this record, so they are runs of their own).
  GnssInsMcSetup setup;
  setup.scenario = ScenarioFile();
  const mc::RunRecord r = GnssInsMcRun(setup, 7, 0);
  ASSERT_EQ(r.methods.size(), 5u);  // filter, rts, batch, filter_adapted, rts_adapted
  for (const mc::MethodRecord& m : r.methods) {
    ASSERT_TRUE(m.failure.empty()) << m.method << ": " << m.failure;
    for (const char* name : {"position", "velocity", "attitude"}) {
      const mc::Quantity& q = Find(m, name);
      ASSERT_EQ(q.points(), 60) << m.method << " " << name;  // whole seconds 1..60
      for (int p = 0; p < q.points(); ++p) {
        const Eigen::Map<const Eigen::Matrix3d> P(&q.covariance[p * 9]);
        ASSERT_TRUE(P.allFinite()) << m.method << " " << name << " t " << q.axis[p];
        EXPECT_LT((P - P.transpose()).norm(), 1e-12 * P.norm());
        EXPECT_EQ(Eigen::LLT<Eigen::Matrix3d>(P).info(), Eigen::Success);
      }
    }
    // GNSS at 1.5 m (horizontal) sigma: the final position within 5 m.
    const mc::Quantity& pos = Find(m, "position");
    EXPECT_LT(Eigen::Map<const Eigen::Vector3d>(&pos.error[59 * 3]).norm(), 5.0) << m.method;
  }
  EXPECT_EQ(r.methods[3].method, "filter_adapted");
  EXPECT_NE(Find(r.methods[3], "attitude").covariance, Find(r.methods[0], "attitude").covariance);
}

TEST(GnssInsMcTest, TheBoundLiesBelowTheFiltersSigmaInsideTheFlight) {
  GnssInsMcSetup setup;
  setup.scenario = ScenarioFile();
  setup.methods = {"filter"};
  const mc::MethodRecord bound = GnssInsBound(setup, 7);
  const mc::RunRecord r = GnssInsMcRun(setup, 7, 0);
  for (const char* name : {"position", "attitude"}) {
    const mc::Quantity& b = Find(bound, name);
    const mc::Quantity& f = Find(r.methods[0], name);
    // At t = 30 s the smoother's information (past and future) exceeds the filter's (past).
    const int p = 29;
    for (int i = 0; i < 3; ++i) {
      EXPECT_LT(b.covariance[p * 9 + i * 4], f.covariance[p * 9 + i * 4]) << name << " " << i;
      EXPECT_GT(b.covariance[p * 9 + i * 4], 0.0) << name << " " << i;
    }
  }
}

}  // namespace gnss_ins_monte_carlo_test
}  // namespace navtwin::gnss_ins
