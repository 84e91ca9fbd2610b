// PX4's own estimate as navigation states (OpenULogPx4Estimate in core/io/ulog.h):
// synthetic logs with known answers, then ekf_failure.ulg (px4-ulog/).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "core/io/input_error.h"
#include "core/io/open.h"
#include "core/io/ulog.h"
#include "core/io/ulog_time.h"
#include "core/rotation.h"
#include "core/units.h"
#include "tests/core/io/io_test_util.h"
#include "tests/core/io/ulog_writer.h"
#include "tests/test_data.h"

namespace navtwin {
namespace ulog_estimate_test {

using testing::ReadAllSamples;
using ulog_writer::Bytes;
using ulog_writer::ULogWriter;

double Yaw(const Eigen::Quaterniond& q) { return EulerFromQuat<double>(q)[2]; }

Bytes Quaternion(const Eigen::Quaterniond& q) {
  Bytes b;
  b.F32(static_cast<float>(q.w())).F32(static_cast<float>(q.x()));
  b.F32(static_cast<float>(q.y())).F32(static_cast<float>(q.z()));
  return b;
}

// Position epochs (s): 0.95 before the velocity/attitude records, 1.05
// inside, 1.10 on samples, 1.15 flagged invalid, 1.27 with an attitude reset between its
// samples, 1.35 next to an invalid velocity, 1.50 in a 1.1 s gap, 2.60 after the records.
std::string EstimateLog(bool with_ellipsoid) {
  ULogWriter w;
  w.Format(std::string("vehicle_global_position:uint64_t timestamp;uint64_t timestamp_sample;"
                       "double lat;double lon;float alt;") +
           (with_ellipsoid ? "float alt_ellipsoid;" : "") + "bool lat_lon_valid;bool alt_valid;")
      .Format(
          "vehicle_local_position:uint64_t timestamp;uint64_t timestamp_sample;float vx;"
          "float vy;float vz;bool v_xy_valid;bool v_z_valid;uint8_t vxy_reset_counter;"
          "uint8_t vz_reset_counter;")
      .Format(
          "vehicle_attitude:uint64_t timestamp;uint64_t timestamp_sample;float[4] q;"
          "uint8_t quat_reset_counter;uint8_t[7] _padding0;")
      .Subscribe(0, 0, "vehicle_global_position")
      .Subscribe(0, 1, "vehicle_local_position")
      .Subscribe(0, 2, "vehicle_attitude");
  // Published 2 ms after the sample time (timestamp_sample is the one used).
  const auto stamp = [](double t_s) {
    const std::uint64_t t_us = static_cast<std::uint64_t>(std::llround(t_s * 1e6));
    return Bytes().U64(t_us + 2000).U64(t_us);
  };
  const double sample_t[] = {1.0, 1.1, 1.2, 1.3, 1.4, 2.5};
  const double yaw_deg[] = {0, 20, 40, 90, 90, 90};
  for (int k = 0; k < 6; ++k) {
    const double v = k < 5 ? k : 0.0;
    const bool valid = k != 4;
    w.Data(1, Bytes(stamp(sample_t[k]))
                  .F32(static_cast<float>(v)).F32(static_cast<float>(2 * v)).F32(static_cast<float>(-v))
                  .U8(valid).U8(1).U8(0).U8(0));
    const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw_deg[k] * kDegToRad, Eigen::Vector3d::UnitZ()));
    w.Data(2, Bytes(stamp(sample_t[k])).Str(Quaternion(q).data()).U8(k >= 3).Zeros(7));
  }
  for (double t : {0.95, 1.05, 1.10, 1.15, 1.27, 1.35, 1.50, 2.60}) {
    Bytes b = stamp(t);
    b.F64(10.0 + t).F64(20.0).F32(100.f);
    if (with_ellipsoid) b.F32(130.f);
    b.U8(t != 1.15).U8(1);
    w.Data(0, b);
  }
  return w.Save(with_ellipsoid ? "estimate.ulg" : "estimate_amsl.ulg");
}

TEST(Px4EstimateTest, InterpolatesVelocityAndAttitudeAndSkipsWhatItCannotUse) {
  auto reader = OpenULogPx4Estimate(EstimateLog(true));
  const std::vector<NavState> s = ReadAllSamples(*reader);
  ASSERT_EQ(s.size(), 3u);
  const Px4EstimateStats& st = reader->stats();
  EXPECT_EQ(st.epochs, 3u);
  EXPECT_EQ(st.outside, 2u);       // 0.95, 2.60
  EXPECT_EQ(st.invalid, 2u);       // 1.15 (position flag), 1.35 (velocity flag)
  EXPECT_EQ(st.gaps, 1u);          // 1.50
  EXPECT_EQ(st.across_reset, 1u);  // 1.27
  EXPECT_TRUE(st.ellipsoid);
  // 1e-6: float fields.
  EXPECT_NEAR(s[0].t_s, 1.05, 1e-12);  // timestamp_sample, not timestamp
  EXPECT_EQ(s[0].gps_week, -1);        // no GNSS in this log: boot time
  EXPECT_NEAR(s[0].lat_rad, 11.05 * kDegToRad, 1e-12);
  EXPECT_NEAR(s[0].lon_rad, 20.0 * kDegToRad, 1e-12);
  EXPECT_DOUBLE_EQ(s[0].h_m, 130.0);  // alt_ellipsoid, not the AMSL alt
  EXPECT_TRUE(s[0].v_n_mps.isApprox(Eigen::Vector3d(0.5, 1.0, -0.5), 1e-6));
  EXPECT_NEAR(Yaw(s[0].q_n_b) * kRadToDeg, 10.0, 1e-5);  // slerp half way
  EXPECT_TRUE(s[1].v_n_mps.isApprox(Eigen::Vector3d(1.0, 2.0, -1.0), 1e-6));
  EXPECT_NEAR(Yaw(s[1].q_n_b) * kRadToDeg, 20.0, 1e-5);
  // 1.27: velocity interpolated (0.7 of the way from 1.2 to 1.3), attitude from the
  // nearer sample after the reset (1.30: 90 deg), not a blend across the reset.
  EXPECT_TRUE(s[2].v_n_mps.isApprox(Eigen::Vector3d(2.7, 5.4, -2.7), 1e-6));
  EXPECT_NEAR(Yaw(s[2].q_n_b) * kRadToDeg, 90.0, 1e-5);
  for (const NavState& n : s) EXPECT_NEAR(n.q_n_b.norm(), 1.0, 1e-12);
}

TEST(Px4EstimateTest, WithoutEllipsoidHeightTheAmslHeightIsUsedAndSaid) {
  auto reader = OpenULogPx4Estimate(EstimateLog(false));
  NavState n;
  ASSERT_TRUE(reader->Next(&n));
  EXPECT_DOUBLE_EQ(n.h_m, 100.0);
  EXPECT_FALSE(reader->stats().ellipsoid);
  EXPECT_EQ(reader->stats().height_field, "alt");
  // OpenNav gives the same reader for a ULog file.
  NavState m;
  ASSERT_TRUE(OpenNav(EstimateLog(false))->Next(&m));
  EXPECT_DOUBLE_EQ(m.t_s, n.t_s);
}

TEST(Px4EstimateTest, NonUnitQuaternionNamesTheFieldAndByte) {
  ULogWriter w;
  w.Format("vehicle_global_position:uint64_t timestamp;double lat;double lon;float alt;")
      .Format("vehicle_local_position:uint64_t timestamp;float vx;float vy;float vz;")
      .Format("vehicle_attitude:uint64_t timestamp;float[4] q;")
      .Subscribe(0, 0, "vehicle_global_position")
      .Subscribe(0, 1, "vehicle_local_position")
      .Subscribe(0, 2, "vehicle_attitude")
      .Data(1, Bytes().U64(1000).F32(0.f).F32(0.f).F32(0.f))
      .Data(1, Bytes().U64(3000).F32(0.f).F32(0.f).F32(0.f));
  const long long bad_at = w.offset();
  w.Data(2, Bytes().U64(1000).F32(0.5f).F32(0.f).F32(0.f).F32(0.f))
      .Data(2, Bytes().U64(3000).F32(1.f).F32(0.f).F32(0.f).F32(0.f))
      .Data(0, Bytes().U64(2000).F64(1.0).F64(2.0).F32(3.f));
  auto reader = OpenULogPx4Estimate(w.Save("bad_q.ulg"));
  NavState n;
  try {
    reader->Next(&n);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "vehicle_attitude.q");
    EXPECT_EQ(e.byte_offset(), bad_at);
    EXPECT_NE(e.reason().find("unit quaternion"), std::string::npos) << e.reason();
  }
}

// ---------------------------------------------------------------------------------------
// ekf_failure.ulg

TEST(Px4EstimateRealDataTest, EkfFailureEstimateIsOrderedFiniteUnitAndOnTheEllipsoid) {
  const std::string path = testing::DataPath("px4-ulog/ekf_failure.ulg");
  NAVTWIN_REQUIRE_DATA(path);
  auto reader = OpenULogPx4Estimate(path);
  const std::vector<NavState> nav = ReadAllSamples(*reader);
  const Px4EstimateStats& st = reader->stats();
  std::printf("ekf_failure estimate: %zu epochs, invalid %zu, outside %zu, gaps %zu, across reset %zu\n",
              st.epochs, st.invalid, st.outside, st.gaps, st.across_reset);
  // 399 vehicle_global_position messages; the first lies 5 ms before the first attitude
  // sample. Exact counts: the file does not change.
  EXPECT_EQ(nav.size(), 398u);
  EXPECT_EQ(st.outside, 1u);
  EXPECT_TRUE(st.ellipsoid);
  for (std::size_t k = 0; k < nav.size(); ++k) {
    const NavState& n = nav[k];
    ASSERT_TRUE(std::isfinite(n.t_s) && std::isfinite(n.lat_rad) && std::isfinite(n.lon_rad) &&
                std::isfinite(n.h_m) && n.v_n_mps.allFinite() && n.q_n_b.coeffs().allFinite())
        << k;
    EXPECT_LE(std::abs(n.lat_rad), 90.0 * kDegToRad);
    EXPECT_NEAR(n.q_n_b.norm(), 1.0, 1e-12);
    EXPECT_EQ(n.gps_week, 2353);
    if (k > 0) {
      EXPECT_GT(n.t_s, nav[k - 1].t_s) << k;
    }
  }
  // Heights against the GNSS ellipsoidal heights: the estimate follows them within a few
  // metres (median), where the AMSL alt would be 45 m lower (geoid undulation here).
  const std::vector<GnssSample> gnss = ReadAllSamples(*OpenULogGnss(path));
  std::vector<double> dh;
  std::size_t j = 0;
  for (const GnssSample& g : gnss) {
    while (j + 1 < nav.size() && nav[j + 1].t_s <= g.t_s) ++j;
    dh.push_back(nav[j].h_m - g.h_m);
  }
  std::nth_element(dh.begin(), dh.begin() + dh.size() / 2, dh.end());
  std::printf("estimate - GNSS height: median %.2f m\n", dh[dh.size() / 2]);
  EXPECT_LT(std::abs(dh[dh.size() / 2]), 5.0);
}

// vehicle_attitude.q convention: propagating q1 with the gyro increments between two
// attitude samples 0.5 s apart must give q2. Hamilton q_n_b (body FRD to NED, q2 = q1 *
// Exp(sum dtheta)) matches to a few tenths of a degree (gyro bias and the EKF's
// corrections); the transposed convention (q2 = Exp(sum dtheta) * q1) or the inverse
// (JPL-like, q1 * Exp(-sum dtheta)) are several degrees off.
TEST(Px4EstimateRealDataTest, AttitudeQuaternionIsHamiltonBodyToNed) {
  const std::string path = testing::DataPath("px4-ulog/ekf_failure.ulg");
  NAVTWIN_REQUIRE_DATA(path);
  std::vector<std::pair<std::uint64_t, Eigen::Quaterniond>> att;
  ULogFile log(path);
  while (log.NextOf("vehicle_attitude")) {
    att.emplace_back(log.timestamp_us(), Eigen::Quaterniond(log.GetArray("q", 0), log.GetArray("q", 1),
                                                            log.GetArray("q", 2), log.GetArray("q", 3)));
  }
  const std::vector<ImuSample> imu = ReadAllSamples(*OpenULogImu(path));
  const double shift_s = static_cast<double>(FindULogClock(path).shift_us) * 1e-6;
  std::vector<double> err[3];
  std::size_t i = 0;
  for (std::size_t k = 100; k + 10 < att.size(); k += 40) {
    const double t1 = static_cast<double>(att[k].first) * 1e-6 + shift_s;
    const double t2 = static_cast<double>(att[k + 10].first) * 1e-6 + shift_s;
    while (i < imu.size() && imu[i].t_s <= t1) ++i;
    Eigen::Quaterniond dq = Eigen::Quaterniond::Identity();
    for (std::size_t m = i; m < imu.size() && imu[m].t_s <= t2; ++m) dq = dq * QuatFromRotVec<double>(imu[m].dtheta_b_rad);
    const Eigen::Quaterniond& q1 = att[k].second;
    const Eigen::Quaterniond& q2 = att[k + 10].second;
    const Eigen::Quaterniond predicted[3] = {q1 * dq, dq * q1, q1 * dq.conjugate()};
    for (int h = 0; h < 3; ++h) err[h].push_back(predicted[h].angularDistance(q2) * kRadToDeg);
  }
  double median[3];
  for (int h = 0; h < 3; ++h) {
    std::nth_element(err[h].begin(), err[h].begin() + err[h].size() / 2, err[h].end());
    median[h] = err[h][err[h].size() / 2];
  }
  std::printf("attitude propagation, median error [deg]: q1*dq %.3f, dq*q1 %.3f, q1*dq^-1 %.3f\n",
              median[0], median[1], median[2]);
  EXPECT_LT(median[0], 1.0);  // measured 0.22 deg
  EXPECT_GT(median[1], 3.0);  // measured 5.8 deg
  EXPECT_GT(median[2], 3.0);  // measured 9.9 deg
}

}  // namespace ulog_estimate_test
}  // namespace navtwin
