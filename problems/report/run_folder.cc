#include "problems/report/run_folder.h"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <exception>
#include <fstream>
#include <map>
#include <set>
#include <thread>

#include "core/config/yaml_config.h"
#include "core/io/input_error.h"
#include "problems/report/csv_table.h"
#include "problems/report/decimate.h"
#include "solvers/eskf.h"

namespace navtwin::report {
namespace {

bool IsFile(const std::string& path) {
  std::ifstream in(path);
  return static_cast<bool>(in);
}

long MarkLine(const YAML::Node& node) { return node.Mark().line >= 0 ? node.Mark().line + 1 : 0; }

}  // namespace

YAML::Node ReadSummaryJson(const std::string& dir, const std::string& path) {
  if (!IsFile(path)) {
    throw InputError(path, 0, "", "no summary.json in " + dir +
                                      " (not the run folder of navtwin navigate, smooth, transfer-align, "
                                      "inflight-align, level-mc, calibrate-imu or calibrate-mag)");
  }
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw InputError(path, e.mark.line >= 0 ? e.mark.line + 1 : 0, "", "malformed JSON: " + e.msg);
  }
  RequireUniqueKeys(root, path);
  if (!root.IsMap()) throw InputError(path, 1, "", "expected a JSON object");
  const YAML::Node command = root["command"];
  const bool calibration =
      command && command.IsScalar() && (command.Scalar() == "calibrate-imu" || command.Scalar() == "calibrate-mag");
  if (!calibration && (!root["methods"] || !root["methods"].IsMap() || root["methods"].size() == 0)) {
    throw InputError(path, MarkLine(root), "methods", "missing or empty object 'methods'");
  }
  return root;
}

namespace {

std::vector<Outage> ReadOutages(const YAML::Node& summary, const std::string& path) {
  std::vector<Outage> out;
  const YAML::Node list = JsonChild(summary, "outages");
  if (list.IsNull()) return out;
  if (!list.IsSequence()) throw InputError(path, MarkLine(list), "outages", "expected an array of [start, end]");
  for (const YAML::Node& pair : list) {
    if (!pair.IsSequence() || pair.size() != 2) {
      throw InputError(path, MarkLine(pair), "outages", "expected [start, end]");
    }
    out.push_back({JsonNumber(pair[0], path, "outages"), JsonNumber(pair[1], path, "outages")});
  }
  return out;
}

/// nav.csv: the track, thinned uniformly.
Series LoadTrack(const std::string& path, std::size_t max_points) {
  const CsvTable csv(path, {{"t_s"}, {"lat_deg"}, {"lon_deg"}});
  const std::vector<std::size_t> keep = UniformIndices(csv.rows(), max_points);
  return {Pick(csv.number(0), keep), {Pick(csv.number(1), keep), Pick(csv.number(2), keep)}};
}

double Hypot2(double a, double b) { return std::sqrt(a * a + b * b); }

/// std.csv: horizontal and down sigmas of position and velocity, tilt and heading sigmas.
Series LoadSigma(const std::string& path, std::size_t max_points) {
  const CsvTable csv(path, {{"t_s"},
                            {"pos_n_std_m"},
                            {"pos_e_std_m"},
                            {"pos_d_std_m"},
                            {"vel_n_std_mps"},
                            {"vel_e_std_mps"},
                            {"vel_d_std_mps"},
                            {"att_n_std_deg"},
                            {"att_e_std_deg"},
                            {"att_d_std_deg"}});
  std::vector<std::vector<double>> full(6, std::vector<double>(csv.rows()));
  for (std::size_t r = 0; r < csv.rows(); ++r) {
    for (int g = 0; g < 3; ++g) {
      full[2 * g][r] = Hypot2(csv.number(1 + 3 * g)[r], csv.number(2 + 3 * g)[r]);
      full[2 * g + 1][r] = csv.number(3 + 3 * g)[r];
    }
  }
  const std::vector<std::size_t> keep = MinMaxIndices(full[0], max_points);
  Series s{Pick(csv.number(0), keep), {}};
  for (const auto& column : full) s.y.push_back(Pick(column, keep));
  return s;
}

void CountBounds(double value, const std::array<double, 2>& b, BoundsCount* c) {
  if (!std::isfinite(value)) return;
  ++c->values;
  if (value < b[0]) ++c->below;
  if (value > b[1]) ++c->above;
}

std::vector<CsvColumn> ErrorsColumns() {
  static const char* const kNames[] = {
      "t_s",           "pos_n_err_m",   "pos_e_err_m",   "pos_d_err_m",   "vel_n_err_mps", "vel_e_err_mps",
      "vel_d_err_mps", "roll_err_deg",  "pitch_err_deg", "yaw_err_deg",   "pos_n_std_m",   "pos_e_std_m",
      "pos_d_std_m",   "vel_n_std_mps", "vel_e_std_mps", "vel_d_std_mps", "roll_std_deg",  "pitch_std_deg",
      "yaw_std_deg",   "in_outage"};
  static const char* const kReference[] = {"ref_pos_n_std_m",   "ref_pos_e_std_m",   "ref_pos_d_std_m",
                                           "ref_vel_n_std_mps", "ref_vel_e_std_mps", "ref_vel_d_std_mps"};
  std::vector<CsvColumn> columns;
  for (const char* name : kNames) columns.push_back({name});
  for (const char* name : kReference) columns.push_back({name, false, false});
  return columns;
}

/// The sigma the errors are judged by: the solution's, combined with the reference's when
/// the file has it (a GNSS reference), as the run's scoring does.
double CombinedSigma(const CsvTable& csv, int component, std::size_t row) {
  const double own = csv.number(10 + static_cast<std::size_t>(component))[row];
  if (component >= 6 || !csv.has(20 + static_cast<std::size_t>(component))) return own;
  const double ref = csv.number(20 + static_cast<std::size_t>(component))[row];
  return std::isfinite(ref) ? Hypot2(own, ref) : own;
}

/// errors.csv: per component the error and its sigma, the position NEES, the drift per outage.
void LoadErrors(const std::string& path, const std::vector<Outage>& outages, std::size_t max_points,
                MethodData* m) {
  const CsvTable csv(path, ErrorsColumns());
  const std::size_t n = csv.rows();
  const std::vector<double>& t = csv.number(0);
  std::vector<double> sigma(n), nees(n);
  for (int c = 0; c < kComponents; ++c) {
    const std::vector<double>& err = csv.number(1 + static_cast<std::size_t>(c));
    for (std::size_t r = 0; r < n; ++r) sigma[r] = CombinedSigma(csv, c, r);
    m->compared[c] = std::any_of(err.begin(), err.end(), [](double x) { return std::isfinite(x); });
    const std::vector<std::size_t> keep = MinMaxIndices(err, max_points);
    m->errors[c] = {Pick(t, keep), {Pick(err, keep), Pick(sigma, keep)}};
  }
  const std::array<double, 2> bounds3 = ChiSquareBounds95(3);
  for (std::size_t r = 0; r < n; ++r) {
    double sum = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double s = CombinedSigma(csv, c, r);
      const double e = csv.number(1 + static_cast<std::size_t>(c))[r];
      sum += s > 0.0 ? e * e / (s * s) : std::nan("");
    }
    nees[r] = sum;
    CountBounds(sum, bounds3, &m->nees_counts);
  }
  const std::vector<std::size_t> keep = MinMaxIndices(nees, max_points);
  m->nees = {Pick(t, keep), {Pick(nees, keep)}};
  m->outage_max_horizontal_m.assign(outages.size(), std::nan(""));
  const std::vector<double>& in_outage = csv.number(19);
  for (std::size_t r = 0; r < n; ++r) {
    if (in_outage[r] != 1.0) continue;
    for (std::size_t k = 0; k < outages.size(); ++k) {
      if (t[r] < outages[k].start_s || t[r] > outages[k].end_s) continue;
      const double h = Hypot2(csv.number(1)[r], csv.number(2)[r]);
      double& max = m->outage_max_horizontal_m[k];
      if (std::isnan(max) || h > max) max = h;
    }
  }
  m->has_errors = true;
}

/// residuals.csv: per sensor the chi2 of each update against its dof's bounds.
std::vector<NisSeries> LoadResiduals(const std::string& path, std::size_t max_points) {
  const CsvTable csv(path, {{"t_s"}, {"sensor", true}, {"dof"}, {"chi2"}, {"rejected"}});
  std::map<std::string, std::vector<std::size_t>> rows;
  std::vector<std::string> order;
  for (std::size_t r = 0; r < csv.rows(); ++r) {
    const std::string& sensor = csv.text(1)[r];
    if (rows.find(sensor) == rows.end()) order.push_back(sensor);
    rows[sensor].push_back(r);
  }
  std::vector<NisSeries> out;
  std::map<int, std::array<double, 2>> bounds;  // per dof, computed once
  for (const std::string& sensor : order) {
    NisSeries s;
    s.sensor = sensor;
    std::vector<double> t, chi2, dof, rt, rchi2;
    std::set<int> dofs;
    for (std::size_t r : rows[sensor]) {
      const int d = static_cast<int>(std::lround(csv.number(2)[r]));
      if (csv.number(4)[r] != 0.0) {
        rt.push_back(csv.number(0)[r]);
        rchi2.push_back(csv.number(3)[r]);
        continue;
      }
      t.push_back(csv.number(0)[r]);
      chi2.push_back(csv.number(3)[r]);
      dof.push_back(d);
      if (d < 1) continue;
      dofs.insert(d);
      if (bounds.find(d) == bounds.end()) bounds[d] = ChiSquareBounds95(d);
      CountBounds(chi2.back(), bounds[d], &s.counts);
    }
    s.rejected_count = rt.size();
    const std::vector<std::size_t> keep = MinMaxIndices(chi2, max_points);
    s.accepted = {Pick(t, keep), {Pick(chi2, keep), Pick(dof, keep)}};
    const std::vector<std::size_t> rkeep = MinMaxIndices(rchi2, max_points);
    s.rejected = {Pick(rt, rkeep), {Pick(rchi2, rkeep)}};
    s.dofs.assign(dofs.begin(), dofs.end());
    out.push_back(std::move(s));
  }
  return out;
}

/// The method's file `name`: <dir>/<method>/<name>, else the top-level one when the
/// method is the folder's output method; empty when neither exists.
std::string MethodFile(const RunData& run, const std::string& method, const std::string& name) {
  const std::string own = run.dir + "/" + method + "/" + name;
  if (IsFile(own)) return own;
  const std::string top = run.dir + "/" + name;
  if (method == run.output_method && IsFile(top)) return top;
  return "";
}

/// Reads one method's files; what is missing goes to *notes.
MethodData LoadMethod(const RunData& run, const std::string& method, const std::string& label,
                      std::size_t max_points, std::vector<std::string>* notes) {
  MethodData m;
  m.method = method;
  m.label = label;
  const std::string nav = MethodFile(run, method, "nav.csv");
  const std::string std_csv = MethodFile(run, method, "std.csv");
  const std::string errors = run.dir + "/" + method + "/errors.csv";
  const std::string residuals = run.dir + "/" + method + "/residuals.csv";
  if (!nav.empty()) m.track = LoadTrack(nav, max_points);
  else notes->push_back(label + ": no " + method + "/nav.csv: not in the track");
  if (!std_csv.empty()) m.sigma = LoadSigma(std_csv, max_points);
  else notes->push_back(label + ": no " + method + "/std.csv: not in the sigma figure");
  if (IsFile(errors)) LoadErrors(errors, run.outages, max_points, &m);
  else notes->push_back(label + ": no " + method + "/errors.csv (run without --truth?): no errors, NEES or drift");
  if (IsFile(residuals)) m.nis = LoadResiduals(residuals, max_points);
  else notes->push_back(label + ": no " + method + "/residuals.csv: no residual figure");
  return m;
}

}  // namespace

double JsonNumber(const YAML::Node& node, const std::string& path, const std::string& key) {
  if (!node || node.IsNull()) return std::nan("");
  if (!node.IsScalar()) throw InputError(path, MarkLine(node), key, "expected a number");
  const std::string& text = node.Scalar();
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size()) {
    throw InputError(path, MarkLine(node), key, "'" + text + "' is not a number");
  }
  return value;
}

YAML::Node JsonChild(const YAML::Node& node, const std::string& key) {
  if (!node || !node.IsMap()) return YAML::Node();
  const YAML::Node child = node[key];
  return child ? child : YAML::Node();
}

std::array<double, 2> ChiSquareBounds95(int dof) {
  return {ChiSquareQuantile(0.025, dof), ChiSquareQuantile(0.975, dof)};
}

RunData LoadRunFolder(const std::string& dir, const std::string& label, bool label_methods,
                      std::size_t max_points, int jobs) {
  RunData run;
  run.dir = dir;
  run.label = label;
  run.summary_path = dir + "/summary.json";
  run.summary = ReadSummaryJson(dir, run.summary_path);
  run.output_method = JsonChild(run.summary, "output_method").Scalar();
  run.outages = ReadOutages(run.summary, run.summary_path);
  run.t_start_s =
      JsonNumber(JsonChild(JsonChild(run.summary, "inputs"), "t_start_s"), run.summary_path, "inputs.t_start_s");
  const std::string gnss = dir + "/gnss.csv";
  if (IsFile(gnss)) {
    const CsvTable csv(gnss, {{"t_s"}, {"lat_deg"}, {"lon_deg"}, {"in_outage"}});
    const std::vector<std::size_t> keep = UniformIndices(csv.rows(), max_points);
    run.gnss = {Pick(csv.number(0), keep), {Pick(csv.number(1), keep), Pick(csv.number(2), keep),
                                            Pick(csv.number(3), keep)}};
    run.has_gnss = true;
  } else {
    run.notes.push_back(label + ": no gnss.csv: the track shows no GNSS fixes");
  }
  std::vector<std::string> names;
  for (const auto& kv : run.summary["methods"]) names.push_back(kv.first.as<std::string>());
  run.methods.resize(names.size());
  std::vector<std::vector<std::string>> notes(names.size());
  std::vector<std::exception_ptr> failures(names.size());
  std::atomic<std::size_t> next{0};
  const auto worker = [&] {
    for (std::size_t i = next++; i < names.size(); i = next++) {
      try {
        run.methods[i] = LoadMethod(run, names[i], label_methods ? label + "/" + names[i] : names[i], max_points,
                                    &notes[i]);
      } catch (...) {
        failures[i] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> threads;
  for (int j = 1; j < std::max(1, jobs); ++j) threads.emplace_back(worker);
  worker();
  for (std::thread& th : threads) th.join();
  for (const std::exception_ptr& e : failures) {
    if (e) std::rethrow_exception(e);
  }
  for (const auto& n : notes) run.notes.insert(run.notes.end(), n.begin(), n.end());
  return run;
}

}  // namespace navtwin::report
