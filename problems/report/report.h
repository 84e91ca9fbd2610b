// navtwin report: one self-contained HTML page from one or several run folders of navtwin
// navigate / smooth (run_folder.h lists what it reads; docs/report.md shows the page).
#pragma once

#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

namespace navtwin::report {

struct ReportOptions {
  std::vector<std::string> run_dirs;
  std::string out_path;               ///< the HTML file, written whole or not at all
  /// When set, every figure also as an SVG file <figures_dir>/<figure id>.svg (the folder
  /// created if missing), written with the page: all or nothing.
  std::string figures_dir;
  std::size_t max_points = 2000;      ///< per plotted series (the scores use every row)
  int jobs = 2;                       ///< files read and gnuplot processes run at once
  std::ostream* progress = nullptr;   ///< one line per step, when given
};

struct ReportSummary {
  std::size_t figures = 0;
  std::vector<std::string> left_out;  ///< figures not made and why
  double run_time_s = 0.0;
};

/// Reads the folders, draws the figures with gnuplot and writes the page. Throws InputError
/// for a folder without summary.json or a malformed file (nothing is written), and
/// std::runtime_error when gnuplot fails (with its stderr) or the page cannot be written.
ReportSummary WriteReport(const ReportOptions& options);

}  // namespace navtwin::report
