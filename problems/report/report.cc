#include "problems/report/report.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <stdexcept>

#include "core/io/atomic_file.h"
#include "core/io/folder.h"
#include "core/io/input_error.h"
#include "problems/report/alignment_pages.h"
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

/// The kind of page a summary.json asks for: its "command", with navigate and smooth (and
/// folders written before the key existed) the GNSS/INS page.
std::string PageKind(const AlignmentFolder& f) {
  const YAML::Node c = JsonChild(f.summary, "command");
  const std::string command = c && c.IsScalar() ? c.Scalar() : "";
  if (command.empty() || command == "navigate" || command == "smooth") return "gnss-ins";
  if (command == "transfer-align" || command == "inflight-align" || command == "level-mc" ||
      command == "calibrate-imu" || command == "calibrate-mag") {
    return command;
  }
  throw InputError(f.summary_path, c.Mark().line >= 0 ? c.Mark().line + 1 : 0, "command",
                   "'" + command + "' is not a command whose folder the report reads (navigate, smooth, "
                   "transfer-align, inflight-align, level-mc, calibrate-imu, calibrate-mag)");
}

/// The folders' summary.json and the one kind of page they share; InputError naming the
/// folders when their commands differ.
std::vector<AlignmentFolder> ReadFolders(const std::vector<std::string>& dirs, std::string* kind) {
  const std::vector<std::string> labels = Labels(dirs);
  std::vector<AlignmentFolder> folders;
  std::string kinds;
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    const std::string path = dirs[i] + "/summary.json";
    folders.push_back({dirs[i], labels[i], path, ReadSummaryJson(dirs[i], path)});
    const std::string k = PageKind(folders.back());
    kinds += (i ? ", " : "") + dirs[i] + " (" + k + ")";
    if (i == 0) *kind = k;
    if (k != *kind) {
      throw InputError(path, 0, "command", "the folders come from different commands and cannot share a page: " +
                                               kinds + "; make one report per command");
    }
  }
  return folders;
}

/// Writes the page and, with options.figures_dir, every figure's SVG; all or nothing.
void WritePageFiles(const ReportOptions& options, const std::string& html, const std::vector<Figure>& figures) {
  std::vector<std::unique_ptr<AtomicFile>> files;
  files.push_back(std::make_unique<AtomicFile>(options.out_path));
  files.back()->stream() << html;
  if (!options.figures_dir.empty()) {
    EnsureFolder(options.figures_dir);
    for (const Figure& f : figures) {
      files.push_back(std::make_unique<AtomicFile>(options.figures_dir + "/" + HtmlAnchor(f.id) + ".svg"));
      files.back()->stream() << f.svg;
    }
  }
  try {
    for (auto& f : files) f->Commit();
  } catch (...) {
    for (auto& f : files) f->Revoke();
    throw;
  }
}

/// The page of transfer-align, inflight-align, level-mc or calibration folders.
ReportSummary WriteAlignmentReport(const ReportOptions& options, const std::vector<AlignmentFolder>& folders,
                                   const std::string& kind) {
  PageParts page = kind == "transfer-align"   ? TransferPage(folders, options.max_points)
                   : kind == "inflight-align" ? InflightPage(folders, options.max_points)
                   : kind == "level-mc"       ? LevelingPage(folders, options.max_points)
                                              : CalibrationPage(folders, options.max_points);
  if (options.progress) {
    *options.progress << "report: drawing " << page.figures.figures.size() << " figures with gnuplot\n";
  }
  RenderFigures(&page.figures.figures, options.jobs);
  WritePageFiles(options, HtmlPage(page.text, page.figures.figures, page.figures.left_out), page.figures.figures);
  ReportSummary summary;
  summary.figures = page.figures.figures.size();
  summary.left_out = page.figures.left_out;
  summary.left_out.insert(summary.left_out.end(), page.text.notes.begin(), page.text.notes.end());
  return summary;
}

}  // namespace

PageText AlignmentPageText(const std::vector<AlignmentFolder>& folders, const std::string& what,
                           const std::string& intro, const std::string& tables) {
  PageText text;
  text.title = "navtwin report (" + what + "):";
  for (const AlignmentFolder& f : folders) text.title += " " + f.label;
  text.intro = intro;
  text.sections = {{"tables", "Summary tables"}};
  text.body = "<h2 id=\"tables\">Summary tables</h2>\n" + tables;
  return text;
}

ReportSummary WriteReport(const ReportOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (options.run_dirs.empty()) throw std::invalid_argument("report: no run folder given");
  std::string kind;
  const std::vector<AlignmentFolder> folders = ReadFolders(options.run_dirs, &kind);
  if (kind != "gnss-ins") {
    ReportSummary summary = WriteAlignmentReport(options, folders, kind);
    summary.run_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
  }
  std::vector<RunData> runs;
  for (std::size_t i = 0; i < options.run_dirs.size(); ++i) {
    if (options.progress) *options.progress << "report: reading " << options.run_dirs[i] << "\n";
    runs.push_back(LoadRunFolder(options.run_dirs[i], folders[i].label, options.run_dirs.size() > 1, options.max_points,
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
  WritePageFiles(options, ReportHtml(runs, set.figures, set.left_out), set.figures);
  ReportSummary summary;
  summary.figures = set.figures.size();
  summary.left_out = set.left_out;
  for (const RunData& r : runs) summary.left_out.insert(summary.left_out.end(), r.notes.begin(), r.notes.end());
  summary.run_time_s = elapsed_s();
  return summary;
}

}  // namespace navtwin::report
