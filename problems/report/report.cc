#include "problems/report/report.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "core/io/atomic_file.h"
#include "problems/report/figures.h"
#include "problems/report/html.h"
#include "problems/report/run_folder.h"

namespace navtwin::report {
namespace {

/// The folder's name: its last path component ("." and trailing slashes ignored).
std::string FolderName(std::string dir) {
  while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
  const std::size_t slash = dir.rfind('/');
  std::string name = slash == std::string::npos ? dir : dir.substr(slash + 1);
  return name.empty() || name == "." ? "run" : name;
}

/// Distinct labels: a repeated folder name gets "#2", "#3", ...
std::vector<std::string> Labels(const std::vector<std::string>& dirs) {
  std::vector<std::string> out;
  for (const std::string& d : dirs) {
    std::string label = FolderName(d);
    int k = 1;
    const std::string base = label;
    while (std::find(out.begin(), out.end(), label) != out.end()) label = base + "#" + std::to_string(++k);
    out.push_back(label);
  }
  return out;
}

}  // namespace

ReportSummary WriteReport(const ReportOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (options.run_dirs.empty()) throw std::invalid_argument("report: no run folder given");
  const std::vector<std::string> labels = Labels(options.run_dirs);
  std::vector<RunData> runs;
  for (std::size_t i = 0; i < options.run_dirs.size(); ++i) {
    if (options.progress) *options.progress << "report: reading " << options.run_dirs[i] << "\n";
    runs.push_back(LoadRunFolder(options.run_dirs[i], labels[i], options.run_dirs.size() > 1, options.max_points,
                                 options.jobs));
  }
  const auto elapsed_s = [&start] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  FigureSet set = BuildFigures(runs);
  if (options.progress) {
    *options.progress << "report: read in " << elapsed_s() << " s; drawing " << set.figures.size()
                      << " figures with gnuplot\n";
  }
  RenderFigures(&set.figures, options.jobs);
  if (options.progress) *options.progress << "report: drawn at " << elapsed_s() << " s\n";
  AtomicFile out(options.out_path);
  out.stream() << ReportHtml(runs, set.figures, set.left_out);
  out.Commit();
  ReportSummary summary;
  summary.figures = set.figures.size();
  summary.left_out = set.left_out;
  for (const RunData& r : runs) summary.left_out.insert(summary.left_out.end(), r.notes.begin(), r.notes.end());
  summary.run_time_s = elapsed_s();
  return summary;
}

}  // namespace navtwin::report
