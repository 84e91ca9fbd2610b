// The report page of level-mc run folders (alignment_pages.h).
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/io/input_error.h"
#include "problems/report/alignment_pages.h"
#include "problems/report/csv_table.h"
#include "problems/report/gnuplot.h"
#include "problems/report/run_folder.h"

namespace navtwin::report {
namespace {

/// Bins of the error histograms: enough to show a Gaussian's shape over a few thousand runs.
constexpr int kHistogramBins = 60;

/// One method of one level-mc folder: every run's pitch and roll error.
struct LevelingMethod {
  const AlignmentFolder* folder = nullptr;
  std::string method;
  std::string label;  ///< "method", or "folder/method" with several folders
  std::string color;
  std::vector<double> pitch_deg, roll_deg;
};

std::vector<LevelingMethod> LoadLevelingMethods(const std::vector<AlignmentFolder>& folders) {
  std::vector<LevelingMethod> out;
  for (const AlignmentFolder& f : folders) {
    const std::string path = f.dir + "/errors.csv";
    if (!std::filesystem::is_regular_file(path)) {
      throw InputError(path, 0, "", "missing: a level-mc folder has every run's errors in errors.csv");
    }
    std::vector<std::string> names;
    std::vector<CsvColumn> columns;
    for (const auto& kv : f.summary["methods"]) {
      names.push_back(kv.first.Scalar());
      columns.push_back({names.back() + "_pitch_deg"});
      columns.push_back({names.back() + "_roll_deg"});
    }
    const CsvTable csv(path, columns);
    for (std::size_t i = 0; i < names.size(); ++i) {
      LevelingMethod m;
      m.folder = &f;
      m.method = names[i];
      m.label = folders.size() > 1 ? f.label + "/" + m.method : m.method;
      m.color = SeriesColor(out.size());
      m.pitch_deg = csv.number(2 * i);
      m.roll_deg = csv.number(2 * i + 1);
      out.push_back(std::move(m));
    }
  }
  return out;
}

double LevelingNumber(const LevelingMethod& m, const std::string& key) {
  const YAML::Node node = JsonChild(JsonChild(JsonChild(m.folder->summary, "methods"), m.method), key);
  return JsonNumber(node, m.folder->summary_path, "methods." + m.method + "." + key);
}

std::string LevelingTable(const std::vector<LevelingMethod>& methods) {
  const std::vector<std::pair<std::string, std::string>> columns = {
      {"pitch_rms_deg", "pitch RMS [deg]"},        {"pitch_max_deg", "pitch max [deg]"},
      {"roll_rms_deg", "roll RMS [deg]"},          {"roll_max_deg", "roll max [deg]"},
      {"pitch_sigma_mean_deg", "mean σ pitch [deg]"}, {"roll_sigma_mean_deg", "mean σ roll [deg]"},
      {"pitch_error_over_sigma_rms", "pitch err/σ RMS"}, {"fallbacks", "fallbacks"},
      {"cpu_time_s", "CPU [s]"}};
  std::vector<std::string> head = {"method", "runs"};
  for (const auto& c : columns) head.push_back(c.second);
  std::string s = "<h3>Errors over the runs (estimate − truth)</h3>\n<table>" + HtmlHead(head);
  for (const LevelingMethod& m : methods) {
    s += "<tr>" + HtmlNameCell(m.label) + HtmlCell(static_cast<double>(m.pitch_deg.size()), "%.0f");
    for (const auto& c : columns) s += HtmlCell(LevelingNumber(m, c.first), "%.4g");
    s += "</tr>\n";
  }
  return s + "</table>\n";
}

/// RMS of the finite values (NaN without any).
double FiniteRms(const std::vector<double>& v) {
  double ss = 0.0;
  std::size_t n = 0;
  for (const double x : v) {
    if (std::isfinite(x)) ss += x * x, ++n;
  }
  return n > 0 ? std::sqrt(ss / static_cast<double>(n)) : NAN;
}

/// One panel of a histogram figure: the method's errors on kHistogramBins bins over [-L, L],
/// L its largest finite |error| but at most 6 × its RMS (heavy tails would squeeze the
/// histogram into a few bins; the runs beyond are counted in the key), and the normal
/// density of its RMS dashed. Appends the datablock `name` and returns the plot command.
std::string HistogramPanel(const LevelingMethod& m, const std::vector<double>& e, const std::string& name,
                           Figure* f) {
  const double rms = FiniteRms(e);
  double largest = 0.0;
  for (const double x : e) {
    if (std::isfinite(x)) largest = std::max(largest, std::abs(x));
  }
  double limit = rms > 0.0 ? std::min(largest, 6.0 * rms) : largest;
  if (!(limit > 0.0)) limit = 1.0;
  const double width = 2.0 * limit / kHistogramBins;
  std::vector<double> centres(kHistogramBins), counts(kHistogramBins, 0.0);
  for (int b = 0; b < kHistogramBins; ++b) centres[b] = -limit + (b + 0.5) * width;
  std::size_t runs = 0, beyond = 0;
  for (const double x : e) {
    if (!std::isfinite(x)) continue;
    ++runs;
    if (std::abs(x) > limit) {
      ++beyond;
      continue;
    }
    counts[std::min(kHistogramBins - 1, static_cast<int>((x + limit) / width))] += 1.0;
  }
  AppendDatablock(&f->script, name, {centres, counts});
  std::string title = m.label + ": RMS " + GnuplotNumber("%.3g", rms) + " deg";
  if (beyond > 0) title += ", " + std::to_string(beyond) + " beyond";
  const double s = rms > 0.0 ? rms : 1.0;
  f->series += 2;
  return "set xrange [" + GnuplotNumber("%.9g", -limit) + ":" + GnuplotNumber("%.9g", limit) + "]\nplot $" + name +
         " u 1:2 w histeps lw 1.4 lc rgb '" + m.color + "' title " + GnuplotQuote(title) + ", " +
         GnuplotNumber("%.9g", static_cast<double>(runs) * width / (s * std::sqrt(2.0 * M_PI))) + " * exp(-0.5 * (x / " +
         GnuplotNumber("%.9g", s) + ")**2) w l dt 2 lw 1.2 lc rgb '#000000' title 'normal, same RMS'\n";
}

/// The histograms of one error (pitch or roll): one panel per method (two columns), each
/// on its own range.
Figure HistogramFigure(const std::vector<LevelingMethod>& methods, bool pitch) {
  const char* what = pitch ? "pitch" : "roll";
  const std::size_t columns = methods.size() > 1 ? 2 : 1;
  const std::size_t rows = (methods.size() + columns - 1) / columns;
  Figure f;
  f.id = std::string(what) + "_histogram";
  f.title = std::string("Histograms of the ") + what + " error";
  f.height_px = static_cast<int>(std::max<std::size_t>(1, rows)) * 320 + 80;
  f.script = GnuplotCommon() + "set multiplot layout " + std::to_string(rows) + "," + std::to_string(columns) +
             "\nset ylabel 'runs per bin'\nset xlabel '" + what + " error [deg]'\nset samples 400\n" +
             "set offsets 0, 0, graph 0.3, 0\n";  // room above the peak for the key
  for (std::size_t i = 0; i < methods.size(); ++i) {
    f.script += HistogramPanel(methods[i], pitch ? methods[i].pitch_deg : methods[i].roll_deg,
                               std::string(what) + std::to_string(i), &f);
  }
  f.script += "unset multiplot\n";
  f.caption = std::string("The ") + what + " error of every run (errors.csv), one panel per method: " +
              std::to_string(kHistogramBins) +
              " bins over ± the method's largest error, or ± 6 × its RMS when the tails are longer (the runs beyond "
              "the axis are counted in the key); dashed: the normal density with the method's RMS. Non-finite "
              "errors left out.";
  return f;
}

}  // namespace

PageParts LevelingPage(const std::vector<AlignmentFolder>& folders, std::size_t max_points) {
  (void)max_points;  // histograms use every run
  PageParts page;
  const std::vector<LevelingMethod> methods = LoadLevelingMethods(folders);
  page.text = AlignmentPageText(
      folders, "leveling Monte Carlo",
      "Leveling under rotor vibration: every method's roll and pitch errors over the Monte Carlo runs; made by "
      "<code>navtwin report</code> from the folders' summary.json and errors.csv (<code>navtwin level-mc "
      "--out</code>).",
      LevelingTable(methods));
  page.figures.figures.push_back(HistogramFigure(methods, true));
  page.figures.figures.push_back(HistogramFigure(methods, false));
  return page;
}

}  // namespace navtwin::report
