// The report page of calibrate-imu and calibrate-mag run folders (alignment_pages.h).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>

#include "core/io/input_error.h"
#include "core/units.h"
#include "problems/report/alignment_pages.h"
#include "problems/report/csv_table.h"
#include "problems/report/decimate.h"
#include "problems/report/gnuplot.h"
#include "problems/report/run_folder.h"

namespace navtwin::report {
namespace {

std::string RequiredFile(const AlignmentFolder& f, const std::string& name, const std::string& what) {
  const std::string path = f.dir + "/" + name;
  if (!std::filesystem::is_regular_file(path)) throw InputError(path, 0, "", "missing: " + what);
  return path;
}

std::string SummaryText(const AlignmentFolder& f, const std::string& key) {
  const YAML::Node n = JsonChild(f.summary, key);
  return n && n.IsScalar() ? n.Scalar() : "";
}

/// The items of a summary.json array of strings, as an HTML list (empty without items).
std::string SummaryList(const AlignmentFolder& f, const std::string& key, const std::string& heading) {
  const YAML::Node n = JsonChild(f.summary, key);
  if (!n || !n.IsSequence() || n.size() == 0) return "";
  std::string s = "<p>" + HtmlEscape(heading) + "</p>\n<ul>\n";
  for (const YAML::Node& item : n) s += "<li>" + HtmlEscape(item.IsScalar() ? item.Scalar() : "?") + "</li>\n";
  return s + "</ul>\n";
}

/// A folder's label in a column head or a series title.
std::string Who(const std::vector<AlignmentFolder>& folders, const AlignmentFolder& f) {
  return folders.size() > 1 ? f.label : std::string();
}

// ------------------------------------------------------------------------- IMU

struct ImuFolder {
  const AlignmentFolder* folder = nullptr;
  std::vector<std::string> names, units;
  std::vector<double> values, sigmas;
  std::vector<double> accel_before_mg, accel_after_mg, gyro_before_deg_h, gyro_after_deg_h;  ///< norms
  bool rms = false;
};

double Norm3(const CsvTable& csv, std::size_t first, std::size_t row) {
  double s = 0.0;
  for (std::size_t k = 0; k < 3; ++k) s += csv.number(first + k)[row] * csv.number(first + k)[row];
  return std::sqrt(s);
}

ImuFolder LoadImuFolder(const AlignmentFolder& f) {
  ImuFolder out;
  out.folder = &f;
  const CsvTable p(RequiredFile(f, "parameters.csv", "a calibrate-imu folder has its parameters in parameters.csv"),
                   {{"name", true}, {"value"}, {"sigma"}, {"unit", true}});
  out.names = p.text(0);
  out.values = p.number(1);
  out.sigmas = p.number(2);
  out.units = p.text(3);
  std::vector<CsvColumn> columns = {{"rms"}};
  for (const char* sensor : {"accel", "gyro"}) {
    for (const char* when : {"before", "after"}) {
      for (const char* axis : {"x", "y", "z"}) {
        columns.push_back({std::string(sensor) + "_" + when + "_" + axis + (sensor[0] == 'a' ? "_mg" : "_deg_h")});
      }
    }
  }
  const CsvTable r(RequiredFile(f, "residuals.csv", "a calibrate-imu folder has its residuals in residuals.csv"),
                   columns);
  for (std::size_t i = 0; i < r.rows(); ++i) {
    out.rms = out.rms || r.number(0)[i] != 0.0;
    out.accel_before_mg.push_back(Norm3(r, 1, i));
    out.accel_after_mg.push_back(Norm3(r, 4, i));
    out.gyro_before_deg_h.push_back(Norm3(r, 7, i));
    out.gyro_after_deg_h.push_back(Norm3(r, 10, i));
  }
  return out;
}

/// Parameters in rows, one value ± σ column per folder (the union of the folders' names).
std::string ImuParameterTable(const std::vector<AlignmentFolder>& folders, const std::vector<ImuFolder>& imu) {
  std::vector<std::string> names, units;
  for (const ImuFolder& m : imu) {
    for (std::size_t i = 0; i < m.names.size(); ++i) {
      if (std::find(names.begin(), names.end(), m.names[i]) != names.end()) continue;
      names.push_back(m.names[i]);
      units.push_back(m.units[i]);
    }
  }
  std::vector<std::string> head = {"parameter", "unit"};
  for (const ImuFolder& m : imu) {
    const std::string who = Who(folders, *m.folder);
    head.push_back(who.empty() ? "value" : who + " value");
    head.push_back("σ");
  }
  std::string s = "<h3>Parameters (σ: 1σ; – not estimated)</h3>\n<table>" + HtmlHead(head, 2);
  for (std::size_t k = 0; k < names.size(); ++k) {
    s += "<tr>" + HtmlNameCell(names[k]) + HtmlNameCell(units[k]);
    for (const ImuFolder& m : imu) {
      const auto it = std::find(m.names.begin(), m.names.end(), names[k]);
      const std::size_t i = static_cast<std::size_t>(it - m.names.begin());
      const bool has = it != m.names.end();
      s += HtmlCell(has ? m.values[i] : NAN, "%.6g") + HtmlCell(has ? m.sigmas[i] : NAN, "%.3g");
    }
    s += "</tr>\n";
  }
  return s + "</table>\n";
}

std::string ImuSummaryTable(const std::vector<ImuFolder>& imu) {
  std::string s = "<h3>Fit</h3>\n<table>" +
                  HtmlHead({"folder", "rig", "positions / runs", "accel residual RMS [mg]", "gyro residual RMS [deg/h]"});
  for (const ImuFolder& m : imu) {
    const AlignmentFolder& f = *m.folder;
    s += "<tr>" + HtmlNameCell(f.label) + HtmlNameCell(SummaryText(f, "rig")) +
         HtmlCell(JsonNumber(JsonChild(f.summary, "positions"), f.summary_path, "positions"), "%.0f") +
         HtmlCell(JsonNumber(JsonChild(f.summary, "accel_residual_rms_mps2"), f.summary_path,
                             "accel_residual_rms_mps2") / kMilliG_mps2) +
         HtmlCell(JsonNumber(JsonChild(f.summary, "gyro_residual_rms_rad_per_s"), f.summary_path,
                             "gyro_residual_rms_rad_per_s") / kDegPerHour_radps) +
         "</tr>\n";
  }
  s += "</table>\n";
  for (const ImuFolder& m : imu) {
    s += SummaryList(*m.folder, "unobservable", m.folder->label + ": not observable (held at 0)");
    s += SummaryList(*m.folder, "notes", m.folder->label + ": notes");
  }
  return s;
}

/// |residual| per position (or run) before and after, log scale: the calibration's gain.
Figure ImuResidualFigure(const std::vector<AlignmentFolder>& folders, const std::vector<ImuFolder>& imu, bool gyro) {
  Figure f;
  f.id = gyro ? "gyro_residuals" : "accel_residuals";
  const char* unit = gyro ? "deg/h" : "mg";
  f.title = std::string(gyro ? "Gyro" : "Accelerometer") + " residuals before and after calibration";
  f.script = GnuplotCommon() + "set logscale y\nset offsets 0.5, 0.5, 0, 0\nset xlabel 'static position (pendulum: run)'\nset ylabel '|residual| [" +
             unit + "]'\n";
  std::string plots;
  for (std::size_t k = 0; k < imu.size(); ++k) {
    const ImuFolder& m = imu[k];
    std::vector<double> index;
    for (std::size_t i = 0; i < m.accel_before_mg.size(); ++i) index.push_back(static_cast<double>(i + 1));
    const std::vector<double>& before = gyro ? m.gyro_before_deg_h : m.accel_before_mg;
    const std::vector<double>& after = gyro ? m.gyro_after_deg_h : m.accel_after_mg;
    const std::string name = std::string(gyro ? "g" : "a") + std::to_string(k);
    AppendDatablock(&f.script, name, {index, before, after});
    const std::string who = Who(folders, *m.folder);
    const std::string color = SeriesColor(k);
    plots += (plots.empty() ? "" : ", ") + std::string("$") + name + " u 1:($2 > 0 ? $2 : NaN) w p pt 6 ps 1.2 lc rgb '" +
             color + "' title " + GnuplotQuote((who.empty() ? "" : who + " ") + "before") + ", $" + name +
             " u 1:($3 > 0 ? $3 : NaN) w lp pt 7 ps 0.9 lw 1.2 lc rgb '" + color + "' title " +
             GnuplotQuote((who.empty() ? "" : who + " ") + "after");
    f.series += 2;
  }
  f.script += "plot " + plots + "\n";
  f.caption = std::string("Norm of the ") + (gyro ? "gyro" : "accelerometer") +
              " residual (measured mean minus the error model applied to the truth) at each static position, "
              "without calibration (open) and with the estimate (filled), " + unit +
              ", log scale (residuals.csv); for the pendulum the RMS over each run's samples.";
  return f;
}

/// convergence.csv of a recursive calibration, when the folder has one: x (positions or
/// samples) and per requested column its values (and σ, NaN where the file has none).
struct Convergence {
  const AlignmentFolder* folder = nullptr;
  std::vector<double> x;
  std::vector<std::vector<double>> value, sigma;
};

/// The columns: (name, unit) pairs, read as "<name>_<unit>" and "<name>_sigma_<unit>".
std::optional<Convergence> LoadConvergence(const AlignmentFolder& f, const std::string& x_column,
                                           const std::vector<std::pair<std::string, std::string>>& columns,
                                           bool with_sigma) {
  const std::string path = f.dir + "/convergence.csv";
  if (!std::filesystem::is_regular_file(path)) return std::nullopt;
  std::vector<CsvColumn> request = {{x_column}};
  for (const auto& [name, unit] : columns) {
    request.push_back({name + "_" + unit});
    if (with_sigma) request.push_back({name + "_sigma_" + unit});
  }
  const CsvTable csv(path, request);
  Convergence out{&f, csv.number(0), {}, {}};
  const std::size_t stride = with_sigma ? 2 : 1;
  for (std::size_t k = 0; k < columns.size(); ++k) {
    out.value.push_back(csv.number(1 + stride * k));
    out.sigma.push_back(with_sigma ? csv.number(2 + stride * k) : std::vector<double>(csv.rows(), NAN));
  }
  return out;
}

bool AnyFinite(const std::vector<double>& v) {
  return std::any_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

/// Panels of convergence: panel p draws columns [3p, 3p + 3) (x, y, z) of every folder's
/// convergence, with ±3σ bands where σ is known. A series without a finite value is left
/// out, a panel without any (a block never estimated) too, with its name in `left_out`.
Figure ConvergenceFigure(const std::vector<AlignmentFolder>& folders, const std::vector<Convergence>& data,
                         const std::vector<std::string>& panel_labels, const std::string& x_label, Figure f,
                         std::vector<std::string>* left_out) {
  static const char* const kAxis[3] = {"x", "y", "z"};
  std::vector<std::string> panels;
  for (std::size_t p = 0; p < panel_labels.size(); ++p) {
    std::string plots;
    for (std::size_t d = 0; d < data.size(); ++d) {
      for (std::size_t a = 0; a < 3; ++a) {
        const std::size_t c = 3 * p + a;
        if (!AnyFinite(data[d].value[c])) continue;
        const std::string name = "c" + std::to_string(p) + "_" + std::to_string(d) + "_" + std::to_string(a);
        AppendDatablock(&f.script, name, {data[d].x, data[d].value[c], data[d].sigma[c]});
        const std::string who = Who(folders, *data[d].folder);
        const std::string color = SeriesColor(3 * d + a);
        if (AnyFinite(data[d].sigma[c])) {
          plots += (plots.empty() ? "" : ", ") + std::string("$") + name +
                   " u 1:($2-3*$3):($2+3*$3) w filledcurves fc rgb '" + color +
                   "' fs transparent solid 0.15 noborder notitle";
          ++f.series;
        }
        plots += (plots.empty() ? "" : ", ") + std::string("$") + name + " u 1:2 w lp pt 7 ps 0.6 lw 1.3 lc rgb '" +
                 color + "' title " + GnuplotQuote((who.empty() ? "" : who + " ") + kAxis[a]);
        ++f.series;
      }
    }
    if (plots.empty()) {
      left_out->push_back(f.title + ": " + panel_labels[p] + " not estimated in any folder");
      continue;
    }
    panels.push_back("set ylabel " + GnuplotQuote(panel_labels[p]) + "\nplot " + plots + "\n");
  }
  f.height_px = 260 * static_cast<int>(std::max<std::size_t>(panels.size(), 1)) + 60;
  f.script += GnuplotCommon() + "set multiplot layout " + std::to_string(panels.size()) + ",1\nset lmargin 12\n" +
              "set xlabel " + GnuplotQuote(x_label) + "\n";
  for (const std::string& panel : panels) f.script += panel;
  f.script += "unset multiplot\n";
  return f;
}

void ImuConvergenceFigure(const std::vector<AlignmentFolder>& folders, FigureSet* out) {
  std::vector<std::pair<std::string, std::string>> columns;
  const std::pair<const char*, const char*> blocks[4] = {
      {"accel.bias.", "mg"}, {"gyro.bias.", "deg_h"}, {"accel.scale_factor.", "ppm"}, {"gyro.scale_factor.", "ppm"}};
  for (const auto& [block, unit] : blocks) {
    for (const char* axis : {"x", "y", "z"}) columns.emplace_back(block + std::string(axis), unit);
  }
  std::vector<Convergence> data;
  for (const AlignmentFolder& f : folders) {
    if (std::optional<Convergence> c = LoadConvergence(f, "positions", columns, true)) data.push_back(std::move(*c));
  }
  if (data.empty()) return;  // no recursive run among the folders
  Figure f;
  f.id = "recursive_convergence";
  f.title = "Recursive estimate after each position";
  f.caption = "The recursive multi-position calibration (calibrate-imu --method recursive, convergence.csv): the "
              "biases and scale factors after each static position with their ±3σ bands; a parameter appears once "
              "the positions so far observe it (until then it is held at 0 and the others' σ are conditional on that).";
  Figure drawn = ConvergenceFigure(
      folders, data, {"accel bias [mg]", "gyro bias [deg/h]", "accel scale factor [ppm]", "gyro scale factor [ppm]"},
      "static positions", std::move(f), &out->left_out);
  if (drawn.series > 0) out->figures.push_back(std::move(drawn));
}

// ------------------------------------------------------------------------- magnetometer

struct MagFolder {
  const AlignmentFolder* folder = nullptr;
  std::vector<double> t, before, after;
};

MagFolder LoadMagFolder(const AlignmentFolder& f) {
  const CsvTable r(RequiredFile(f, "residuals.csv", "a calibrate-mag folder has every sample's field in residuals.csv"),
                   {{"t_s"}, {"field_before_uT"}, {"field_after_uT"}});
  return {&f, r.number(0), r.number(1), r.number(2)};
}

/// One row per folder: `columns` (summary.json key, heading) after the folder and method.
std::string MagRows(const std::vector<MagFolder>& mag, const std::vector<std::pair<std::string, std::string>>& columns,
                    bool with_hard_iron) {
  std::vector<std::string> head = {"folder", "method"};
  for (const auto& c : columns) head.push_back(c.second);
  if (with_hard_iron) head.push_back("hard iron x, y, z (σ) [uT]");
  std::string s = "<table>" + HtmlHead(head, 2);
  for (const MagFolder& m : mag) {
    const AlignmentFolder& f = *m.folder;
    s += "<tr>" + HtmlNameCell(f.label) + HtmlNameCell(SummaryText(f, "method"));
    for (const auto& c : columns) s += HtmlCell(JsonNumber(JsonChild(f.summary, c.first), f.summary_path, c.first));
    if (with_hard_iron) {
      std::string iron;
      const YAML::Node h = JsonChild(f.summary, "hard_iron_uT");
      const YAML::Node hs = JsonChild(f.summary, "hard_iron_sigma_uT");
      for (std::size_t i = 0; h && h.IsSequence() && i < h.size(); ++i) {
        iron += (i ? ", " : "") + HtmlNumber("%.3f", JsonNumber(h[i], f.summary_path, "hard_iron_uT"));
        if (hs && hs.IsSequence() && i < hs.size()) {
          iron += " (" + HtmlNumber("%.3f", JsonNumber(hs[i], f.summary_path, "hard_iron_sigma_uT")) + ")";
        }
      }
      s += HtmlNameCell(iron);
    }
    s += "</tr>\n";
  }
  return s + "</table>\n";
}

std::string MagTables(const std::vector<MagFolder>& mag) {
  return "<h3>Fit</h3>\n" +
         MagRows(mag,
                 {{"samples", "samples"},
                  {"field_uT", "field [uT]"},
                  {"residual_rms_uT", "residual RMS [uT]"},
                  {"field_spread_before_uT", "|m| spread before [uT]"},
                  {"field_spread_after_uT", "after [uT]"}},
                 false) +
         "<h3>Heading error (with a reference attitude) and hard iron</h3>\n" +
         MagRows(mag,
                 {{"heading_samples", "samples"},
                  {"heading_error_before_deg", "RMS before [deg]"},
                  {"heading_error_after_deg", "after [deg]"}},
                 true);
}

Figure MagFieldFigure(const std::vector<AlignmentFolder>& folders, const std::vector<MagFolder>& mag,
                      std::size_t max_points) {
  Figure f;
  f.id = "mag_field";
  f.title = "Field magnitude before and after calibration";
  f.script = GnuplotCommon() + "set xlabel 'time [s]'\nset ylabel 'field magnitude [uT]'\n";
  std::string plots;
  for (std::size_t k = 0; k < mag.size(); ++k) {
    const MagFolder& m = mag[k];
    const std::string who = Who(folders, *m.folder);
    const std::string color = SeriesColor(k);
    for (int after = 0; after < 2; ++after) {
      const std::vector<double>& y = after ? m.after : m.before;
      const std::vector<std::size_t> pick = MinMaxIndices(y, max_points);
      const std::string name = "m" + std::to_string(k) + (after ? "a" : "b");
      AppendDatablock(&f.script, name, {Pick(m.t, pick), Pick(y, pick)});
      plots += (plots.empty() ? "" : ", ") + std::string("$") + name + " u 1:2 w l lw " + (after ? "1.4" : "0.8") +
               (after ? "" : " dt 2") + " lc rgb '" + color + "' title " +
               GnuplotQuote((who.empty() ? "" : who + " ") + (after ? "after" : "before"));
      ++f.series;
    }
  }
  f.script += "plot " + plots + "\n";
  f.caption = "|m| of every sample raw (dashed) and |A (m − h)| calibrated (solid), uT (residuals.csv; the planar "
              "and 2-axis methods: the part in the calibrated plane). A good calibration makes the calibrated "
              "magnitude flat at the field.";
  return f;
}

}  // namespace

PageParts CalibrationPage(const std::vector<AlignmentFolder>& folders, std::size_t max_points) {
  PageParts page;
  const bool imu = SummaryText(folders.front(), "command") == "calibrate-imu";
  if (imu) {
    std::vector<ImuFolder> data;
    for (const AlignmentFolder& f : folders) data.push_back(LoadImuFolder(f));
    page.text = AlignmentPageText(
        folders, "IMU calibration",
        "IMU error-model calibration: the parameters with their σ and the residuals at every static position "
        "before and after calibration; made by <code>navtwin report</code> from the folders' summary.json, "
        "parameters.csv and residuals.csv (<code>navtwin calibrate-imu --run_dir</code>).",
        ImuSummaryTable(data) + ImuParameterTable(folders, data));
    if (std::any_of(data.begin(), data.end(), [](const ImuFolder& m) { return !m.accel_before_mg.empty(); })) {
      page.figures.figures.push_back(ImuResidualFigure(folders, data, false));
      page.figures.figures.push_back(ImuResidualFigure(folders, data, true));
    } else {
      page.figures.left_out.push_back(
          "Residuals before and after calibration: no static position with a known attitude in any folder (the "
          "handheld method knows none; its gravity residuals are in the notes)");
    }
    ImuConvergenceFigure(folders, &page.figures);
    return page;
  }
  std::vector<MagFolder> data;
  for (const AlignmentFolder& f : folders) data.push_back(LoadMagFolder(f));
  page.text = AlignmentPageText(
      folders, "magnetometer calibration",
      "Magnetometer hard- and soft-iron calibration: the fit and the field magnitude of every sample before and "
      "after; made by <code>navtwin report</code> from the folders' summary.json and residuals.csv "
      "(<code>navtwin calibrate-mag --run_dir</code>).",
      MagTables(data));
  page.figures.figures.push_back(MagFieldFigure(folders, data, max_points));
  std::vector<Convergence> convergence;
  for (const AlignmentFolder& f : folders) {
    if (std::optional<Convergence> c = LoadConvergence(
            f, "samples", {{"hard_iron_x", "uT"}, {"hard_iron_y", "uT"}, {"hard_iron_z", "uT"}}, false)) {
      convergence.push_back(std::move(*c));
    }
  }
  if (!convergence.empty()) {
    Figure f;
    f.id = "recursive_convergence";
    f.title = "Recursive hard-iron estimate";
    f.caption = "The recursive ellipsoid fit (calibrate-mag --method recursive, convergence.csv): the hard iron after "
                "every 1/20 of the samples (no σ: the recursive fit gives none; gaps where it could not yet estimate).";
    Figure drawn =
        ConvergenceFigure(folders, convergence, {"hard iron [uT]"}, "samples", std::move(f), &page.figures.left_out);
    if (drawn.series > 0) page.figures.figures.push_back(std::move(drawn));
  }
  return page;
}

}  // namespace navtwin::report
