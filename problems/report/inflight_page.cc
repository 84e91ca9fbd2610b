// The report page of inflight-align run folders (alignment_pages.h).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "core/io/input_error.h"
#include "problems/report/alignment_pages.h"
#include "problems/report/csv_table.h"
#include "problems/report/decimate.h"
#include "problems/report/run_folder.h"

namespace navtwin::report {
namespace {

/// One method of one inflight-align folder.
struct InflightMethod {
  const AlignmentFolder* folder = nullptr;
  std::string method;
  std::string label;  ///< "method", or "folder/method" with several folders
  std::string color;
  Series track;       ///< t = path length (km); y: σ, heading error (arcmin)
  bool has_errors = false;
};

/// track.csv against the distance flown, thinned uniformly.
Series LoadInflightTrack(const std::string& path, std::size_t max_points) {
  if (!std::filesystem::is_regular_file(path)) {
    throw InputError(path, 0, "", "missing: every method of summary.json has its track.csv");
  }
  const CsvTable csv(path, {{"path_length_km"}, {"sigma_arcmin"}, {"error_arcmin"}});
  const std::vector<std::size_t> keep = UniformIndices(csv.rows(), max_points);
  return {Pick(csv.number(0), keep), {Pick(csv.number(1), keep), Pick(csv.number(2), keep)}};
}

std::vector<InflightMethod> LoadInflightMethods(const std::vector<AlignmentFolder>& folders, std::size_t max_points,
                                                std::vector<std::string>* notes) {
  std::vector<InflightMethod> out;
  for (const AlignmentFolder& f : folders) {
    for (const auto& kv : f.summary["methods"]) {
      InflightMethod m;
      m.folder = &f;
      m.method = kv.first.Scalar();
      m.label = folders.size() > 1 ? f.label + "/" + m.method : m.method;
      m.color = SeriesColor(out.size());
      m.track = LoadInflightTrack(f.dir + "/" + m.method + "/track.csv", max_points);
      const std::vector<double>& e = m.track.y[1];
      m.has_errors = std::any_of(e.begin(), e.end(), [](double x) { return std::isfinite(x); });
      if (!m.has_errors) notes->push_back(m.label + ": no heading errors in track.csv (run without a truth)");
      out.push_back(std::move(m));
    }
  }
  return out;
}

YAML::Node InflightJson(const InflightMethod& m, const std::string& key) {
  return JsonChild(JsonChild(JsonChild(m.folder->summary, "methods"), m.method), key);
}

double InflightNumber(const InflightMethod& m, const std::string& key, const YAML::Node& node) {
  return JsonNumber(node, m.folder->summary_path, "methods." + m.method + "." + key);
}

/// The distances (km) of the methods' "<key>" objects, increasing, with their keys.
std::vector<std::pair<double, std::string>> InflightDistances(const std::vector<InflightMethod>& methods,
                                                              const std::string& key) {
  std::map<double, std::string> found;
  for (const InflightMethod& m : methods) {
    for (const auto& kv : InflightJson(m, key)) {
      found.emplace(InflightNumber(m, key, kv.first), kv.first.Scalar());
    }
  }
  return {found.begin(), found.end()};
}

/// One row per method: the `key` object's values at the distances, then `finals`.
std::string InflightTable(const std::vector<InflightMethod>& methods, const std::string& heading,
                          const std::string& key, const std::vector<std::pair<std::string, std::string>>& finals) {
  const std::vector<std::pair<double, std::string>> distances = InflightDistances(methods, key);
  std::vector<std::string> head = {"method"};
  for (const auto& d : distances) head.push_back(d.second + " km");
  for (const auto& f : finals) head.push_back(f.second);
  std::string s = "<h3>" + HtmlEscape(heading) + "</h3>\n<table>" + HtmlHead(head);
  for (const InflightMethod& m : methods) {
    s += "<tr>" + HtmlNameCell(m.label);
    for (const auto& d : distances) {
      s += HtmlCell(InflightNumber(m, key + "." + d.second, JsonChild(InflightJson(m, key), d.second)), "%.3f");
    }
    for (const auto& f : finals) s += HtmlCell(InflightNumber(m, f.first, InflightJson(m, f.first)), "%.4g");
    s += "</tr>\n";
  }
  return s + "</table>\n";
}

std::string InflightNotes(const std::vector<InflightMethod>& methods) {
  std::string items;
  for (const InflightMethod& m : methods) {
    const YAML::Node note = InflightJson(m, "note");
    if (note && note.IsScalar() && !note.Scalar().empty()) {
      items += "<li>" + HtmlEscape(m.label + ": " + note.Scalar()) + "</li>\n";
    }
  }
  return items.empty() ? "" : "<h3>Notes of the runs</h3>\n<ul>\n" + items + "</ul>\n";
}

/// The heading error against distance with ±3σ bands; with `second_half` only the second
/// half of the distance flown (where the bands of the start no longer set the scale).
void InflightErrorFigure(const std::vector<InflightMethod>& methods, bool second_half, FigureSet* out) {
  std::vector<BandedSeries> list;
  double longest_km = 0.0;
  for (const InflightMethod& m : methods) {
    for (const double d : m.track.t) {
      if (std::isfinite(d)) longest_km = std::max(longest_km, d);
    }
  }
  const double from_km = second_half ? 0.5 * longest_km : -INFINITY;
  for (const InflightMethod& m : methods) {
    if (!m.has_errors) continue;
    BandedSeries b{m.label, m.color, {}, {}, {}};
    for (std::size_t i = 0; i < m.track.t.size(); ++i) {
      if (!(m.track.t[i] >= from_km)) continue;
      b.x.push_back(m.track.t[i]);
      b.y.push_back(m.track.y[1][i]);
      b.sigma.push_back(m.track.y[0][i]);
    }
    list.push_back(std::move(b));
  }
  if (list.empty()) {
    if (!second_half) {
      out->left_out.push_back("Heading error against distance: no heading errors in any track.csv (run without a truth)");
    }
    return;
  }
  Figure f;
  f.id = second_half ? "heading_error_second_half" : "heading_error";
  f.title = second_half ? "Heading error, second half of the distance" : "Heading error against distance";
  f.script = GnuplotCommon() + "set ylabel 'heading error [arcmin]'\nset xlabel 'distance flown [km]'\n";
  f.script += BandedErrorPlot(list, second_half ? "z" : "h", &f);
  f.caption = "Heading error (estimate − truth, track.csv error_arcmin) of each method against the distance flown, "
              "with its ±3σ band (σ: sigma_arcmin) shaded in the same colour" +
              std::string(second_half ? ", from half the longest distance on" : "") +
              ". The y range is clipped to 1.15 × the 99th percentile of max(|error|, 3σ). Thinned uniformly.";
  out->figures.push_back(std::move(f));
}

Figure InflightSigmaFigure(const std::vector<InflightMethod>& methods) {
  Figure f;
  f.id = "heading_sigma";
  f.title = "Heading σ against distance";
  f.script = GnuplotCommon() + "set logscale y\nset ylabel 'heading σ [arcmin]'\nset xlabel 'distance flown [km]'\n";
  std::string plots;
  for (std::size_t i = 0; i < methods.size(); ++i) {
    const InflightMethod& m = methods[i];
    const std::string name = "s" + std::to_string(i);
    AppendDatablock(&f.script, name, {m.track.t, m.track.y[0]});
    plots += (plots.empty() ? "" : ", ") + std::string("$") + name + " u 1:2 w l lw 1.3 lc rgb '" + m.color +
             "' title " + GnuplotQuote(m.label);
    ++f.series;
  }
  f.script += "plot " + plots + "\n";
  f.caption = "The σ each method states for its heading (track.csv sigma_arcmin) against the distance flown, log "
              "scale. Thinned uniformly.";
  return f;
}

}  // namespace

PageParts InflightPage(const std::vector<AlignmentFolder>& folders, std::size_t max_points) {
  PageParts page;
  std::vector<std::string> notes;
  const std::vector<InflightMethod> methods = LoadInflightMethods(folders, max_points, &notes);
  page.text = AlignmentPageText(
      folders, "in-flight alignment",
      "In-flight heading alignment from the distance flown: the methods of each run folder compared with each other "
      "and with the truth; made by <code>navtwin report</code> from the folders' summary.json and CSV files "
      "(<code>navtwin inflight-align --out</code>).",
      InflightTable(methods, "Heading error (estimate − truth) [arcmin] at the distance flown, and at the end",
                    "heading_error_arcmin_at_km",
                    {{"final_heading_error_arcmin", "final error"}, {"heading_sigma_arcmin", "final σ"},
                     {"path_length_km", "distance [km]"}, {"fixes", "GPS fixes"}, {"gps_sigma_m", "GPS σ [m]"},
                     {"run_time_s", "run [s]"}}) +
          InflightTable(methods, "Heading σ [arcmin] at the distance flown", "heading_sigma_arcmin_at_km", {}) +
          InflightNotes(methods));
  page.text.notes = notes;
  InflightErrorFigure(methods, false, &page.figures);
  InflightErrorFigure(methods, true, &page.figures);
  page.figures.figures.push_back(InflightSigmaFigure(methods));
  return page;
}

}  // namespace navtwin::report
