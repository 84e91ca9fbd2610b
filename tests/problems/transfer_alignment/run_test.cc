// The entry point of issue 6's methods (run.h) and the inputs (inputs.h): the scoring of
// the slave attitude against a synthetic truth whose error is known (including headings
// across +-180 deg), the JSON of the issue, the method names, input validation, and the
// simulated inputs of a shortened transfer-alignment scenario (simulated once).
#include "problems/transfer_alignment/run.h"

#include <algorithm>
#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/input_error.h"
#include "core/rotation.h"
#include "core/sim/scenario.h"
#include "core/config/yaml_config.h"
#include "core/units.h"
#include "problems/transfer_alignment/inputs.h"
#include "tests/problems/transfer_alignment/short_scenario.h"

namespace navtwin::transfer {
namespace transfer_alignment_run_test {


NavState StateAt(double t_s, const Eigen::Vector3d& euler_rad) {
  NavState s;
  s.t_s = t_s;
  s.lat_rad = 36.0 * kDegToRad;
  s.lon_rad = 127.5 * kDegToRad;
  s.h_m = 3000.0;
  s.q_n_b = QuatFromEuler(euler_rad.x(), euler_rad.y(), euler_rad.z());
  return s;
}

/// The body truth's Euler angles at t: a rolling, pitching turn through heading 180 deg
/// (yaw from 170 deg to 190 deg = -170 deg over 0..10 s).
Eigen::Vector3d TruthEuler(double t_s) {
  return Eigen::Vector3d(0.5 * std::sin(0.7 * t_s), 0.1 * std::cos(0.3 * t_s), WrapPi((170.0 + 2.0 * t_s) * kDegToRad));
}

/// Truth at 100 Hz over [0, 10] s, a true mounting and a true delay.
TransferInputs SyntheticInputs() {
  TransferInputs in;
  for (int k = 0; k <= 1000; ++k) in.truth.push_back(StateAt(0.01 * k, TruthEuler(0.01 * k)));
  in.true_misalignment = QuatFromEuler(0.01, -0.005, 0.02);
  in.true_delay_s = 0.3;
  in.slave_initial = in.truth.front();
  return in;
}

// Tolerance 1e-6 mrad (1e-9 rad): the angles go through quaternions, slerp between records
// and back (round-off of a few ulps, amplified by the Euler conversion at pitch < 0.1 rad).
constexpr double kTolMrad = 1e-6;

TEST(TransferRunTest, ScoringRecoversAKnownEulerErrorAcrossSouth) {
  const TransferInputs in = SyntheticInputs();
  const Eigen::Quaterniond M = *in.true_misalignment;
  // Estimates at 50 Hz, between the truth records (odd times), whose slave Euler angles
  // differ from the truth's by a known offset: 20 mrad before t = 2 s (excluded by
  // settle_s = 2), then +1, -2, +3 mrad (heading: yaw near 180 deg, the difference wraps).
  std::vector<NavState> est;
  for (int k = 0; k < 490; ++k) {
    const double t = 0.005 + 0.02 * k;
    // The slave truth as the scorer forms it: the body truth slerped between its records
    // (not the analytic Euler path, which differs between records by O(h^2)), times M.
    const int i = static_cast<int>(std::floor(t / 0.01));
    const double w = (t - in.truth[i].t_s) / 0.01;
    const Eigen::Quaterniond q_true_s = in.truth[i].q_n_b.slerp(w, in.truth[i + 1].q_n_b) * M;
    const Eigen::Vector3d e_true = EulerFromQuat(q_true_s);
    const Eigen::Vector3d offset =
        t < 2.0 ? Eigen::Vector3d(20.0, 20.0, 20.0) * kMrad_rad : Eigen::Vector3d(1.0, -2.0, 3.0) * kMrad_rad;
    NavState s = StateAt(t, Eigen::Vector3d(e_true.x() + offset.x(), e_true.y() + offset.y(),
                                            WrapPi(e_true.z() + offset.z())));
    est.push_back(s);
  }
  TransferResult r;
  ScoreAttitude(in, est, M, /*settle_s=*/2.0, &r);
  ASSERT_EQ(r.t_s.size(), est.size());
  EXPECT_NEAR(r.rms_mrad.x(), 1.0, kTolMrad);
  EXPECT_NEAR(r.rms_mrad.y(), 2.0, kTolMrad);
  EXPECT_NEAR(r.rms_mrad.z(), 3.0, kTolMrad);  // not ~2 pi: the heading difference wraps
  EXPECT_NEAR(r.max_mrad.z(), 3.0, kTolMrad);
  EXPECT_NEAR(r.error_mrad.front().x(), 20.0, kTolMrad);  // kept for plots, not in the RMS
  EXPECT_NEAR(r.error_mrad.back().y(), -2.0, kTolMrad);
  EXPECT_NEAR(r.misalignment_error_mrad, 0.0, kTolMrad);
  EXPECT_NEAR(r.delay_true_s, 0.3, 0.0);
  EXPECT_NEAR(r.misalignment_true_deg.z(), 0.02 * kRadToDeg, 1e-12);
}

TEST(TransferRunTest, ScoringWithoutTheTrueMountingUsesTheBodyEstimate) {
  TransferInputs in = SyntheticInputs();
  const Eigen::Quaterniond M = *in.true_misalignment;
  in.true_misalignment.reset();
  // The estimate of the body attitude R_n_s_est M_est^T is the truth rotated by 2 mrad about
  // north at each record (t on the records: no interpolation). M_est = M.
  std::vector<NavState> est;
  for (int k = 0; k <= 1000; k += 2) {
    NavState s = in.truth[k];
    s.q_n_b = ApplyAttitudeError<double>(Eigen::Vector3d(-2.0 * kMrad_rad, 0.0, 0.0), in.truth[k].q_n_b) * M;
    est.push_back(s);
  }
  TransferResult r;
  ScoreAttitude(in, est, M, 0.0, &r);
  ASSERT_EQ(r.t_s.size(), est.size());
  // Rotating by -2 mrad about north changes roll/pitch/yaw by at most 2 mrad in total
  // (mixing with the heading): the norm of the Euler error per epoch is 2 mrad to first order.
  double max_norm = 0.0;
  for (const Eigen::Vector3d& e : r.error_mrad) max_norm = std::max(max_norm, e.norm());
  EXPECT_GT(max_norm, 1.9);   // 1st-order: |dEuler| >= |phi| x min singular value ~ 0.995 at pitch 0.1
  EXPECT_LT(max_norm, 2.3);   // and <= |phi| / cos(pitch) plus 2nd order
  EXPECT_TRUE(std::isnan(r.misalignment_error_mrad));
  EXPECT_NE(r.note.find("body truth"), std::string::npos) << r.note;
}

TEST(TransferRunTest, NoTruthGivesNaNScores) {
  TransferInputs in = SyntheticInputs();
  const std::vector<NavState> est = {in.truth[100], in.truth[200]};
  in.truth.clear();
  TransferResult r;
  ScoreAttitude(in, est, Eigen::Quaterniond::Identity(), 0.0, &r);
  EXPECT_TRUE(r.t_s.empty());
  EXPECT_TRUE(std::isnan(r.rms_mrad.x()));
  EXPECT_TRUE(std::isnan(r.max_mrad.z()));
}

TEST(TransferRunTest, JsonHasTheIssuesKeysInOrderAndNullForNaN) {
  TransferResult r;
  r.method = Method::kOrder1;
  r.rms_mrad = Eigen::Vector3d(1.5, 1.25, 2.0);
  r.max_mrad = Eigen::Vector3d(3.5, 3.25, 4.0);
  r.delay_s = 0.3;
  r.delay_sigma_s = 0.001;
  r.misalignment_deg = Eigen::Vector3d(0.5, -0.3, 0.8);
  r.run_time_s = 1.5;
  const std::string json = TransferResultJson(r);
  const std::regex issue(
      "^\\{\"method\":\"order1\",\"roll_rms_mrad\":1\\.5,\"pitch_rms_mrad\":1\\.25,\"heading_rms_mrad\":2,"
      "\"roll_max_mrad\":3\\.5,\"pitch_max_mrad\":3\\.25,\"heading_max_mrad\":4,\"delay_est_s\":0\\.3,"
      "\"delay_sigma_s\":0\\.001,\"misalignment_deg\":\\[0\\.5,-0\\.3,0\\.8\\],\"run_time_s\":1\\.5,.*\\}$");
  EXPECT_TRUE(std::regex_match(json, issue)) << json;
  // Unknown truth: null, never NaN (invalid JSON).
  EXPECT_NE(json.find("\"delay_true_s\":null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"misalignment_error_mrad\":null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"nees_misalignment_delay\":null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"nis_mean\":null"), std::string::npos) << json;
  EXPECT_EQ(json.find("nan"), std::string::npos) << json;
  TransferResult none;
  const std::string j2 = TransferResultJson(none);
  EXPECT_NE(j2.find("\"roll_rms_mrad\":null"), std::string::npos) << j2;
  EXPECT_NE(TransferResultTable(r).find("method order1"), std::string::npos);
}

TEST(TransferRunTest, MethodNamesRoundTrip) {
  for (const Method m : {Method::kOrder1, Method::kOrder2, Method::kHistory, Method::kBatch}) {
    EXPECT_EQ(ParseMethod(MethodName(m)), m);
  }
  EXPECT_THROW(ParseMethod("order3"), std::invalid_argument);
}

// ----------------------------------------------------------------------------- inputs

/// The preset shortened to 6 s (cruise 2 s, wing rock 4 s) with the master's errors as in
/// the preset; simulated once with the delay overridden to 0.12 s.
const TransferInputs& ShortInputs() {
  static const TransferInputs in = [] {
    return SimulateTransferInputs(test_scenarios::ShortTransferScenario(4.0, 0.3), 1, 0.12);
  }();
  return in;
}

TEST(TransferInputsTest, SimulatedInputsCarryTheTruthAndTheSlaveStart) {
  const TransferInputs& in = ShortInputs();
  ASSERT_TRUE(in.true_delay_s && in.true_misalignment);
  EXPECT_EQ(*in.true_delay_s, 0.12);  // the override replaced the scenario's 0.3 s
  // R_b_s = DcmFromEuler(mounting): exact up to the quaternion round trip.
  const Eigen::Quaterniond M = QuatFromEuler(0.5 * kDegToRad, -0.3 * kDegToRad, 0.8 * kDegToRad);
  EXPECT_LT(AttitudeError(*in.true_misalignment, M).norm(), 1e-12);
  EXPECT_EQ(in.slave_imu.size(), 600u);  // 6 s at 100 Hz
  ASSERT_FALSE(in.truth.empty());
  // The master's first record is tagged at the delay (its data time = the first truth time).
  ASSERT_GE(in.master.size(), 3u);
  EXPECT_NEAR(in.master.front().t_s, 0.12, 1e-9);
  // The record tagged t carries the truth at t - 0.12 s, up to the master's attitude error
  // (0.05 mrad per axis, 1 sigma: within 0.5 mrad at 5 sigma of the norm of three axes).
  const NavState& m = in.master[100];  // tag 2.12 s
  const auto it = std::find_if(in.truth.begin(), in.truth.end(), [&](const NavState& s) {
    return std::abs(s.t_s - (m.t_s - 0.12)) < 1e-6;
  });
  ASSERT_NE(it, in.truth.end());
  EXPECT_LT(AttitudeError(it->q_n_b, m.q_n_b).norm(), 0.5e-3);
  EXPECT_LT((it->v_n_mps - m.v_n_mps).norm(), 0.1);  // 0.01 m/s noise per axis, 5 sigma
  // The slave starts at t = 0 from the body truth with the init errors (R_true = Exp(phi)
  // R_init; velocity estimate minus truth), its mounting unknown (identity guess):
  // attitude to 1e-12 rad, velocity to 1e-9 m/s (file round trip of doubles).
  EXPECT_EQ(in.slave_initial.t_s, 0.0);
  const Eigen::Vector3d phi = AttitudeError(in.truth.front().q_n_b, in.slave_initial.q_n_b);
  EXPECT_LT((phi - Eigen::Vector3d(0.5, -0.5, 1.0) * kDegToRad).norm(), 1e-12);
  EXPECT_LT((in.slave_initial.v_n_mps - in.truth.front().v_n_mps - Eigen::Vector3d(0.5, -0.5, 0.2)).norm(), 1e-9);
  EXPECT_NO_THROW(ValidateInputs(in));
}

TEST(TransferInputsTest, ValidationNamesTheFileTheRecordAndTheField) {
  TransferInputs in = ShortInputs();
  in.master_path = "master.nav";
  in.master[5].t_s = in.master[4].t_s;
  try {
    ValidateInputs(in);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "master.nav");
    EXPECT_EQ(e.field(), "record 6: t_s") << e.what();
  }
  in = ShortInputs();
  in.slave_path = "imu.txt";
  in.slave_imu[10].dtheta_b_rad.x() = NAN;
  try {
    ValidateInputs(in);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "imu.txt");
    EXPECT_EQ(e.field(), "sample 11: dtheta_b_rad") << e.what();
  }
  // No overlap: the master on another time scale.
  in = ShortInputs();
  for (NavState& m : in.master) m.t_s += 1000.0;
  EXPECT_THROW(ValidateInputs(in), InputError);
}

}  // namespace transfer_alignment_run_test
}  // namespace navtwin::transfer
