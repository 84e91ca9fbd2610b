#include "solvers/mc_output.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <sstream>

#include "core/io/atomic_file.h"
#include "core/io/folder.h"
#include "core/io/json_writer.h"

namespace navtwin::mc {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Ratio(double a, double b) { return (std::isfinite(a) && std::isfinite(b) && b > 0.0) ? a / b : kNaN; }

/// Mean ANEES over the axis points that have one, and the share of them inside the bounds.
void AneesOverAxis(const QuantityStatistics& q, double* mean, double* inside) {
  double sum = 0.0;
  int n = 0, in = 0;
  for (const PointStatistics& p : q.points) {
    if (!std::isfinite(p.anees)) continue;
    sum += p.anees;
    ++n;
    if (p.anees >= p.anees_lo && p.anees <= p.anees_hi) ++in;
  }
  *mean = n > 0 ? sum / n : kNaN;
  *inside = n > 0 ? static_cast<double>(in) / n : kNaN;
}

void ComponentArray(JsonWriter& w, const std::string& key, const std::vector<double>& si, double scale) {
  w.Key(key).BeginArray();
  for (const double x : si) w.Value(x * scale);
  w.EndArray();
}

void QuantityJson(JsonWriter& w, const QuantityStatistics& q) {
  const Quantity& l = q.layout;
  const PointStatistics& f = q.points.back();
  w.Key(l.name).BeginObject();
  w.Field("unit", l.unit).Field("axis", l.axis_name);
  w.Key("components").BeginArray();
  for (const std::string& c : l.components) w.Value(c);
  w.EndArray();
  w.Key("final").BeginObject();
  w.Field("at", l.axis.back()).Field("runs", f.runs);
  ComponentArray(w, "rms", f.rms, l.scale);
  ComponentArray(w, "sigma_mean", f.sigma_mean, l.scale);
  std::vector<double> ratio, over_bound;
  for (int i = 0; i < l.dim(); ++i) {
    ratio.push_back(Ratio(f.rms[i], f.sigma_mean[i]));
    over_bound.push_back(Ratio(f.rms[i], f.bound_sigma[i]));
  }
  ComponentArray(w, "rms_over_sigma", ratio, 1.0);
  ComponentArray(w, "bound", f.bound_sigma, l.scale);
  ComponentArray(w, "rms_over_bound", over_bound, 1.0);
  ComponentArray(w, "within_3sigma", f.within_3sigma, 1.0);
  w.Field("anees", f.anees).Field("nees_runs", f.nees_runs);
  w.Key("anees_95").BeginArray().Value(f.anees_lo).Value(f.anees_hi).EndArray();
  w.EndObject();
  double mean = kNaN, inside = kNaN;
  AneesOverAxis(q, &mean, &inside);
  w.Field("anees_mean_over_axis", mean).Field("anees_share_inside_95", inside);
  w.EndObject();
}

std::string Fixed(double x, int width = 10) {
  char buf[48];
  if (!std::isfinite(x)) {
    std::snprintf(buf, sizeof buf, "%*s", width, "-");
  } else {
    std::snprintf(buf, sizeof buf, "%*.4g", width, x);
  }
  return buf;
}

std::string QuantityCsv(const QuantityStatistics& q) {
  std::ostringstream out;
  out.precision(10);
  const Quantity& l = q.layout;
  out << l.axis_name << ",runs";
  for (const std::string& c : l.components) {
    out << ",rms_" << c << "_" << l.unit << ",sigma_" << c << "_" << l.unit << ",ratio_" << c << ",bound_" << c
        << "_" << l.unit;
  }
  out << ",anees,anees_lo,anees_hi\n";
  for (int p = 0; p < l.points(); ++p) {
    const PointStatistics& s = q.points[p];
    out << l.axis[p] << "," << s.runs;
    for (int i = 0; i < l.dim(); ++i) {
      out << "," << s.rms[i] * l.scale << "," << s.sigma_mean[i] * l.scale << "," << Ratio(s.rms[i], s.sigma_mean[i])
          << "," << s.bound_sigma[i] * l.scale;
    }
    out << "," << s.anees << "," << s.anees_lo << "," << s.anees_hi << "\n";
  }
  return out.str();
}

std::string BoundCsv(const Quantity& q) {
  std::ostringstream out;
  out.precision(10);
  out << q.axis_name;
  for (const std::string& c : q.components) out << ",sigma_" << c << "_" << q.unit;
  out << "\n";
  const int d = q.dim();
  for (int p = 0; p < q.points(); ++p) {
    out << q.axis[p];
    for (int i = 0; i < d; ++i) out << "," << q.Sigma(p, i) * q.scale;
    out << "\n";
  }
  return out.str();
}

std::string FinalsCsv(const ExperimentInfo& info, const std::vector<MethodStatistics>& stats) {
  std::ostringstream out;
  out.precision(10);
  out << "run,seed,method,quantity,component,unit,error,sigma\n";
  for (int run = 0; run < info.runs; ++run) {
    for (const MethodStatistics& m : stats) {
      for (const QuantityStatistics& q : m.quantities) {
        const Quantity& l = q.layout;
        for (int i = 0; i < l.dim(); ++i) {
          const std::size_t k = static_cast<std::size_t>(run) * l.dim() + i;
          if (k >= q.final_error.size()) continue;
          const std::uint64_t seed = static_cast<std::size_t>(run) < info.run_seeds.size() ? info.run_seeds[run] : info.seed + run;
          out << run << "," << seed << "," << m.method << "," << l.name << "," << l.components[i] << ","
              << l.unit << "," << q.final_error[k] * l.scale << "," << q.final_sigma[k] * l.scale << "\n";
        }
      }
    }
  }
  return out.str();
}

void HistogramRows(std::ostringstream& out, const std::string& prefix, const Histogram& h) {
  const int bins = static_cast<int>(h.counts.size());
  const double width = (h.hi - h.lo) / bins;
  out << prefix << h.kind << ",-inf," << h.lo << "," << h.below << "\n";
  for (int b = 0; b < bins; ++b) {
    out << prefix << h.kind << "," << h.lo + b * width << "," << h.lo + (b + 1) * width << "," << h.counts[b] << "\n";
  }
  out << prefix << h.kind << "," << h.hi << ",inf," << h.above << "\n";
}

std::string HistogramsCsv(const std::vector<MethodStatistics>& stats) {
  std::ostringstream out;
  out.precision(10);
  out << "method,quantity,component,unit,kind,bin_lo,bin_hi,count\n";
  for (const MethodStatistics& m : stats) {
    for (const QuantityStatistics& q : m.quantities) {
      const Quantity& l = q.layout;
      const int d = l.dim();
      for (int i = 0; i < d; ++i) {
        std::vector<double> error, normalised;
        for (std::size_t k = i; k < q.final_error.size(); k += d) {
          error.push_back(q.final_error[k] * l.scale);
          normalised.push_back(Ratio(q.final_error[k], q.final_sigma[k]));
        }
        const std::string prefix = m.method + "," + l.name + "," + l.components[i] + "," + l.unit + ",";
        Histogram h = ErrorHistogram(error, 4.0 * q.points.back().rms[i] * l.scale);
        h.kind = "error";
        HistogramRows(out, prefix, h);
        Histogram n = ErrorHistogram(normalised, 5.0);
        n.kind = "normalised";
        HistogramRows(out, prefix, n);
      }
    }
  }
  return out.str();
}

}  // namespace

Histogram ErrorHistogram(const std::vector<double>& values, double half_width) {
  Histogram h;
  constexpr int kBins = 20;
  h.counts.assign(kBins, 0);
  h.lo = -half_width;
  h.hi = half_width;
  if (!(half_width > 0.0) || !std::isfinite(half_width)) return h;
  for (const double v : values) {
    if (!std::isfinite(v)) continue;
    if (v < h.lo) {
      ++h.below;
    } else if (v >= h.hi) {
      ++h.above;
    } else {
      ++h.counts[std::min(kBins - 1, static_cast<int>((v - h.lo) / (h.hi - h.lo) * kBins))];
    }
  }
  return h;
}

std::string SummaryJson(const ExperimentInfo& info, const std::vector<MethodStatistics>& stats,
                        const MethodRecord* bound) {
  std::ostringstream out;
  JsonWriter w(out);
  w.BeginObject();
  w.Field("command", "mc").Field("problem", info.problem).Field("scenario", info.scenario);
  w.Field("seed", static_cast<long long>(info.seed)).Field("runs", info.runs).Field("seeding", info.seeding);
  w.Key("notes").BeginArray();
  for (const std::string& n : info.notes) w.Value(n);
  w.EndArray();
  if (bound != nullptr) {
    w.Key("bound").BeginObject();
    for (const Quantity& q : bound->quantities) {
      const int d = q.dim();
      std::vector<double> sigma;
      for (int i = 0; i < d; ++i) sigma.push_back(q.Sigma(q.points() - 1, i));
      ComponentArray(w, q.name, sigma, q.scale);
    }
    w.EndObject();
  }
  w.Key("methods").BeginObject();
  for (const MethodStatistics& m : stats) {
    w.Key(m.method).BeginObject();
    w.Field("runs", m.runs).Field("failures", m.failures).Field("first_failure", m.first_failure);
    w.Key("quantities").BeginObject();
    for (const QuantityStatistics& q : m.quantities) QuantityJson(w, q);
    w.EndObject();
    w.EndObject();
  }
  w.EndObject();
  w.EndObject();
  out << "\n";
  return out.str();
}

std::string SummaryTable(const ExperimentInfo& info, const std::vector<MethodStatistics>& stats,
                         const MethodRecord* bound) {
  std::ostringstream out;
  out << info.problem << " Monte Carlo: " << info.runs << " runs of " << info.scenario << ", " << info.seeding << "\n";
  for (const std::string& n : info.notes) out << "  note: " << n << "\n";
  out << "final values (RMS over runs, mean reported sigma, their ratio, the Cramer-Rao bound):\n";
  out << "method         quantity           comp              rms      sigma  rms/sigma      bound  rms/bound  in 3sigma\n";
  for (const MethodStatistics& m : stats) {
    for (const QuantityStatistics& q : m.quantities) {
      const Quantity& l = q.layout;
      const PointStatistics& f = q.points.back();
      for (int i = 0; i < l.dim(); ++i) {
        char head[96];
        std::snprintf(head, sizeof head, "%-14s %-18s %-10s", m.method.c_str(), l.name.c_str(),
                      (l.components[i] + (l.unit.empty() ? "" : " " + l.unit)).c_str());
        out << head << Fixed(f.rms[i] * l.scale, 11) << Fixed(f.sigma_mean[i] * l.scale, 11)
            << Fixed(Ratio(f.rms[i], f.sigma_mean[i]), 11) << Fixed(f.bound_sigma[i] * l.scale, 11)
            << Fixed(Ratio(f.rms[i], f.bound_sigma[i]), 11) << Fixed(f.within_3sigma[i], 11) << "\n";
      }
      double mean = kNaN, inside = kNaN;
      AneesOverAxis(q, &mean, &inside);
      char line[240];
      if (f.nees_runs == 0) {
        std::snprintf(line, sizeof line, "%-14s %-18s no sigma reported: no ANEES\n", m.method.c_str(), l.name.c_str());
      } else {
        std::snprintf(line, sizeof line,
                      "%-14s %-18s ANEES final %.3g in [%.3g, %.3g] (%d runs)%s; over the axis mean %.3g, %.0f %% "
                      "of points inside\n",
                      m.method.c_str(), l.name.c_str(), f.anees, f.anees_lo, f.anees_hi, f.nees_runs,
                      f.anees < f.anees_lo || f.anees > f.anees_hi ? " OUTSIDE" : "", mean, 100.0 * inside);
      }
      out << line;
    }
    if (m.failures > 0) out << m.method << ": failed on " << m.failures << " runs; first: " << m.first_failure << "\n";
  }
  if (bound == nullptr) out << "(no bound for this problem)\n";
  return out.str();
}

std::string BoundTable(const MethodRecord& bound, bool json) {
  std::ostringstream out;
  JsonWriter w(out);
  if (json) w.BeginObject().Key("bound").BeginObject();
  for (const Quantity& q : bound.quantities) {
    const int d = q.dim(), n = q.points();
    std::vector<int> shown;
    for (int k = 0; k < 6 && n > 0; ++k) {
      const int p = n <= 6 ? k : static_cast<int>(std::lround(k * (n - 1) / 5.0));
      if (p < n && (shown.empty() || shown.back() != p)) shown.push_back(p);
    }
    if (json) {
      w.Key(q.name).BeginObject().Field("unit", q.unit).Field("axis", q.axis_name);
      w.Key("components").BeginArray();
      for (const std::string& c : q.components) w.Value(c);
      w.EndArray().Key("points").BeginArray();
    } else {
      out << q.name << " (" << q.unit << "), sigma at " << q.axis_name << ":\n";
    }
    for (const int p : shown) {
      std::vector<double> sigma;
      for (int i = 0; i < d; ++i) sigma.push_back(q.Sigma(p, i) * q.scale);
      if (json) {
        w.BeginObject().Field("at", q.axis[p]);
        ComponentArray(w, "sigma", sigma, 1.0);
        w.EndObject();
        continue;
      }
      out << "  " << Fixed(q.axis[p], 9);
      for (int i = 0; i < d; ++i) out << "  " << q.components[i] << " " << Fixed(sigma[i], 10);
      out << "\n";
    }
    if (json) w.EndArray().EndObject();
  }
  if (json) w.EndObject().EndObject();
  out << (json ? "\n" : "");
  return out.str();
}

void WriteExperimentFolder(const std::string& dir, const ExperimentInfo& info,
                           const std::vector<MethodStatistics>& stats, const MethodRecord* bound) {
  std::vector<std::pair<std::string, std::string>> files;
  files.emplace_back(dir + "/summary.json", SummaryJson(info, stats, bound));
  files.emplace_back(dir + "/finals.csv", FinalsCsv(info, stats));
  files.emplace_back(dir + "/histograms.csv", HistogramsCsv(stats));
  for (const MethodStatistics& m : stats) {
    for (const QuantityStatistics& q : m.quantities) {
      files.emplace_back(dir + "/" + m.method + "/" + q.layout.name + ".csv", QuantityCsv(q));
    }
  }
  if (bound != nullptr) {
    for (const Quantity& q : bound->quantities) files.emplace_back(dir + "/bound/" + q.name + ".csv", BoundCsv(q));
  }
  EnsureFolder(dir);
  std::vector<std::unique_ptr<AtomicFile>> written;
  try {
    for (const auto& [path, text] : files) {
      EnsureFolder(path.substr(0, path.rfind('/')));
      written.push_back(std::make_unique<AtomicFile>(path));
      written.back()->stream() << text;
      written.back()->Commit();
    }
  } catch (...) {
    for (auto& f : written) f->Revoke();
    throw;
  }
}

}  // namespace navtwin::mc
