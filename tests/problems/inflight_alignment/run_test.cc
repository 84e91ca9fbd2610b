// The entry point of the three methods (run.h): the truth heading interpolation across
// +-180 deg (the preset flies south), the method names, and the outputs on the preset
// inflight-mach07-south (seed 1, simulated once for the whole file).
#include "problems/inflight_alignment/run.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/rotation.h"
#include "core/sim/scenario.h"
#include "core/units.h"
#include "problems/inflight_alignment/inputs.h"

namespace navtwin::inflight {
namespace inflight_alignment_run_test {


NavState StateWithYaw(double t_s, double yaw_deg) {
  NavState s;
  s.t_s = t_s;
  s.lat_rad = 36.5 * kDegToRad;
  s.lon_rad = 127.0 * kDegToRad;
  s.q_n_b = QuatFromEuler(0.01, -0.02, yaw_deg * kDegToRad);
  return s;
}

// Tolerance 1e-12 rad: the yaw goes through a quaternion and back (a few ulps of pi).
constexpr double kYawTol = 1e-12;

TEST(InflightRunTest, TruthYawInterpolatesThroughSouth) {
  // 179.5 deg -> -179.5 deg is a 1 deg turn through south, not 359 deg the other way.
  const std::vector<NavState> truth = {StateWithYaw(10.0, 179.5), StateWithYaw(11.0, -179.5),
                                       StateWithYaw(12.0, -178.5)};
  EXPECT_NEAR(TruthYawAt(truth, 10.0), 179.5 * kDegToRad, kYawTol);
  EXPECT_NEAR(TruthYawAt(truth, 10.25), 179.75 * kDegToRad, kYawTol);
  // Half way is exactly south: +-pi (WrapPi gives +pi; either sign is the same heading).
  EXPECT_NEAR(std::abs(TruthYawAt(truth, 10.5)), M_PI, kYawTol);
  EXPECT_NEAR(TruthYawAt(truth, 10.75), -179.75 * kDegToRad, kYawTol);
  EXPECT_NEAR(TruthYawAt(truth, 11.0), -179.5 * kDegToRad, kYawTol);
  EXPECT_NEAR(TruthYawAt(truth, 11.5), -179.0 * kDegToRad, kYawTol);
  EXPECT_NEAR(TruthYawAt(truth, 12.0), -178.5 * kDegToRad, kYawTol);  // the last record itself
  // Outside the span, or without truth: unknown.
  EXPECT_TRUE(std::isnan(TruthYawAt(truth, 9.999)));
  EXPECT_TRUE(std::isnan(TruthYawAt(truth, 12.001)));
  EXPECT_TRUE(std::isnan(TruthYawAt({}, 10.0)));
}

TEST(InflightRunTest, TruthYawInterpolatesAwayFromSouth) {
  const std::vector<NavState> truth = {StateWithYaw(0.0, 10.0), StateWithYaw(2.0, 14.0)};
  EXPECT_NEAR(TruthYawAt(truth, 0.5), 11.0 * kDegToRad, kYawTol);
  EXPECT_NEAR(TruthYawAt(truth, 1.5), 13.0 * kDegToRad, kYawTol);
}

TEST(InflightRunTest, MethodNamesRoundTrip) {
  for (const Method m : {Method::kDistance, Method::kKalman, Method::kBatch}) {
    EXPECT_EQ(ParseMethod(MethodName(m)), m);
  }
  try {
    ParseMethod("ekf");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("distance, kalman or batch"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------
// A JSON syntax check (objects, arrays, strings, numbers, literals), enough to show that
// MethodResultJson writes a document a JSON reader accepts.
class JsonSyntax {
 public:
  explicit JsonSyntax(const std::string& s) : s_(s) {}
  bool Valid() {
    Space();
    if (!Value()) return false;
    Space();
    return i_ == s_.size();
  }

 private:
  void Space() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool Eat(char c) {
    Space();
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  bool Literal(const char* word) {
    const std::string w(word);
    if (s_.compare(i_, w.size(), w) != 0) return false;
    i_ += w.size();
    return true;
  }
  bool String() {
    if (!Eat('"')) return false;
    while (i_ < s_.size() && s_[i_] != '"') i_ += s_[i_] == '\\' ? 2 : 1;
    return i_ < s_.size() && s_[i_++] == '"';
  }
  bool Number() {
    static const std::regex number("-?(0|[1-9][0-9]*)(\\.[0-9]+)?([eE][+-]?[0-9]+)?");
    std::smatch m;
    const std::string rest = s_.substr(i_, 40);
    if (!std::regex_search(rest, m, number, std::regex_constants::match_continuous)) return false;
    i_ += m.length(0);
    return true;
  }
  bool Value() {
    Space();
    if (i_ >= s_.size()) return false;
    const char c = s_[i_];
    if (c == '{') return Container('}', true);
    if (c == '[') return Container(']', false);
    if (c == '"') return String();
    if (c == 't') return Literal("true");
    if (c == 'f') return Literal("false");
    if (c == 'n') return Literal("null");
    return Number();
  }
  bool Container(char close, bool object) {
    ++i_;
    if (Eat(close)) return true;
    do {
      if (object && !(String() && Eat(':'))) return false;
      if (!Value()) return false;
    } while (Eat(','));
    return Eat(close);
  }
  const std::string& s_;
  std::size_t i_ = 0;
};

TEST(InflightRunTest, JsonSyntaxCheckerRejectsBrokenDocuments) {
  EXPECT_TRUE(JsonSyntax(R"({"a":[1,-2.5e3,null,"x\"y"],"b":{}})").Valid());
  EXPECT_FALSE(JsonSyntax(R"({"a":nan})").Valid());
  EXPECT_FALSE(JsonSyntax(R"({"a":1,})").Valid());
  EXPECT_FALSE(JsonSyntax(R"({"a":1)").Valid());
}

// ---------------------------------------------------------------------------------------
// The preset, seed 1: simulated once (about 1-2 s), each method run once.

const InflightInputs& PresetInputs() {
  static const InflightInputs inputs =
      SimulateInflightInputs(sim::LoadScenario("inflight-mach07-south"), /*seed=*/1);
  return inputs;
}

const MethodResult& PresetResult(Method m) {
  static std::map<Method, std::unique_ptr<MethodResult>> cache;
  auto& slot = cache[m];
  if (!slot) slot = std::make_unique<MethodResult>(RunMethod(PresetInputs(), InflightConfig(), m));
  return *slot;
}

class InflightRunPresetTest : public ::testing::TestWithParam<Method> {};

TEST_P(InflightRunPresetTest, ErrorsAtEveryDistanceAreFiniteAndSmallerThanTheInitialError) {
  const MethodResult& r = PresetResult(GetParam());
  // The preset flies about 125 km (10 s at 100 m/s, the pull-up, 20 s accelerating to
  // 238 m/s, 510 s cruise): every default distance is reached, and the truth is known.
  ASSERT_EQ(r.at_km, (std::vector<double>{10.0, 20.0, 50.0, 100.0}));
  ASSERT_EQ(r.error_at_km_rad.size(), 4u);
  ASSERT_EQ(r.sigma_at_km_rad.size(), 4u);
  ASSERT_FALSE(r.track.empty());
  EXPECT_GT(r.track.back().path_length_m, 100e3);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_TRUE(std::isfinite(r.error_at_km_rad[i])) << MethodName(r.method) << " at " << r.at_km[i] << " km";
    EXPECT_TRUE(std::isfinite(r.sigma_at_km_rad[i]) && r.sigma_at_km_rad[i] > 0.0) << r.at_km[i] << " km";
  }
  // The INS starts 20' off in heading. Even the Kalman-only baseline, the weakest method,
  // ends within its ~3' plateau (seed 003); 10' is a bound that only a sign or wrap error
  // (a heading south compared the long way round) or a diverged estimator would break.
  EXPECT_LT(std::abs(r.final_error_rad), 10.0 * kArcmin_rad) << r.final_error_rad / kArcmin_rad << "'";
  EXPECT_GT(r.final_sigma_rad, 0.0);
  EXPECT_EQ(r.final_error_rad, r.track.back().error_rad);
  EXPECT_GT(r.run_time_s, 0.0);
  EXPECT_GT(r.gps_sigma_m, 0.0);
  // The track's times and distances increase, its errors are yaw - truth wrapped.
  for (std::size_t k = 1; k < r.track.size(); ++k) {
    ASSERT_GT(r.track[k].t_s, r.track[k - 1].t_s);
    ASSERT_GE(r.track[k].path_length_m, r.track[k - 1].path_length_m);
  }
  const HeadingPoint& last = r.track.back();
  EXPECT_NEAR(last.error_rad, WrapPi(last.yaw_rad - TruthYawAt(PresetInputs().truth, last.t_s)), 1e-12);
  // Flying south: the yaw itself is near +-180 deg (the case the wrap is for).
  EXPECT_GT(std::abs(last.yaw_rad), 179.0 * kDegToRad);
}

TEST_P(InflightRunPresetTest, JsonHasTheIssuesKeysAndParses) {
  const MethodResult& r = PresetResult(GetParam());
  const std::string json = MethodResultJson(r);
  EXPECT_TRUE(JsonSyntax(json).Valid()) << json;
  EXPECT_EQ(json.rfind(std::string("{\"method\":\"") + MethodName(r.method) + "\",\"heading_error_arcmin_at_km\":{\"10\":",
                       0),
            0u)
      << json;
  for (const char* key : {"\"20\":", "\"50\":", "\"100\":", "\"final_heading_error_arcmin\":", "\"heading_sigma_arcmin\":",
                          "\"run_time_s\":", "\"heading_sigma_arcmin_at_km\":", "\"path_length_km\":",
                          "\"gps_sigma_m\":", "\"note\":"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << "\n" << json;
  }
  EXPECT_EQ(json.find("null"), std::string::npos) << "every figure is known on the preset\n" << json;
  // The final error in the JSON is the result's, in arcmin (10 significant digits).
  std::smatch m;
  ASSERT_TRUE(std::regex_search(json, m, std::regex("\"final_heading_error_arcmin\":(-?[0-9.eE+-]+)")));
  EXPECT_NEAR(std::stod(m[1]), r.final_error_rad / kArcmin_rad, 1e-8 * std::max(1.0, std::abs(r.final_error_rad / kArcmin_rad)));
  if (r.method == Method::kBatch) {
    EXPECT_NE(json.find("\"batch\":{\"dh_arcmin\":"), std::string::npos);
  }
  if (r.method == Method::kDistance) {
    EXPECT_NE(json.find("\"computations\":[{"), std::string::npos);
  }

  const std::string table = MethodResultTable(r);
  EXPECT_NE(table.find("distance_km"), std::string::npos) << table;
  EXPECT_NE(table.find("final"), std::string::npos) << table;
}

TEST_P(InflightRunPresetTest, TrackCsvHasOneRowPerFix) {
  const MethodResult& r = PresetResult(GetParam());
  const std::string path = ::testing::TempDir() + "inflight_track_" + MethodName(r.method) + ".csv";
  WriteTrackCsv(r, path);
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t_s,path_length_km,yaw_deg,sigma_arcmin,error_arcmin");
  std::size_t rows = 0;
  double t = 0, km = 0, yaw = 0, sigma = 0, err = 0;
  while (std::getline(in, line)) {
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf", &t, &km, &yaw, &sigma, &err), 5) << line;
    ++rows;
  }
  EXPECT_EQ(rows, r.track.size());
  // The last row is the final error, written in the shortest exact form (1e-12 relative:
  // rad -> arcmin scaled by kRadToDeg * 60 there, by 1 / (kDegToRad / 60) here).
  EXPECT_NEAR(err, r.final_error_rad / kArcmin_rad, 1e-12 * std::abs(r.final_error_rad / kArcmin_rad));
  std::remove(path.c_str());
}

INSTANTIATE_TEST_SUITE_P(InflightMethods, InflightRunPresetTest,
                         ::testing::Values(Method::kDistance, Method::kKalman, Method::kBatch),
                         [](const ::testing::TestParamInfo<Method>& info) { return std::string(MethodName(info.param)); });

TEST(InflightRunTest, WithoutTruthTheErrorsAreUnknownAndWrittenAsNull) {
  InflightInputs inputs = PresetInputs();
  inputs.truth.clear();
  const MethodResult r = RunMethod(inputs, InflightConfig(), Method::kKalman, {10.0, 1000.0});
  EXPECT_TRUE(std::isnan(r.error_at_km_rad[0]));
  EXPECT_TRUE(std::isfinite(r.sigma_at_km_rad[0]));  // the sigma needs no truth
  EXPECT_TRUE(std::isnan(r.sigma_at_km_rad[1]));     // 1000 km is never reached
  EXPECT_TRUE(std::isnan(r.final_error_rad));
  const std::string json = MethodResultJson(r);
  EXPECT_TRUE(JsonSyntax(json).Valid()) << json;
  EXPECT_NE(json.find("\"heading_error_arcmin_at_km\":{\"10\":null,\"1000\":null}"), std::string::npos) << json;
}

}  // namespace inflight_alignment_run_test
}  // namespace navtwin::inflight
