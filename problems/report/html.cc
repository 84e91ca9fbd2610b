#include "problems/report/html.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "core/text.h"

namespace navtwin::report {
namespace {

const char* const kStyle = R"(
body{font-family:system-ui,-apple-system,"Segoe UI","DejaVu Sans",sans-serif;margin:0 auto;max-width:1100px;
padding:1em 2em;color:#222;line-height:1.45;background:#fff}
h1{font-size:1.6em;margin-bottom:.2em}h2{border-bottom:2px solid #ddd;padding-bottom:.2em;margin-top:2em}
h3{margin-bottom:.3em}
table{border-collapse:collapse;margin:.5em 0 1em;font-size:.9em;display:block;overflow-x:auto;max-width:100%}
th,td{border:1px solid #ccc;padding:.25em .6em;text-align:right;white-space:nowrap}
th{background:#f0f3f7}td.name,th.name{text-align:left}tr:nth-child(even) td{background:#fafafa}
td.bad{background:#fde2e1!important;color:#a00;font-weight:600}
.warnings{border:2px solid #c00;background:#fff3f3;padding:.5em 1em;border-radius:4px}
.warnings li{color:#a00}.ok{color:#276d2a}
figure{margin:1.5em 0;border:1px solid #e0e0e0;padding:.5em;border-radius:4px}
figure img{width:100%;height:auto;display:block}
figcaption{font-size:.9em;color:#444;margin-top:.4em}
figure.broken{border:2px solid #c00}
.note{color:#666;font-size:.9em}nav ul{columns:2}
code{background:#f4f4f4;padding:0 .2em}
)";

const char* const kScript = R"(<script>
window.addEventListener('load', function () {
  var images = document.querySelectorAll('figure img'), loaded = 0;
  images.forEach(function (img) {
    if (img.complete && img.naturalWidth > 0) loaded++; else img.parentNode.classList.add('broken');
  });
  document.body.setAttribute('data-figures-loaded', loaded + '/' + images.length);
});
</script>)";

}  // namespace

std::string HtmlNumber(const char* format, double x) {
  if (!std::isfinite(x)) return "–";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

std::string HtmlCell(double x, const char* format, bool bad) {
  return std::string(bad ? "<td class=\"bad\">" : "<td>") + HtmlNumber(format, x) + "</td>";
}

std::string HtmlNameCell(const std::string& text) { return "<td class=\"name\">" + HtmlEscape(text) + "</td>"; }

std::string HtmlHead(const std::vector<std::string>& names, std::size_t text_columns) {
  std::string s = "<tr>";
  for (std::size_t i = 0; i < names.size(); ++i) {
    s += std::string(i < text_columns ? "<th class=\"name\">" : "<th>") + HtmlEscape(names[i]) + "</th>";
  }
  return s + "</tr>\n";
}

namespace {

std::string MethodName(const RunData& run, const std::string& method, bool several) {
  return several ? run.label + "/" + method : method;
}

double SummaryNumber(const RunData& run, const YAML::Node& node, const std::string& key) {
  return JsonNumber(node, run.summary_path, key);
}

std::string InputsSection(const std::vector<RunData>& runs) {
  std::string s = "<h2 id=\"inputs\">Runs</h2>\n<table>" +
                  HtmlHead({"folder", "command", "output", "IMU samples", "GNSS epochs", "removed by outages", "outages",
                        "span [s]", "reference"}, 3);
  for (const RunData& r : runs) {
    const YAML::Node in = JsonChild(r.summary, "inputs");
    const std::string p = r.summary_path;
    s += "<tr>" + HtmlNameCell(r.dir) + HtmlNameCell(JsonChild(r.summary, "command") ? JsonChild(r.summary, "command").Scalar() : "") +
         HtmlNameCell(r.output_method) + HtmlCell(JsonNumber(JsonChild(in, "imu_samples"), p, "inputs.imu_samples"), "%.0f") +
         HtmlCell(JsonNumber(JsonChild(in, "gnss_epochs"), p, "inputs.gnss_epochs"), "%.0f") +
         HtmlCell(JsonNumber(JsonChild(in, "gnss_removed_by_outages"), p, "inputs.gnss_removed_by_outages"), "%.0f") +
         HtmlCell(static_cast<double>(r.outages.size()), "%.0f") +
         HtmlCell(JsonNumber(JsonChild(in, "t_end_s"), p, "inputs.t_end_s") - JsonNumber(JsonChild(in, "t_start_s"), p, "inputs.t_start_s"),
              "%.1f") +
         HtmlNameCell(JsonChild(r.summary, "truth") ? JsonChild(r.summary, "truth").Scalar() : "none") + "</tr>\n";
  }
  return s + "</table>\n";
}

std::string WarningsSection(const std::vector<RunData>& runs) {
  std::string items;
  for (const RunData& r : runs) {
    for (const YAML::Node& w : JsonChild(r.summary, "warnings")) {
      items += "<li>" + HtmlEscape((runs.size() > 1 ? r.label + ": " : "") + w.Scalar()) + "</li>\n";
    }
  }
  if (items.empty()) return "<h2 id=\"warnings\">Warnings</h2>\n<p class=\"ok\">No warnings.</p>\n";
  return "<h2 id=\"warnings\">Warnings</h2>\n<div class=\"warnings\"><ul>\n" + items + "</ul></div>\n";
}

std::string ErrorsTable(const std::vector<RunData>& runs) {
  std::string rows;
  for (const RunData& r : runs) {
    for (const auto& kv : JsonChild(r.summary, "methods")) {
      const YAML::Node e = JsonChild(kv.second, "errors");
      if (!e) continue;
      const YAML::Node all = JsonChild(e, "all");
      const std::string k = "methods." + kv.first.Scalar() + ".errors.";
      rows += "<tr>" + HtmlNameCell(MethodName(r, kv.first.Scalar(), runs.size() > 1)) +
              HtmlCell(SummaryNumber(r, JsonChild(JsonChild(all, "horizontal_m"), "rms"), k + "all.horizontal_m.rms")) +
              HtmlCell(SummaryNumber(r, JsonChild(JsonChild(all, "horizontal_m"), "max"), k + "all.horizontal_m.max")) +
              HtmlCell(SummaryNumber(r, JsonChild(JsonChild(all, "vertical_m"), "rms"), k + "all.vertical_m.rms")) +
              HtmlCell(SummaryNumber(r, JsonChild(all, "velocity_rms_mps"), k + "all.velocity_rms_mps")) +
              HtmlCell(SummaryNumber(r, JsonChild(JsonChild(all, "roll_deg"), "rms"), k + "all.roll_deg.rms")) +
              HtmlCell(SummaryNumber(r, JsonChild(JsonChild(all, "pitch_deg"), "rms"), k + "all.pitch_deg.rms")) +
              HtmlCell(SummaryNumber(r, JsonChild(JsonChild(all, "yaw_deg"), "rms"), k + "all.yaw_deg.rms")) +
              HtmlCell(SummaryNumber(r, JsonChild(e, "outage_horizontal_rms_m"), k + "outage_horizontal_rms_m")) +
              HtmlCell(SummaryNumber(r, JsonChild(e, "outage_vertical_rms_m"), k + "outage_vertical_rms_m")) +
              HtmlCell(SummaryNumber(r, JsonChild(kv.second, "run_time_s"), "methods." + kv.first.Scalar() + ".run_time_s"), "%.2f") + "</tr>\n";
    }
  }
  if (rows.empty()) return "<p class=\"note\">No errors: the runs had no reference (--truth).</p>\n";
  return "<h3>Errors (RMS over every compared epoch; drift: RMS over the outages of the per-outage maximum)</h3>\n<table>" +
         HtmlHead({"method", "horiz. RMS [m]", "horiz. max [m]", "vert. RMS [m]", "vel. RMS [m/s]", "roll [deg]",
               "pitch [deg]", "yaw [deg]", "drift H [m]", "drift V [m]", "run [s]"}) +
         rows + "</table>\n";
}

/// err/sigma beyond 3 or below 1/3: the sigma is not honest (the run's own warning rule).
bool Dishonest(double ratio) { return std::isfinite(ratio) && (ratio > 3.0 || ratio < 1.0 / 3.0); }

std::string ConsistencyTable(const std::vector<RunData>& runs) {
  static const char* const kKeys[9] = {"pos_n", "pos_e", "pos_d", "vel_n", "vel_e", "vel_d", "roll", "pitch", "yaw"};
  std::string rows;
  for (const RunData& r : runs) {
    for (const auto& kv : JsonChild(r.summary, "methods")) {
      const YAML::Node c = JsonChild(JsonChild(kv.second, "errors"), "consistency");
      if (!c) continue;
      for (const char* scope : {"all", "inside_outages"}) {
        const YAML::Node s = JsonChild(c, scope);
        if (!s) continue;
        const std::string k = "methods." + kv.first.Scalar() + ".errors.consistency." + scope + ".";
        rows += "<tr>" + HtmlNameCell(MethodName(r, kv.first.Scalar(), runs.size() > 1)) + HtmlNameCell(scope) +
                HtmlCell(SummaryNumber(r, JsonChild(s, "epochs"), k + "epochs"), "%.0f");
        for (const char* key : kKeys) {
          const double v = SummaryNumber(r, JsonChild(s, key), k + key);
          rows += HtmlCell(v, "%.2f", Dishonest(v));
        }
        rows += HtmlCell(SummaryNumber(r, JsonChild(s, "pos_nees_mean"), k + "pos_nees_mean"), "%.2f") + "</tr>\n";
      }
    }
  }
  if (rows.empty()) return "";
  return "<h3>err/σ (RMS; 1 = honest σ; red beyond 3 or below 1/3) and mean position NEES (expected 3)</h3>\n<table>" +
         HtmlHead({"method", "scope", "epochs", "pos N", "pos E", "pos D", "vel N", "vel E", "vel D", "roll", "pitch",
               "yaw", "NEES pos"}, 2) +
         rows + "</table>\n";
}

std::string ResidualsTable(const std::vector<RunData>& runs) {
  std::string rows;
  for (const RunData& r : runs) {
    for (const auto& kv : JsonChild(r.summary, "methods")) {
      const std::string m = kv.first.Scalar();
      for (const auto& g : JsonChild(kv.second, "residuals")) {
        const YAML::Node v = g.second;
        const std::string k = "methods." + m + ".residuals." + g.first.Scalar() + ".";
        const double dof = SummaryNumber(r, JsonChild(v, "dof"), k + "dof");
        const double configured = JsonChild(v, "configured_chi2_per_dof") && !JsonChild(v, "configured_chi2_per_dof").IsNull()
                                      ? SummaryNumber(r, JsonChild(v, "configured_chi2_per_dof"), k + "configured_chi2_per_dof")
                                      : SummaryNumber(r, JsonChild(v, "chi2_per_dof"), k + "chi2_per_dof");
        const bool adapted = JsonChild(v, "adapted") && JsonChild(v, "adapted").Scalar() == "true";
        const YAML::Node count = JsonChild(JsonChild(kv.second, "counts"), g.first.Scalar());
        rows += "<tr>" + HtmlNameCell(MethodName(r, m, runs.size() > 1)) + HtmlNameCell(g.first.Scalar()) +
                HtmlCell(SummaryNumber(r, JsonChild(v, "rows"), k + "rows"), "%.0f") + HtmlCell(dof, "%.1f") +
                HtmlCell(count ? SummaryNumber(r, JsonChild(count, "rejected"), "counts.rejected") : std::nan(""), "%.0f") +
                HtmlCell(dof >= 1.0 ? configured : std::nan(""), "%.3f", dof >= 10.0 && configured > 3.0) +
                HtmlCell(adapted ? SummaryNumber(r, JsonChild(v, "sigma_scale"), k + "sigma_scale") : std::nan(""), "%.3f") +
                HtmlCell(adapted ? SummaryNumber(r, JsonChild(v, "chi2_per_dof"), k + "chi2_per_dof") : std::nan(""), "%.3f") + "</tr>\n";
      }
    }
  }
  if (rows.empty()) return "";
  return "<h3>Residual statistics (whitened; χ²/dof near 1 when the noise fits; batch: σ scale from the variance "
         "components)</h3>\n<table>" +
         HtmlHead({"method", "group", "rows", "dof", "rejected", "χ²/dof configured", "σ scale", "χ²/dof adapted"}, 2) + rows +
         "</table>\n";
}

}  // namespace

std::string HtmlEscape(const std::string& text) { return MarkupEscaped(text); }

std::string Base64(const std::string& bytes) {
  static const char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) | (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    for (int k = 3; k >= 0; --k) out += kAlphabet[(v >> (6 * k)) & 63];
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (two ? static_cast<unsigned char>(bytes[i + 1]) << 8 : 0u);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += two ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

namespace {

/// One parameter of one method: "value ± σ" (scale factors in ppm), "not observable" in red.
std::string ParameterCell(const RunData& r, const std::string& m, const std::string& kind, const std::string& name) {
  const YAML::Node p = JsonChild(JsonChild(JsonChild(JsonChild(r.summary, "methods"), m), kind), name);
  if (!p) return "<td>–</td>";
  const double scale = kind == "imu_scale_factors" ? 1e6 : 1.0;
  const std::string k = "methods." + m + "." + kind + "." + name + ".";
  const double value = SummaryNumber(r, JsonChild(p, "value"), k + "value") * scale, std = SummaryNumber(r, JsonChild(p, "std"), k + "std") * scale;
  if (JsonChild(p, "observable") && JsonChild(p, "observable").Scalar() == "false") {
    return "<td class=\"bad\">not observable (" + HtmlNumber("%.4g", value) + " ± " + HtmlNumber("%.2g", std) + ")</td>";
  }
  return "<td>" + HtmlNumber("%.4g", value) + " ± " + HtmlNumber("%.2g", std) + "</td>";
}

/// Per folder: one row per parameter (auxiliary states, IMU scale factors), one column per method.
std::string ParametersTable(const std::vector<RunData>& runs) {
  std::string out;
  for (const RunData& r : runs) {
    std::vector<std::string> methods;
    std::vector<std::pair<std::string, std::string>> params;  // kind, name
    for (const auto& kv : JsonChild(r.summary, "methods")) {
      methods.push_back(kv.first.Scalar());
      for (const char* kind : {"aux", "imu_scale_factors"}) {
        for (const auto& p : JsonChild(kv.second, kind)) {
          const std::pair<std::string, std::string> key{kind, p.first.Scalar()};
          if (std::find(params.begin(), params.end(), key) == params.end()) params.push_back(key);
        }
      }
    }
    if (params.empty()) continue;
    std::vector<std::string> head = {"parameter"};
    head.insert(head.end(), methods.begin(), methods.end());
    out += (runs.size() > 1 ? "<p>" + HtmlEscape(r.label) + ":</p>" : std::string()) + "<table>" + HtmlHead(head);
    for (const auto& [kind, name] : params) {
      out += "<tr>" + HtmlNameCell(name + (kind == "imu_scale_factors" ? " [ppm]" : ""));
      for (const std::string& m : methods) out += ParameterCell(r, m, kind, name);
      out += "</tr>\n";
    }
    out += "</table>\n";
  }
  if (out.empty()) return "<p class=\"note\">No estimated parameters (auxiliary states, IMU scale factors).</p>\n";
  return "<h3>Estimated parameters at the end of the record (value ± σ; aiding-source states in SI units, IMU scale "
         "factors in ppm; not observable: σ ≥ 0.9 × prior σ)</h3>\n" + out;
}

std::string AdaptedNoiseList(const std::vector<RunData>& runs) {
  std::string items;
  for (const RunData& r : runs) {
    for (const YAML::Node& line : JsonChild(r.summary, "adapted_noise")) {
      items += "<li><code>" + HtmlEscape((runs.size() > 1 ? r.label + ": " : "") + line.Scalar()) + "</code></li>\n";
    }
  }
  if (items.empty()) return "<h3>Adapted noise</h3>\n<p class=\"note\">No noise adapted (no batch variance components).</p>\n";
  return "<h3>Noise adapted by the batch's variance components (used by filter_adapted and rts_adapted)</h3>\n<ul>\n" +
         items + "</ul>\n";
}

}  // namespace

std::string HtmlAnchor(const std::string& id) {
  std::string out;
  for (char c : id) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  return out;
}

namespace {

std::string FigureHtml(const Figure& f) {
  return "<figure id=\"" + HtmlAnchor(f.id) + "\" data-series=\"" + std::to_string(f.series) + "\">\n<h3>" +
         HtmlEscape(f.title) + "</h3>\n<img alt=\"" + HtmlEscape(f.title) + "\" width=\"" + std::to_string(f.width_px) +
         "\" height=\"" + std::to_string(f.height_px) + "\" src=\"data:image/svg+xml;base64," + Base64(f.svg) +
         "\">\n<figcaption>" + HtmlEscape(f.caption) + "</figcaption>\n</figure>\n";
}

std::string Contents(const std::vector<PageSection>& sections, const std::vector<Figure>& figures) {
  std::string s = "<nav><ul>\n";
  for (const PageSection& p : sections) s += "<li><a href=\"#" + HtmlAnchor(p.id) + "\">" + HtmlEscape(p.title) + "</a></li>";
  s += "\n";
  for (const Figure& f : figures) s += "<li><a href=\"#" + HtmlAnchor(f.id) + "\">" + HtmlEscape(f.title) + "</a></li>\n";
  return s + "<li><a href=\"#left_out\">Left out</a></li></ul></nav>\n";
}

std::string LeftOutSection(const std::vector<std::string>& left_out, const std::vector<std::string>& notes) {
  std::string s = "<h2 id=\"left_out\">Left out</h2>\n";
  std::string items;
  for (const std::string& why : left_out) items += "<li>" + HtmlEscape(why) + "</li>\n";
  for (const std::string& n : notes) items += "<li class=\"note\">" + HtmlEscape(n) + "</li>\n";
  return s + (items.empty() ? "<p class=\"note\">Nothing: every figure was made.</p>\n" : "<ul>\n" + items + "</ul>\n");
}

}  // namespace

std::string HtmlPage(const PageText& text, const std::vector<Figure>& figures, const std::vector<std::string>& left_out) {
  std::string s = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" +
                  HtmlEscape(text.title) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n<h1>" +
                  HtmlEscape(text.title) + "</h1>\n<p class=\"note\">" + text.intro + "</p>\n";
  s += Contents(text.sections, figures) + text.body;
  s += "<h2 id=\"figures\">Figures</h2>\n";
  for (const Figure& f : figures) s += FigureHtml(f);
  s += LeftOutSection(left_out, text.notes);
  return s + kScript + "\n</body>\n</html>\n";
}

std::string ReportHtml(const std::vector<RunData>& runs, const std::vector<Figure>& figures,
                       const std::vector<std::string>& left_out) {
  PageText text;
  text.title = "navtwin report:";
  for (const RunData& r : runs) text.title += " " + r.label;
  text.intro = "Filter, RTS smoother and batch smoother of each run folder compared with each other and with the "
               "reference; made by <code>navtwin report</code> from the folders' summary.json and CSV files.";
  text.sections = {{"inputs", "Runs"}, {"warnings", "Warnings"}, {"tables", "Summary tables"}};
  text.body = InputsSection(runs) + WarningsSection(runs) + "<h2 id=\"tables\">Summary tables</h2>\n" +
              ErrorsTable(runs) + ConsistencyTable(runs) + ResidualsTable(runs) + ParametersTable(runs) +
              AdaptedNoiseList(runs);
  for (const RunData& r : runs) text.notes.insert(text.notes.end(), r.notes.begin(), r.notes.end());
  return HtmlPage(text, figures, left_out);
}

}  // namespace navtwin::report
