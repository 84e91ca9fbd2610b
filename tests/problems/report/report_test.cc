// The report (problems/report): a hand-made run folder of two methods (filter, batch) with
// every file of the layout; the figures it makes (valid SVG, the number of plotted series),
// what it leaves out when files are missing, the numbers it scores over every row although
// the plots are thinned, bad input (file, line, field; no page), and the page in a browser.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "core/io/input_error.h"
#include "problems/report/decimate.h"
#include "problems/report/gnuplot.h"
#include "problems/report/html.h"
#include "problems/report/report.h"
#include "problems/report/run_folder.h"
#include "tests/report_page_check.h"
#include "tests/scratch_dir.h"
#include "tests/test_data.h"

namespace navtwin::report_test {
namespace {

using report::ReportOptions;
namespace check = report_page_check;

constexpr double kRateHz = 100.0;       // errors.csv rows
constexpr double kDuration_s = 60.0;
constexpr double kOutageStart_s = 20.0, kOutageEnd_s = 30.0;
constexpr double kFilterDrift_m = 5.0;  // the filter's largest horizontal error in the outage (3-4-5)
constexpr int kNeesOutliers = 100;      // filter rows whose NEES is 3 * 10^2 (above the 9.35 bound)

std::string SummaryJson() {
  return R"({"command": "smooth", "output_method": "batch",
 "inputs": {"imu": "imu.txt", "gnss": "gnss.txt", "imu_samples": 12000, "gnss_epochs": 61,
            "gnss_removed_by_outages": 10, "t_start_s": 0, "t_end_s": 60},
 "outages": [[20, 30]], "truth": "truth.nav",
 "methods": {
  "filter": {"run_time_s": 0.5, "knots": 6001, "counts": {"gnss_position": {"used": 50, "rejected": 1}},
   "aux": {"gnss_time_offset_s": {"value": 0.01, "std": 0.002, "prior_std": 0.1, "observable": true}},
   "imu_scale_factors": {"gyro_scale_x": {"value": 1e-4, "std": 1.9e-3, "prior_std": 2e-3, "observable": false}},
   "residuals": {"gnss_position": {"rows": 150, "dof": 150, "chi2": 160, "chi2_per_dof": 1.07,
                 "configured_chi2_per_dof": null, "sigma_scale": 1, "adapted": false}},
   "errors": {"reference": "navigation",
     "all": {"epochs": 6001, "horizontal_m": {"rms": 1.5, "max": 5.0}, "vertical_m": {"rms": 0.4, "max": 1},
             "velocity_rms_mps": 0.05, "roll_deg": {"rms": 0.1, "max": 0.3}, "pitch_deg": {"rms": 0.1, "max": 0.3},
             "yaw_deg": {"rms": 0.3, "max": 0.9}},
     "outage_horizontal_rms_m": 5.0, "outage_vertical_rms_m": 1.0,
     "consistency": {"all": {"epochs": 6001, "pos_n": 1.1, "pos_e": 0.9, "pos_d": 4.5, "vel_n": 1, "vel_e": 1,
                     "vel_d": 1, "roll": 1, "pitch": 1, "yaw": 0.2, "pos_nees_mean": 3.2}}}},
  "batch": {"run_time_s": 2.5, "knots": 61, "counts": {},
   "residuals": {"gnss_position_h": {"rows": 100, "dof": 95.5, "chi2": 99, "chi2_per_dof": 1.04,
                 "configured_chi2_per_dof": 4.2, "sigma_scale": 2.05, "adapted": true}},
   "errors": {"reference": "navigation",
     "all": {"epochs": 6001, "horizontal_m": {"rms": 0.2, "max": 0.5}, "vertical_m": {"rms": 0.1, "max": 0.3},
             "velocity_rms_mps": 0.01, "roll_deg": {"rms": 0.05, "max": 0.1}, "pitch_deg": {"rms": 0.05, "max": 0.1},
             "yaw_deg": {"rms": 0.1, "max": 0.2}},
     "consistency": {"all": {"epochs": 6001, "pos_n": 1, "pos_e": 1, "pos_d": 1, "vel_n": 1, "vel_e": 1,
                     "vel_d": 1, "roll": 1, "pitch": 1, "yaw": 1, "pos_nees_mean": 3}}}}},
 "adapted_noise": ["GNSS position sigma N, E 1 -> 2.05 x file sigma"],
 "warnings": ["batch: residual group gnss_position_h has chi2/dof 4.2 over 95.5 dof"]}
)";
}

bool InOutage(double t) { return t >= kOutageStart_s && t < kOutageEnd_s; }

/// A track going east at 10 m/s from 48 N, 11 E.
void Position(double t, double* lat_deg, double* lon_deg) {
  *lat_deg = 48.0 + 1e-6 * std::sin(0.1 * t);
  *lon_deg = 11.0 + 10.0 * t / (6378137.0 * std::cos(48.0 * M_PI / 180.0)) * 180.0 / M_PI;
}

std::string GnssCsv() {
  std::ostringstream s;
  s.precision(12);
  s << "t_s,lat_deg,lon_deg,h_m,pos_n_std_m,pos_e_std_m,pos_d_std_m,in_outage\n";
  for (int k = 0; k <= 60; ++k) {
    double lat, lon;
    Position(k, &lat, &lon);
    s << k << "," << lat << "," << lon << ",500,1,1,2," << (InOutage(k) ? 1 : 0) << "\n";
  }
  return s.str();
}

std::string NavCsv(double offset_deg) {
  std::ostringstream s;
  s.precision(12);
  s << "t_s,lat_deg,lon_deg,h_m,vn_mps,ve_mps,vd_mps,roll_deg,pitch_deg,yaw_deg\n";
  for (int k = 0; k <= 600; ++k) {
    double lat, lon;
    Position(0.1 * k, &lat, &lon);
    s << 0.1 * k << "," << lat + offset_deg << "," << lon << ",500,0,10,0,0,0,90\n";
  }
  return s.str();
}

std::string StdCsv(double scale) {
  std::ostringstream s;
  s << "t_s,pos_n_std_m,pos_e_std_m,pos_d_std_m,vel_n_std_mps,vel_e_std_mps,vel_d_std_mps,att_n_std_deg,"
       "att_e_std_deg,att_d_std_deg,bg_x_std_deg_h,bg_y_std_deg_h,bg_z_std_deg_h,ba_x_std_mg,ba_y_std_mg,ba_z_std_mg\n";
  for (int k = 0; k <= 600; ++k) {
    const double grow = InOutage(0.1 * k) ? 1.0 + (0.1 * k - kOutageStart_s) : 1.0;
    s << 0.1 * k;
    for (int c = 0; c < 9; ++c) s << "," << scale * grow * (c < 3 ? 1.0 : c < 6 ? 0.05 : 0.1);
    s << ",1,1,1,0.1,0.1,0.1\n";
  }
  return s.str();
}

/// errors.csv: error = sigma (NEES 3) but for kNeesOutliers rows (error 10 sigma), and for the
/// filter a single 3-4-5 m horizontal error in the outage.
std::string ErrorsCsv(bool filter) {
  std::ostringstream s;
  s << "t_s,pos_n_err_m,pos_e_err_m,pos_d_err_m,vel_n_err_mps,vel_e_err_mps,vel_d_err_mps,roll_err_deg,"
       "pitch_err_deg,yaw_err_deg,pos_n_std_m,pos_e_std_m,pos_d_std_m,vel_n_std_mps,vel_e_std_mps,vel_d_std_mps,"
       "roll_std_deg,pitch_std_deg,yaw_std_deg,in_outage\n";
  const int n = static_cast<int>(kDuration_s * kRateHz);
  for (int k = 0; k <= n; ++k) {
    const double t = k / kRateHz;
    const double sigma = filter ? 1.0 : 0.1;
    const double scale = filter && k < kNeesOutliers ? 10.0 : 1.0;
    double e[3] = {scale * sigma, -scale * sigma, scale * sigma};
    if (filter && k == 2500) e[0] = 3.0, e[1] = 4.0, e[2] = 0.0;
    s << t << "," << e[0] << "," << e[1] << "," << e[2] << ",0.01,-0.01,0.01,0.02,-0.02,0.05,";
    s << sigma << "," << sigma << "," << sigma << ",0.05,0.05,0.05,0.1,0.1,0.2," << (InOutage(t) ? 1 : 0) << "\n";
  }
  return s.str();
}

std::string ResidualsCsv(bool filter) {
  std::ostringstream s;
  s << "t_s,sensor,dof,chi2,rejected\n";
  for (int k = 0; k <= 60; ++k) {
    if (InOutage(k)) continue;
    s << k << ",gnss_position,3," << 0.5 + 0.1 * (k % 40) << "," << (filter && k == 45 ? 1 : 0) << "\n";
    if (filter) s << k + 0.5 << ",mag,3," << 0.3 * (1 + k % 9) << ",0\n";
  }
  return s.str();
}

class ReportTest : public navtwin::testing::ScratchDirTest {
 protected:
  /// The full run folder "run" under the scratch folder; its path.
  std::string WriteRunFolder(const std::string& name = "run") {
    std::filesystem::create_directories(dir_ + "/" + name + "/filter");
    std::filesystem::create_directories(dir_ + "/" + name + "/batch");
    Write(name + "/summary.json", SummaryJson());
    Write(name + "/gnss.csv", GnssCsv());
    Write(name + "/nav.csv", NavCsv(0.0));          // the output method's (batch): top level only
    Write(name + "/std.csv", StdCsv(0.1));
    Write(name + "/filter/nav.csv", NavCsv(2e-5));
    Write(name + "/filter/std.csv", StdCsv(1.0));
    for (const bool filter : {true, false}) {
      const std::string m = name + (filter ? "/filter/" : "/batch/");
      Write(m + "errors.csv", ErrorsCsv(filter));
      Write(m + "residuals.csv", ResidualsCsv(filter));
    }
    return dir_ + "/" + name;
  }
  std::string Report(const std::vector<std::string>& dirs, std::size_t max_points = 500) {
    ReportOptions o;
    o.run_dirs = dirs;
    o.out_path = dir_ + "/report.html";
    o.max_points = max_points;
    report::WriteReport(o);
    std::ifstream in(o.out_path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
};

// Every figure of the full folder is made, is an SVG of the page's size, and draws exactly
// the series the fixture implies (counted from gnuplot's own groups: no tolerance).
TEST_F(ReportTest, EveryFigureIsAValidSvgWithTheExpectedSeries) {
  const std::string html = Report({WriteRunFolder()});
  const std::map<std::string, int> expected = {
      {"track", 4},        // GNSS used, GNSS removed, filter, batch
      {"pos_errors", 12},  // 3 panels x 2 methods x (band + error)
      {"vel_errors", 12}, {"att_errors", 12},
      {"sigma", 12},       // 3 panels x 2 methods x (horizontal + down)
      {"nees", 4},         // 2 methods + the two bounds
      {"drift", 2},        // 2 methods
      {"nis_gnss_position", 5},  // filter, filter rejected, batch, two bounds
      {"nis_mag", 3}};
  const std::vector<check::PageFigure> figures = check::Figures(html);
  ASSERT_EQ(figures.size(), expected.size());
  for (const check::PageFigure& f : figures) {
    SCOPED_TRACE(f.id);
    ASSERT_EQ(expected.count(f.id), 1u);
    EXPECT_EQ(f.mime, "image/svg+xml");
    int w = 0, h = 0;
    check::SvgSize(f.bytes, &w, &h);
    EXPECT_GE(w, 800);
    EXPECT_GE(h, 400);
    EXPECT_EQ(check::PlottedSeries(f.bytes), expected.at(f.id));
    EXPECT_EQ(f.series, expected.at(f.id));
  }
  EXPECT_NE(html.find("class=\"warnings\""), std::string::npos);  // the warning, highlighted
  EXPECT_NE(html.find("not observable"), std::string::npos);       // gyro_scale_x
  EXPECT_NE(html.find("gnss_time_offset_s"), std::string::npos);
  EXPECT_NE(html.find("2.05 x file sigma"), std::string::npos);
  EXPECT_EQ(html.find("http://"), std::string::npos);   // nothing fetched
  EXPECT_EQ(html.find("https://"), std::string::npos);
}

// The drift and the NEES counts come from every row, although the plotted series are thinned
// to 50 points: the single 5 m row and the 100 outlier rows are all found (exact counts).
TEST_F(ReportTest, ScoresUseEveryRowWhileThePlotsAreThinned) {
  const report::RunData run = report::LoadRunFolder(WriteRunFolder(), "run", false, 50, 2);
  ASSERT_EQ(run.methods.size(), 2u);
  const report::MethodData& filter = run.methods[0];
  ASSERT_EQ(filter.method, "filter");
  ASSERT_EQ(filter.outage_max_horizontal_m.size(), 1u);
  EXPECT_DOUBLE_EQ(filter.outage_max_horizontal_m[0], kFilterDrift_m);
  EXPECT_EQ(filter.nees_counts.values, static_cast<std::size_t>(kDuration_s * kRateHz) + 1);
  EXPECT_EQ(filter.nees_counts.above, static_cast<std::size_t>(kNeesOutliers) + 1);  // + the 5 m row
  EXPECT_EQ(filter.nees_counts.below, 0u);
  EXPECT_LE(filter.errors[0].t.size(), 50u);
  EXPECT_LE(filter.nees.t.size(), 50u);
  // The thinned north error keeps the extremes: the 3 m spike and the 10-sigma rows.
  const std::vector<double>& n = filter.errors[0].y[0];
  EXPECT_DOUBLE_EQ(*std::max_element(n.begin(), n.end()), 10.0);
  ASSERT_EQ(filter.nis.size(), 2u);
  EXPECT_EQ(filter.nis[0].sensor, "gnss_position");
  EXPECT_EQ(filter.nis[0].rejected_count, 1u);
  // The batch's nav.csv and std.csv are the top-level ones (output_method batch).
  EXPECT_FALSE(run.methods[1].track.t.empty());
  EXPECT_FALSE(run.methods[1].sigma.t.empty());
}

// Without a reference, residuals and gnss.csv the figures that need them are left out, each
// with a line saying why; the track and sigma figures stay.
TEST_F(ReportTest, MissingFilesLeaveOutTheirFiguresWithTheReason) {
  std::filesystem::create_directories(dir_ + "/bare");
  Write("bare/summary.json", R"({"output_method": "filter", "outages": [], "inputs": {"t_start_s": 0},
    "methods": {"filter": {"run_time_s": 1}}})");
  Write("bare/nav.csv", NavCsv(0.0));
  Write("bare/std.csv", StdCsv(1.0));
  const std::string html = Report({dir_ + "/bare"});
  const std::vector<check::PageFigure> figures = check::Figures(html);
  ASSERT_EQ(figures.size(), 2u);
  EXPECT_EQ(figures[0].id, "track");
  EXPECT_EQ(figures[1].id, "sigma");
  for (const char* why : {"Position errors: no errors.csv", "Position NEES: no errors.csv",
                          "Drift per outage: no injected outages", "Residuals / NIS: no residuals.csv",
                          "no gnss.csv"}) {
    EXPECT_NE(html.find(why), std::string::npos) << why;
  }
}

// Two folders overlay: every series is labelled "folder/method".
TEST_F(ReportTest, SeveralFoldersOverlayWithFolderLabels) {
  const std::string a = WriteRunFolder("config_a"), b = WriteRunFolder("config_b");
  const std::string html = Report({a, b});
  const std::vector<check::PageFigure> figures = check::Figures(html);
  ASSERT_FALSE(figures.empty());
  for (const check::PageFigure& f : figures) {
    if (f.id != "pos_errors") continue;
    EXPECT_EQ(check::PlottedSeries(f.bytes), 24);  // twice the single folder's
    for (const char* label : {"config_a/filter", "config_b/batch"}) {
      EXPECT_NE(f.bytes.find(label), std::string::npos) << label;
    }
  }
}

/// The InputError that writing the report of `dir` throws, and that no page was written.
std::string ReportError(const std::string& dir, const std::string& out) {
  ReportOptions o;
  o.run_dirs = {dir};
  o.out_path = out;
  try {
    report::WriteReport(o);
  } catch (const InputError& e) {
    EXPECT_FALSE(navtwin::testing::FileExists(out)) << "partial report written";
    return e.what();
  }
  ADD_FAILURE() << "no InputError for " << dir;
  return "";
}

TEST_F(ReportTest, BadInputNamesFileLineAndFieldAndWritesNoPage) {
  const std::string out = dir_ + "/bad.html";
  std::filesystem::create_directories(dir_ + "/empty");
  EXPECT_NE(ReportError(dir_ + "/empty", out).find("summary.json"), std::string::npos);

  const std::string run = WriteRunFolder();
  std::string errors = ErrorsCsv(true);
  std::size_t at = 0;
  for (int line = 1; line < 5; ++line) at = errors.find('\n', at) + 1;  // start of line 5
  errors.replace(errors.find(',', at) + 1, 0, "x");                       // "x<number>" in pos_n_err_m
  Write("run/filter/errors.csv", errors);
  const std::string csv_error = ReportError(run, out);
  for (const char* part : {"filter/errors.csv", "line 5", "pos_n_err_m"}) {
    EXPECT_NE(csv_error.find(part), std::string::npos) << csv_error;
  }
  Write("run/filter/errors.csv", ErrorsCsv(true));
  Write("run/summary.json", "{\"methods\": {\"filter\": {}},\n \"outages\": [[1, 2]\n");
  const std::string json_error = ReportError(run, out);
  EXPECT_NE(json_error.find("summary.json"), std::string::npos) << json_error;
  EXPECT_NE(json_error.find("line"), std::string::npos) << json_error;
}

TEST(ReportPieces, MinMaxThinningKeepsExtremesAndGaps) {
  std::vector<double> y(10000);
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = std::sin(0.01 * static_cast<double>(i));
  y[5000] = 7.0;
  y[7000] = -7.0;
  for (std::size_t i = 8000; i < 8300; ++i) y[i] = std::nan("");
  const std::vector<std::size_t> keep = report::MinMaxIndices(y, 200);
  EXPECT_LE(keep.size(), 200u);
  EXPECT_TRUE(std::is_sorted(keep.begin(), keep.end()));
  const std::vector<double> picked = report::Pick(y, keep);
  EXPECT_EQ(*std::max_element(picked.begin(), picked.end(), [](double a, double b) { return a < b || std::isnan(a); }), 7.0);
  EXPECT_NE(std::find(keep.begin(), keep.end(), 7000u), keep.end());
  EXPECT_TRUE(std::any_of(picked.begin(), picked.end(), [](double v) { return std::isnan(v); }));  // the gap
  EXPECT_EQ(report::MinMaxIndices(std::vector<double>(100, 1.0), 200).size(), 100u);
}

// Reference values of the χ² quantiles (tables: 0.2158 and 9.348 for 3 dof) to 1e-3.
TEST(ReportPieces, ChiSquareBoundsAndBase64) {
  const std::array<double, 2> b = report::ChiSquareBounds95(3);
  EXPECT_NEAR(b[0], 0.2158, 1e-3);
  EXPECT_NEAR(b[1], 9.348, 1e-3);
  EXPECT_EQ(report::Base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(report::Base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(report::Base64("f"), "Zg==");
  EXPECT_EQ(check::DecodeBase64(report::Base64("any\x01\xff bytes")), "any\x01\xff bytes");
}

// A script gnuplot rejects: the error names the figure and carries gnuplot's own message.
TEST(ReportPieces, GnuplotFailureReportsItsStderr) {
  std::vector<report::Figure> figures(1);
  figures[0].id = "broken";
  figures[0].script = "plot $nothing_defined u 1:2\n";
  try {
    report::RenderFigures(&figures, 1);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("figure broken"), std::string::npos) << what;
    EXPECT_NE(what.find("nothing_defined"), std::string::npos) << what;
  }
}

// The page in a real browser: after the load event every <img> has a natural width (the
// page's own script writes loaded/total into the body). Fails without chromium in CI.
TEST_F(ReportTest, ChromiumLoadsEveryFigure) {
  const std::string chromium = check::ChromiumProgram();
  if (chromium.empty()) {
    if (navtwin::testing::InCi()) FAIL() << "chromium is missing in CI (.ci/setup installs it)";
    GTEST_SKIP() << "chromium not installed";
  }
  const std::string html = Report({WriteRunFolder()});
  const std::size_t figures = check::Figures(html).size();
  ASSERT_EQ(figures, 9u);
  const std::string dom = check::DumpDom(chromium, dir_ + "/report.html", dir_);
  ASSERT_FALSE(dom.empty()) << "chromium failed";
  EXPECT_NE(dom.find("data-figures-loaded=\"9/9\""), std::string::npos) << dom.substr(0, 400);
  EXPECT_EQ(dom.find("class=\"broken\""), std::string::npos);
}

}  // namespace
}  // namespace navtwin::report_test
