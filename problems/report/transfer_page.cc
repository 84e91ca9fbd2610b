// The report page of transfer-align run folders (alignment_pages.h).
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>

#include "core/io/input_error.h"
#include "core/units.h"
#include "problems/report/alignment_pages.h"
#include "problems/report/csv_table.h"
#include "problems/report/decimate.h"
#include "problems/report/run_folder.h"

namespace navtwin::report {
namespace {

/// One method of one transfer-align folder.
struct TransferMethod {
  const AlignmentFolder* folder = nullptr;
  std::string method;
  std::string label;           ///< "method", or "folder/method" with several folders
  std::string color;
  Series estimates;            ///< y: misalignment roll, pitch, yaw (deg) and their σ (deg), delay and σ (ms)
  bool has_attitude = false;
  std::array<Series, 3> attitude;  ///< y[0]: slave roll, pitch, heading error (mrad)
  std::array<double, 3> true_deg{};
  double delay_true_s = 0.0;
};

/// Element i of the 3-array node[key] of a method (NaN when absent or null).
double TransferJsonElement(const YAML::Node& method, const std::string& key, std::size_t i, const std::string& path,
                           const std::string& where) {
  const YAML::Node a = JsonChild(method, key);
  if (!a || a.IsNull()) return std::nan("");
  if (!a.IsSequence() || a.size() != 3) {
    throw InputError(path, a.Mark().line >= 0 ? a.Mark().line + 1 : 0, where + key, "expected an array of 3 numbers");
  }
  return JsonNumber(a[i], path, where + key);
}

/// estimates.csv thinned uniformly (the estimates are smooth), σ in deg and the delay in ms.
Series LoadTransferEstimates(const std::string& path, std::size_t max_points) {
  if (!std::filesystem::is_regular_file(path)) {
    throw InputError(path, 0, "", "missing: every method of summary.json has its estimates.csv");
  }
  const CsvTable csv(path, {{"t_s"}, {"mis_roll_deg"}, {"mis_pitch_deg"}, {"mis_yaw_deg"}, {"mis_roll_std_mrad"},
                            {"mis_pitch_std_mrad"}, {"mis_yaw_std_mrad"}, {"delay_s"}, {"delay_std_s"}});
  const std::vector<std::size_t> keep = UniformIndices(csv.rows(), max_points);
  Series s{Pick(csv.number(0), keep), {}};
  for (std::size_t c = 1; c <= 8; ++c) {
    std::vector<double> v = Pick(csv.number(c), keep);
    const double scale = c >= 4 && c <= 6 ? 1e-3 * kRadToDeg : c >= 7 ? 1e3 : 1.0;
    for (double& x : v) x *= scale;
    s.y.push_back(std::move(v));
  }
  return s;
}

/// attitude_errors.csv: each component thinned keeping its extremes.
std::array<Series, 3> LoadTransferAttitude(const std::string& path, std::size_t max_points) {
  const CsvTable csv(path, {{"t_s"}, {"roll_err_mrad"}, {"pitch_err_mrad"}, {"heading_err_mrad"}});
  std::array<Series, 3> out;
  for (std::size_t c = 0; c < 3; ++c) {
    const std::vector<std::size_t> keep = MinMaxIndices(csv.number(c + 1), max_points);
    out[c] = {Pick(csv.number(0), keep), {Pick(csv.number(c + 1), keep)}};
  }
  return out;
}

std::vector<TransferMethod> LoadTransferMethods(const std::vector<AlignmentFolder>& folders, std::size_t max_points,
                                                std::vector<std::string>* notes) {
  std::vector<TransferMethod> out;
  for (const AlignmentFolder& f : folders) {
    for (const auto& kv : f.summary["methods"]) {
      TransferMethod m;
      m.folder = &f;
      m.method = kv.first.Scalar();
      m.label = folders.size() > 1 ? f.label + "/" + m.method : m.method;
      m.color = SeriesColor(out.size());
      const std::string where = "methods." + m.method + ".";
      for (std::size_t i = 0; i < 3; ++i) {
        m.true_deg[i] = TransferJsonElement(kv.second, "misalignment_true_deg", i, f.summary_path, where);
      }
      m.delay_true_s = JsonNumber(JsonChild(kv.second, "delay_true_s"), f.summary_path, where + "delay_true_s");
      m.estimates = LoadTransferEstimates(f.dir + "/" + m.method + "/estimates.csv", max_points);
      const std::string attitude = f.dir + "/" + m.method + "/attitude_errors.csv";
      m.has_attitude = std::filesystem::is_regular_file(attitude);
      if (m.has_attitude) m.attitude = LoadTransferAttitude(attitude, max_points);
      else notes->push_back(m.label + ": no " + m.method + "/attitude_errors.csv (run without a truth)");
      out.push_back(std::move(m));
    }
  }
  return out;
}

double TransferNumber(const TransferMethod& m, const std::string& key) {
  const YAML::Node node = JsonChild(JsonChild(JsonChild(m.folder->summary, "methods"), m.method), key);
  return JsonNumber(node, m.folder->summary_path, "methods." + m.method + "." + key);
}

std::string TransferAttitudeTable(const std::vector<TransferMethod>& methods) {
  std::string s = "<h3>Slave attitude errors after the settling time (estimate − truth) [mrad]</h3>\n<table>" +
                  HtmlHead({"method", "roll RMS", "pitch RMS", "heading RMS", "roll max", "pitch max", "heading max",
                            "epochs", "run [s]"});
  for (const TransferMethod& m : methods) {
    s += "<tr>" + HtmlNameCell(m.label);
    for (const char* key : {"roll_rms_mrad", "pitch_rms_mrad", "heading_rms_mrad", "roll_max_mrad", "pitch_max_mrad",
                            "heading_max_mrad"}) {
      s += HtmlCell(TransferNumber(m, key), "%.3f");
    }
    s += HtmlCell(TransferNumber(m, "epochs"), "%.0f") + HtmlCell(TransferNumber(m, "run_time_s"), "%.2f") + "</tr>\n";
  }
  return s + "</table>\n";
}

std::string TransferEstimatesTable(const std::vector<TransferMethod>& methods) {
  std::string s = "<h3>Final estimates (value ± σ; true value of the simulation)</h3>\n<table>" +
                  HtmlHead({"method", "delay [ms]", "true delay [ms]", "misalignment roll [deg] ± [mrad]",
                            "pitch [deg] ± [mrad]", "yaw [deg] ± [mrad]", "true [deg]", "misalignment error [mrad]",
                            "note"});
  for (const TransferMethod& m : methods) {
    const YAML::Node j = JsonChild(JsonChild(m.folder->summary, "methods"), m.method);
    const std::string where = "methods." + m.method + ".";
    s += "<tr>" + HtmlNameCell(m.label) + "<td>" + HtmlNumber("%.3f", 1e3 * TransferNumber(m, "delay_est_s")) +
         " ± " + HtmlNumber("%.2g", 1e3 * TransferNumber(m, "delay_sigma_s")) + "</td>" +
         HtmlCell(1e3 * m.delay_true_s, "%.3f");
    for (std::size_t i = 0; i < 3; ++i) {
      s += "<td>" + HtmlNumber("%.4f", TransferJsonElement(j, "misalignment_deg", i, m.folder->summary_path, where)) +
           " ± " + HtmlNumber("%.2g", TransferJsonElement(j, "misalignment_sigma_mrad", i, m.folder->summary_path, where)) +
           "</td>";
    }
    s += "<td>" + HtmlNumber("%.4f", m.true_deg[0]) + ", " + HtmlNumber("%.4f", m.true_deg[1]) + ", " +
         HtmlNumber("%.4f", m.true_deg[2]) + "</td>" + HtmlCell(TransferNumber(m, "misalignment_error_mrad"), "%.3f") +
         HtmlNameCell(JsonChild(j, "note") ? JsonChild(j, "note").Scalar() : "") + "</tr>\n";
  }
  return s + "</table>\n";
}

/// The y range of estimates and true values, 10 % wider: the ±3σ bands of the first
/// seconds (σ of the prior) would hide the convergence.
std::string TransferYRange(const std::vector<const std::vector<double>*>& values, const std::vector<double>& lines) {
  double lo = INFINITY, hi = -INFINITY;
  for (const std::vector<double>* v : values) {
    for (double x : *v) {
      if (std::isfinite(x)) lo = std::min(lo, x), hi = std::max(hi, x);
    }
  }
  for (double x : lines) {
    if (std::isfinite(x)) lo = std::min(lo, x), hi = std::max(hi, x);
  }
  if (!(lo <= hi)) return "set autoscale y\n";
  const double pad = std::max(0.1 * (hi - lo), 1e-6 * std::max(1.0, std::abs(hi)));
  return "set yrange [" + GnuplotNumber("%.9g", lo - pad) + ":" + GnuplotNumber("%.9g", hi + pad) + "]\n";
}

/// One panel: per method the estimate (column `value` of the estimates) with its ±3σ band
/// about it (σ: column `sigma`), and per folder its true value (`truth(m)`) as a dashed black line.
template <typename Truth>
std::string TransferEstimatePanel(const std::vector<TransferMethod>& methods, std::size_t value, std::size_t sigma,
                                  const std::string& block, Truth truth, Figure* f) {
  std::string plots;
  std::vector<const std::vector<double>*> values;
  std::vector<double> lines;
  const AlignmentFolder* previous = nullptr;
  for (std::size_t i = 0; i < methods.size(); ++i) {
    const TransferMethod& m = methods[i];
    const std::string name = block + std::to_string(i);
    AppendDatablock(&f->script, name, {m.estimates.t, m.estimates.y[value], m.estimates.y[sigma]});
    values.push_back(&m.estimates.y[value]);
    plots += (plots.empty() ? "" : ", ") + std::string("$") + name + " u 1:($2-3*$3):($2+3*$3) w filledcurves fc rgb '" +
             m.color + "' fs transparent solid 0.15 noborder notitle, $" + name + " u 1:2 w l lw 1.3 lc rgb '" +
             m.color + "' title " + GnuplotQuote(m.label);
    f->series += 2;
    if (m.folder != previous && std::isfinite(truth(m))) {
      lines.push_back(truth(m));
      plots += ", " + GnuplotNumber("%.9g", truth(m)) + " w l lw 1.5 dt 2 lc rgb '#000000' title " +
               GnuplotQuote(m.label != m.method ? m.folder->label + ": true" : "true");
      ++f->series;
    }
    previous = m.folder;
  }
  return TransferYRange(values, lines) + "plot " + plots + "\n";
}

Figure TransferMisalignmentFigure(const std::vector<TransferMethod>& methods) {
  Figure f;
  f.id = "misalignment";
  f.title = "Misalignment estimates";
  f.height_px = 820;
  f.script = GnuplotCommon() + "set multiplot layout 3,1\nset lmargin 12\n";
  static const char* const kAxes[3] = {"roll", "pitch", "yaw"};
  for (std::size_t k = 0; k < 3; ++k) {
    f.script += "set ylabel " + GnuplotQuote(std::string(kAxes[k]) + " misalignment [deg]") + "\n";
    f.script += k == 2 ? "set xlabel 'time [s]'\n" : "unset xlabel\n";
    f.script += k == 0 ? "" : "set key off\n";
    f.script += TransferEstimatePanel(methods, k, k + 3, "m" + std::to_string(k) + "_",
                                      [k](const TransferMethod& m) { return m.true_deg[k]; }, &f);
  }
  f.script += "unset multiplot\n";
  f.caption = "Misalignment of the slave IMU (ZYX Euler angles of R_b_s, estimates.csv) of each method against time, "
              "with its ±3σ band shaded in the same colour; dashed black: the true misalignment (summary.json "
              "misalignment_true_deg) when the run knew it. The y range spans the estimates and the true values "
              "(the bands of the first seconds are cut). Thinned uniformly.";
  return f;
}

Figure TransferDelayFigure(const std::vector<TransferMethod>& methods) {
  Figure f;
  f.id = "delay";
  f.title = "Transfer delay estimate";
  f.script = GnuplotCommon() + "set ylabel 'delay [ms]'\nset xlabel 'time [s]'\n";
  f.script += TransferEstimatePanel(methods, 6, 7, "d", [](const TransferMethod& m) { return 1e3 * m.delay_true_s; }, &f);
  f.caption = "Estimated delay of the master's records (estimates.csv delay_s, in ms) against time with its ±3σ band; "
              "dashed black: the true delay (summary.json delay_true_s) when known. The y range spans the estimates "
              "and the true values. Thinned uniformly.";
  return f;
}

void TransferAttitudeFigure(const std::vector<TransferMethod>& methods, FigureSet* out) {
  if (std::none_of(methods.begin(), methods.end(), [](const TransferMethod& m) { return m.has_attitude; })) {
    out->left_out.push_back("Slave attitude errors: no attitude_errors.csv in any folder (run without a truth)");
    return;
  }
  Figure f;
  f.id = "slave_attitude_errors";
  f.title = "Slave attitude errors";
  f.height_px = 820;
  f.script = GnuplotCommon() + "set multiplot layout 3,1\nset lmargin 12\n";
  static const char* const kAxes[3] = {"roll", "pitch", "heading"};
  for (std::size_t k = 0; k < 3; ++k) {
    std::vector<BandedSeries> list;
    for (const TransferMethod& m : methods) {
      if (m.has_attitude) list.push_back({m.label, m.color, m.attitude[k].t, m.attitude[k].y[0], {}});
    }
    f.script += "set ylabel " + GnuplotQuote(std::string(kAxes[k]) + " error [mrad]") + "\n";
    f.script += k == 2 ? "set xlabel 'time [s]'\n" : "unset xlabel\n";
    f.script += k == 0 ? "" : "set key off\n";
    f.script += BandedErrorPlot(list, "a" + std::to_string(k) + "_", &f);
  }
  f.script += "unset multiplot\n";
  f.caption = "Attitude error of the aligned slave (estimate − truth, ZYX Euler differences, attitude_errors.csv) of "
              "each method at every epoch, in mrad. The y range is clipped to 1.15 × the 99th percentile of |error|; "
              "thinned keeping each bucket's minimum and maximum.";
  out->figures.push_back(std::move(f));
}

/// Several folders that differ in the true delay (a sweep): per method the slave attitude
/// RMS against the true delay, heading on top, roll and pitch below. Needs three folders
/// and two distinct known delays.
void TransferSweepFigure(const std::vector<AlignmentFolder>& folders, const std::vector<TransferMethod>& methods,
                         FigureSet* out) {
  std::vector<double> delays;
  for (const TransferMethod& m : methods) {
    if (std::isfinite(m.delay_true_s) && std::find(delays.begin(), delays.end(), m.delay_true_s) == delays.end()) {
      delays.push_back(m.delay_true_s);
    }
  }
  if (folders.size() < 3 || delays.size() < 2) return;
  std::vector<std::string> names;
  for (const TransferMethod& m : methods) {
    if (std::find(names.begin(), names.end(), m.method) == names.end()) names.push_back(m.method);
  }
  Figure f;
  f.id = "attitude_rms_vs_delay";
  f.title = "Slave attitude RMS against the true delay";
  f.height_px = 760;
  const auto [lo, hi] = std::minmax_element(delays.begin(), delays.end());
  const double pad_ms = 50.0 * (*hi - *lo);  // 5 % of the span, in ms
  f.script = GnuplotCommon() + "set multiplot layout 2,1\nset lmargin 12\nset rmargin 24\nset logscale y\n" +
             "set key outside right top\nset xrange [" + GnuplotNumber("%.9g", 1e3 * *lo - pad_ms) + ":" +
             GnuplotNumber("%.9g", 1e3 * *hi + pad_ms) + "]\n";
  std::string top, bottom;
  for (std::size_t k = 0; k < names.size(); ++k) {
    std::vector<std::array<double, 4>> rows;  // delay ms, roll, pitch, heading RMS (mrad)
    for (const TransferMethod& m : methods) {
      if (m.method != names[k] || !std::isfinite(m.delay_true_s)) continue;
      rows.push_back({1e3 * m.delay_true_s, TransferNumber(m, "roll_rms_mrad"), TransferNumber(m, "pitch_rms_mrad"),
                      TransferNumber(m, "heading_rms_mrad")});
    }
    std::sort(rows.begin(), rows.end());
    std::vector<std::vector<double>> columns(4);
    for (const auto& r : rows) {
      columns[0].push_back(r[0]);
      for (std::size_t c = 1; c < 4; ++c) columns[c].push_back(r[c] > 0.0 ? r[c] : std::nan(""));  // log scale
    }
    const std::string name = "s" + std::to_string(k), color = SeriesColor(k);
    AppendDatablock(&f.script, name, columns);
    top += (top.empty() ? "" : ", ") + std::string("$") + name + " u 1:4 w lp pt 7 lw 1.4 lc rgb '" + color +
           "' title " + GnuplotQuote(names[k]);
    bottom += (bottom.empty() ? "" : ", ") + std::string("$") + name + " u 1:2 w lp pt 7 lw 1.4 lc rgb '" + color +
              "' title " + GnuplotQuote(names[k] + " roll") + ", $" + name + " u 1:3 w lp pt 5 dt 2 lw 1.4 lc rgb '" +
              color + "' title " + GnuplotQuote(names[k] + " pitch");
    f.series += 3;
  }
  f.script += "set ylabel 'heading RMS [mrad]'\nunset xlabel\nplot " + top + "\n";
  f.script += "set ylabel 'roll, pitch RMS [mrad]'\nset xlabel 'true delay [ms]'\nplot " + bottom + "\nunset multiplot\n";
  f.caption = "Each method's slave attitude RMS after the settling time (summary.json roll/pitch/heading_rms_mrad) in "
              "every folder, against the folder's true delay (delay_true_s), log scale: how the methods degrade "
              "with the delay.";
  out->figures.push_back(std::move(f));
}

}  // namespace

PageParts TransferPage(const std::vector<AlignmentFolder>& folders, std::size_t max_points) {
  PageParts page;
  std::vector<std::string> notes;
  const std::vector<TransferMethod> methods = LoadTransferMethods(folders, max_points, &notes);
  page.text = AlignmentPageText(
      folders, "transfer alignment",
      "Transfer alignment of a slave IMU to a master INS: the methods of each run folder compared with each other "
      "and with the truth; made by <code>navtwin report</code> from the folders' summary.json and CSV files "
      "(<code>navtwin transfer-align --out</code>).",
      TransferAttitudeTable(methods) + TransferEstimatesTable(methods));
  page.text.notes = notes;
  page.figures.figures.push_back(TransferMisalignmentFigure(methods));
  page.figures.figures.push_back(TransferDelayFigure(methods));
  TransferAttitudeFigure(methods, &page.figures);
  TransferSweepFigure(folders, methods, &page.figures);
  return page;
}

}  // namespace navtwin::report
