// navtwin report RUN_DIR [RUN_DIR...] --out report.html: one self-contained HTML page with
// the figures and summary tables of run folders (navigate, smooth, transfer-align,
// inflight-align, level-mc, calibrate-imu, calibrate-mag; problems/report/report.h, docs/report.md).
#include <gflags/gflags.h>

#include <iostream>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "problems/report/report.h"

DEFINE_string(figures_dir, "", "report: also write every figure as DIR/<figure id>.svg (for documents)");
DEFINE_int32(max_points, 2000, "report: most points drawn per plotted series (thinned keeping extremes; the tables use every row)");

namespace navtwin::app {
namespace {

const char* const kReportUsage =
    "navtwin report RUN_DIR [RUN_DIR...] --out report.html [--max_points N] [--figures_dir DIR]";

int RunReport(const std::vector<std::string>& args) {
  const auto usage = [](const std::string& why) {
    std::cerr << "navtwin report: " << why << "\nusage: " << kReportUsage << "\n";
    return kExitUsage;
  };
  if (args.empty()) return usage("give at least one run folder");
  if (FLAGS_out.empty()) return usage("--out is required");
  if (FLAGS_max_points < 10) return usage("--max_points must be at least 10");
  report::ReportOptions options;
  options.run_dirs = args;
  options.out_path = FLAGS_out;
  options.max_points = static_cast<std::size_t>(FLAGS_max_points);
  options.figures_dir = FLAGS_figures_dir;
  options.progress = &std::cerr;
  const report::ReportSummary summary = report::WriteReport(options);
  for (const std::string& why : summary.left_out) std::cerr << "report: left out: " << why << "\n";
  std::cout << "report: " << FLAGS_out << ": " << summary.figures << " figures in " << summary.run_time_s << " s\n";
  return kExitOk;
}

}  // namespace

Command ReportCommand() {
  return {"report", "HTML report (figures and tables) of one or several run folders of one command", kReportUsage,
          {"out", "max_points", "figures_dir"}, &RunReport};
}

}  // namespace navtwin::app
