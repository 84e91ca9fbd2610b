// The report of the alignment commands' run folders (problems/report/alignment_pages.h):
// hand-made transfer-align and inflight-align folders of two methods each (the layout of
// docs/run-folder.md); the figures (valid SVG, the exact number of plotted series), several
// folders overlaid, mixed commands refused, bad input (file, line, field; no page), and the
// transfer page in a browser.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "core/io/input_error.h"
#include "problems/calibration/calibration_run_folder.h"
#include "problems/calibration/imu_calibration.h"
#include "problems/calibration/mag_calibration.h"
#include "problems/report/report.h"
#include "tests/report_page_check.h"
#include "tests/scratch_dir.h"
#include "tests/test_data.h"

namespace navtwin::alignment_report_test {
namespace {

namespace check = report_page_check;

std::string TransferMethodJson(const std::string& method, double delay_true_s = 0.3) {
  return "\"" + method + "\":{\"method\":\"" + method +
         "\",\"roll_rms_mrad\":0.5,\"pitch_rms_mrad\":0.4,\"heading_rms_mrad\":0.9,\"roll_max_mrad\":1.5,"
         "\"pitch_max_mrad\":1.2,\"heading_max_mrad\":2.5,\"delay_est_s\":0.2995,\"delay_sigma_s\":0.0002,"
         "\"misalignment_deg\":[0.501,-0.299,0.802],\"run_time_s\":0.4,\"delay_true_s\":" +
         std::to_string(delay_true_s) + ","
         "\"misalignment_sigma_mrad\":[0.04,0.04,0.03],\"misalignment_true_deg\":[0.5,-0.3,0.8],"
         "\"misalignment_error_mrad\":0.04,\"epochs\":201,\"note\":\"scored against the slave truth\"}";
}

/// estimates.csv: the misalignment converging from 0 to its true value, σ shrinking.
std::string EstimatesCsv() {
  std::ostringstream s;
  s << "t_s,mis_roll_deg,mis_pitch_deg,mis_yaw_deg,mis_roll_std_mrad,mis_pitch_std_mrad,mis_yaw_std_mrad,delay_s,"
       "delay_std_s\n";
  for (int k = 0; k <= 200; ++k) {
    const double c = 1.0 - std::exp(-0.05 * k), sigma = 20.0 * std::exp(-0.05 * k) + 0.04;
    s << 0.1 * k << "," << 0.5 * c << "," << -0.3 * c << "," << 0.8 * c << "," << sigma << "," << sigma << ","
      << sigma << "," << 0.3 * c << "," << 1e-3 * sigma << "\n";
  }
  return s.str();
}

std::string AttitudeErrorsCsv() {
  std::ostringstream s;
  s << "t_s,roll_err_mrad,pitch_err_mrad,heading_err_mrad\n";
  for (int k = 0; k <= 200; ++k) s << 0.1 * k << "," << std::sin(0.1 * k) << ",0.5," << -std::cos(0.1 * k) << "\n";
  return s.str();
}

std::string InflightMethodJson(const std::string& method) {
  return "\"" + method + "\":{\"method\":\"" + method +
         "\",\"heading_error_arcmin_at_km\":{\"10\":-2.0,\"20\":-1.5,\"50\":-1.0,\"100\":0.5},"
         "\"final_heading_error_arcmin\":0.4,\"heading_sigma_arcmin\":0.45,\"run_time_s\":0.1,"
         "\"heading_sigma_arcmin_at_km\":{\"10\":3.0,\"20\":1.5,\"50\":1.1,\"100\":0.5},\"path_length_km\":120,"
         "\"gps_sigma_m\":17.4,\"fixes\":121,\"note\":\"0 of 121 GPS fixes rejected\"}";
}

std::string TrackCsv() {
  std::ostringstream s;
  s << "t_s,path_length_km,yaw_deg,sigma_arcmin,error_arcmin\n";
  for (int k = 0; k <= 120; ++k) {
    const double sigma = 30.0 / std::sqrt(1.0 + k);
    s << k << "," << k << ",180," << sigma << "," << 0.5 * sigma * std::sin(0.3 * k) << "\n";
  }
  return s.str();
}

class AlignmentReportTest : public navtwin::testing::ScratchDirTest {
 protected:
  std::string TransferFolder(const std::string& name, double delay_true_s = 0.3) {
    for (const char* m : {"order1", "batch"}) {
      std::filesystem::create_directories(dir_ + "/" + name + "/" + m);
      Write(name + "/" + m + "/estimates.csv", EstimatesCsv());
      Write(name + "/" + m + "/attitude_errors.csv", AttitudeErrorsCsv());
    }
    Write(name + "/summary.json", "{\"command\":\"transfer-align\",\"methods\":{" +
                                      TransferMethodJson("order1", delay_true_s) + "," +
                                      TransferMethodJson("batch", delay_true_s) + "}}\n");
    return dir_ + "/" + name;
  }
  std::string InflightFolder(const std::string& name) {
    for (const char* m : {"distance", "kalman"}) {
      std::filesystem::create_directories(dir_ + "/" + name + "/" + m);
      Write(name + "/" + m + "/track.csv", TrackCsv());
    }
    Write(name + "/summary.json", "{\"command\":\"inflight-align\",\"methods\":{" + InflightMethodJson("distance") +
                                      "," + InflightMethodJson("kalman") + "}}\n");
    return dir_ + "/" + name;
  }
  /// A level-mc folder of two methods over 400 runs: errors spread over +-0.1 / +-0.3 deg.
  std::string LevelingFolder(const std::string& name) {
    std::filesystem::create_directories(dir_ + "/" + name);
    std::ostringstream csv;
    csv << "run,plain_mean_pitch_deg,plain_mean_roll_deg,batch_pitch_deg,batch_roll_deg\n";
    for (int k = 0; k < 400; ++k) {
      const double u = std::sin(0.7 * k), v = std::cos(1.3 * k);
      csv << k << "," << 0.3 * u << "," << 0.3 * v << "," << 0.1 * u << "," << 0.1 * v << "\n";
    }
    Write(name + "/errors.csv", csv.str());
    const std::string stats = "\"pitch_rms_deg\":0.21,\"pitch_max_deg\":0.3,\"roll_rms_deg\":0.2,\"roll_max_deg\":0.3,"
                              "\"pitch_sigma_mean_deg\":0.2,\"roll_sigma_mean_deg\":0.2,"
                              "\"pitch_error_over_sigma_rms\":1.05,\"fallbacks\":0,\"cpu_time_s\":0.5";
    Write(name + "/summary.json", "{\"command\":\"level-mc\",\"runs\":400,\"run_time_s\":1.0,\"methods\":{"
                                  "\"plain_mean\":{" + stats + "},\"batch\":{" + stats + "}}}\n");
    return dir_ + "/" + name;
  }
  /// A calibrate-imu folder written by the command's writers: 8 positions whose raw errors
  /// are 5 mg / 100 deg/h, 0.01 mg / 1 deg/h after.
  std::string ImuCalibrationFolder(const std::string& name, bool recursive = false) {
    calibration::ImuCalibrationResult r;
    r.calibration.accel(9) = 0.05;
    r.calibration.accel_sigma = Eigen::Matrix<double, kTriadParameters, 1>::Constant(1e-4);
    r.positions = 8;
    for (int k = 0; k < 8; ++k) {
      calibration::CalibrationResidual res;
      res.t0_s = 10.0 * k;
      res.t1_s = res.t0_s + 8.0;
      res.accel_before_mps2 = Eigen::Vector3d(0.049, 0.01 * std::sin(k), 0.0);
      res.accel_after_mps2 = Eigen::Vector3d(1e-4 * std::cos(k), 0.0, 0.0);
      res.gyro_before_radps = Eigen::Vector3d(4.8e-4, 0.0, 1e-5 * k);
      res.gyro_after_radps = Eigen::Vector3d(0.0, 4.8e-6, 0.0);
      r.residuals.push_back(res);
    }
    CalibrationFile file;
    file.imu = r.calibration;
    std::vector<calibration::RunFolderFile> files = {
        {"parameters.csv", [&r](std::ostream& o) { calibration::WriteImuParametersCsv(o, r); }},
        {"residuals.csv", [&r](std::ostream& o) { calibration::WriteImuResidualsCsv(o, r); }}};
    const std::vector<calibration::ImuCalibrationResult> steps(3, r);  // a recursive run's estimates
    if (recursive) {
      files.push_back({"convergence.csv", [&steps](std::ostream& o) { calibration::WriteImuConvergenceCsv(o, steps); }});
    }
    calibration::WriteCalibrationRunFolder(
        dir_ + "/" + name, calibration::ImuCalibrationJson(r, "multiposition", "calibrate-imu"), file, files);
    return dir_ + "/" + name;
  }
  /// A calibrate-mag folder: 400 samples of a turning sensor with 10 uT of hard iron.
  std::string MagCalibrationFolder(const std::string& name) {
    calibration::MagCalibration c;
    c.hard_iron_uT = Eigen::Vector3d(10.0, 0.0, 0.0);
    c.field_uT = 50.0;
    std::vector<MagSample> samples;
    for (int k = 0; k < 400; ++k) {
      MagSample m;
      m.t_s = 0.05 * k;
      m.m_b_uT = c.hard_iron_uT + 50.0 * Eigen::Vector3d(std::cos(0.02 * k), std::sin(0.02 * k), 0.0);
      samples.push_back(m);
    }
    CalibrationFile file;
    file.mag = MagCorrection{c.hard_iron_uT, c.correction, c.field_uT};
    calibration::WriteCalibrationRunFolder(
        dir_ + "/" + name,
        "{\"command\":\"calibrate-mag\",\"hard_iron_uT\":[10,0,0],\"hard_iron_sigma_uT\":[0.1,0.1,0.1],"
        "\"field_uT\":50,\"residual_rms_uT\":0.3,\"field_spread_before_uT\":7.1,\"field_spread_after_uT\":0.3,"
        "\"heading_error_before_deg\":null,\"heading_error_after_deg\":null,\"heading_samples\":0,"
        "\"samples\":400,\"method\":\"ellipsoid\"}",
        file, {{"residuals.csv", [&](std::ostream& o) { calibration::WriteMagResidualsCsv(o, c, samples); }}});
    return dir_ + "/" + name;
  }
  std::string Report(const std::vector<std::string>& dirs, const std::string& figures_dir = "") {
    report::ReportOptions o;
    o.run_dirs = dirs;
    o.out_path = dir_ + "/report.html";
    o.figures_dir = figures_dir;
    o.max_points = 100;
    report::WriteReport(o);
    std::ifstream in(o.out_path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
};

/// Every figure of the page is an SVG that draws exactly `expected` series (gnuplot's own
/// groups and the page's data-series attribute).
void ExpectFigures(const std::string& html, const std::map<std::string, int>& expected) {
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
}

TEST_F(AlignmentReportTest, TransferFiguresAndTables) {
  const std::string html = Report({TransferFolder("ta")});
  ExpectFigures(html, {{"misalignment", 15},  // 3 panels x (2 methods x (band + estimate) + the truth)
                       {"delay", 5},         // 2 methods x (band + estimate) + the truth
                       {"slave_attitude_errors", 6}});  // 3 panels x 2 methods
  for (const char* text : {"0.5010 ± 0.04", "299.500 ± 0.2", "0.5000, -0.3000, 0.8000", "heading RMS",
                           "scored against the slave truth"}) {
    EXPECT_NE(html.find(text), std::string::npos) << text;
  }
  EXPECT_EQ(html.find("http://"), std::string::npos);
}

TEST_F(AlignmentReportTest, InflightFiguresAndTables) {
  const std::string html = Report({InflightFolder("ia")});
  ExpectFigures(html, {{"heading_error", 4},              // 2 methods x (band + error)
                       {"heading_error_second_half", 4},  // the same from 60 km on
                       {"heading_sigma", 2}});            // 2 methods
  for (const char* text : {"100 km", "-2.000", "<td>0.45</td>", "0 of 121 GPS fixes rejected"}) {
    EXPECT_NE(html.find(text), std::string::npos) << text;
  }
}

// Two folders of the same command overlay, labelled folder/method; the truth once per folder.
TEST_F(AlignmentReportTest, SeveralFoldersOverlay) {
  const std::string html = Report({TransferFolder("ta_a"), TransferFolder("ta_b")});
  for (const check::PageFigure& f : check::Figures(html)) {
    if (f.id != "misalignment") continue;
    EXPECT_EQ(check::PlottedSeries(f.bytes), 30);  // 3 x (4 methods x 2 + 2 truths)
    for (const char* label : {"ta_a/order1", "ta_b/batch", "ta_b: true"}) {
      EXPECT_NE(f.bytes.find(label), std::string::npos) << label;
    }
  }
  const std::string ia = Report({InflightFolder("ia_a"), InflightFolder("ia_b")});
  EXPECT_NE(ia.find("ia_b/kalman"), std::string::npos);
}

/// The InputError of the report of `dirs`, and that no page was written.
std::string ReportError(const std::vector<std::string>& dirs, const std::string& out) {
  report::ReportOptions o;
  o.run_dirs = dirs;
  o.out_path = out;
  try {
    report::WriteReport(o);
  } catch (const InputError& e) {
    EXPECT_FALSE(navtwin::testing::FileExists(out)) << "partial report written";
    return e.what();
  }
  ADD_FAILURE() << "no InputError";
  return "";
}

TEST_F(AlignmentReportTest, MixedCommandsAreRefusedNamingTheFolders) {
  const std::string e = ReportError({TransferFolder("ta"), InflightFolder("ia")}, dir_ + "/mixed.html");
  for (const char* part : {"/ta (transfer-align)", "/ia (inflight-align)", "different commands"}) {
    EXPECT_NE(e.find(part), std::string::npos) << e;
  }
}

TEST_F(AlignmentReportTest, BadInputNamesFileLineAndFieldAndWritesNoPage) {
  const std::string out = dir_ + "/bad.html";
  const std::string ta = TransferFolder("ta");
  std::filesystem::remove(ta + "/batch/estimates.csv");
  const std::string missing = ReportError({ta}, out);
  EXPECT_NE(missing.find("batch/estimates.csv"), std::string::npos) << missing;

  std::string csv = EstimatesCsv();
  std::size_t at = 0;
  for (int line = 1; line < 5; ++line) at = csv.find('\n', at) + 1;  // start of line 5
  at = csv.find(',', csv.find(',', at) + 1) + 1;                    // the third field: mis_pitch_deg
  csv.replace(at, 0, "x");
  Write("ta/batch/estimates.csv", csv);
  const std::string malformed = ReportError({ta}, out);
  for (const char* part : {"batch/estimates.csv", "line 5", "mis_pitch_deg"}) {
    EXPECT_NE(malformed.find(part), std::string::npos) << malformed;
  }
  const std::string ia = InflightFolder("ia");
  std::filesystem::remove(ia + "/kalman/track.csv");
  EXPECT_NE(ReportError({ia}, out).find("kalman/track.csv"), std::string::npos);
}

// The transfer page in a real browser: every figure loaded. Fails without chromium in CI.
TEST_F(AlignmentReportTest, ChromiumLoadsEveryTransferFigure) {
  const std::string chromium = check::ChromiumProgram();
  if (chromium.empty()) {
    if (navtwin::testing::InCi()) FAIL() << "chromium is missing in CI (.ci/setup installs it)";
    GTEST_SKIP() << "chromium not installed";
  }
  const std::string html = Report({TransferFolder("ta")});
  ASSERT_EQ(check::Figures(html).size(), 3u);
  const std::string dom = check::DumpDom(chromium, dir_ + "/report.html", dir_);
  ASSERT_FALSE(dom.empty()) << "chromium failed";
  EXPECT_NE(dom.find("data-figures-loaded=\"3/3\""), std::string::npos) << dom.substr(0, 400);
  EXPECT_EQ(dom.find("class=\"broken\""), std::string::npos);
}

// The leveling Monte Carlo: one histogram per angle with a series per method; a method of
// summary.json whose columns errors.csv lacks is an InputError naming the column.
TEST_F(AlignmentReportTest, LevelingHistograms) {
  const std::string html = Report({LevelingFolder("lv")});
  ExpectFigures(html, {{"pitch_histogram", 4}, {"roll_histogram", 4}});  // histogram and normal curve per method
  for (const char* text : {"plain_mean", "pitch err/σ RMS", "<td>400</td>"}) {
    EXPECT_NE(html.find(text), std::string::npos) << text;
  }
  Write("lv/errors.csv", "run,plain_mean_pitch_deg,plain_mean_roll_deg\n0,0.1,0.2\n");
  const std::string e = ReportError({dir_ + "/lv"}, dir_ + "/lv_bad.html");
  EXPECT_NE(e.find("batch_pitch_deg"), std::string::npos) << e;
}

// The calibration pages from folders the commands' writers made: the IMU residuals before
// and after per position (one open and one filled series per folder), the parameters with
// σ; the magnetometer field before and after; a column missing from residuals.csv named.
TEST_F(AlignmentReportTest, CalibrationPagesShowResidualsBeforeAndAfter) {
  const std::string imu = ImuCalibrationFolder("cal_a");
  for (const char* file : {"summary.json", "calibration.yaml", "parameters.csv", "residuals.csv"}) {
    EXPECT_TRUE(navtwin::testing::FileExists(imu + "/" + file)) << file;
  }
  const std::string html = Report({imu, ImuCalibrationFolder("cal_b")});
  ExpectFigures(html, {{"accel_residuals", 4}, {"gyro_residuals", 4}});
  for (const char* text : {"accel.bias.x", "cal_b value", "multiposition", "<td>8</td>"}) {
    EXPECT_NE(html.find(text), std::string::npos) << text;
  }
  // A recursive run's folder adds the convergence: the two accelerometer panels x 3 axes x
  // (band + line); the gyro blocks have no σ here (not estimated): left out, and said.
  const std::string rec = Report({ImuCalibrationFolder("cal_r", true)});
  ExpectFigures(rec, {{"accel_residuals", 2}, {"gyro_residuals", 2}, {"recursive_convergence", 12}});
  EXPECT_NE(rec.find("gyro bias [deg/h] not estimated in any folder"), std::string::npos);
  const std::string mag = Report({MagCalibrationFolder("mag")});
  ExpectFigures(mag, {{"mag_field", 2}});
  EXPECT_NE(mag.find("10.000 (0.100)"), std::string::npos);

  Write("cal_a/residuals.csv", "t0_s,t1_s,run,temperature_degC,rms\n0,1,0,nan,0\n");
  const std::string e = ReportError({imu}, dir_ + "/cal_bad.html");
  EXPECT_NE(e.find("accel_before_x_mg"), std::string::npos) << e;
}

// A delay sweep (three folders, distinct true delays) adds the attitude RMS against the true
// delay, one series per method and axis; --figures_dir writes every figure as its SVG.
TEST_F(AlignmentReportTest, DelaySweepFigureAndFigureFiles) {
  const std::string figures = dir_ + "/figures";
  const std::string html =
      Report({TransferFolder("d100", 0.1), TransferFolder("d200", 0.2), TransferFolder("d300", 0.3)}, figures);
  bool found = false;
  for (const check::PageFigure& f : check::Figures(html)) {
    std::ifstream in(figures + "/" + f.id + ".svg");
    std::stringstream file;
    file << in.rdbuf();
    EXPECT_EQ(file.str(), f.bytes) << f.id;  // the page's drawing, byte for byte
    if (f.id != "attitude_rms_vs_delay") continue;
    found = true;
    EXPECT_EQ(check::PlottedSeries(f.bytes), 6);  // 2 methods x (heading; roll, pitch)
    EXPECT_NE(f.bytes.find("true delay [ms]"), std::string::npos);
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(check::Figures(html).size(), 4u);
  // Two folders, or three with one delay, are no sweep.
  EXPECT_EQ(check::Figures(Report({TransferFolder("a"), TransferFolder("b"), TransferFolder("c")})).size(), 3u);
}

}  // namespace
}  // namespace navtwin::alignment_report_test
