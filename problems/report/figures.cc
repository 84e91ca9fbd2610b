#include "problems/report/figures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "core/earth.h"
#include "core/units.h"

namespace navtwin::report {
namespace {

/// One plotted method of one folder with its colour.
struct Entry {
  const RunData* run;
  const MethodData* m;
  std::string color;
};

std::vector<Entry> Entries(const std::vector<RunData>& runs) {
  static const std::map<std::string, int> kMethodColor = {
      {"filter", 0}, {"rts", 1}, {"batch", 2}, {"filter_adapted", 3}, {"rts_adapted", 4}};
  std::vector<Entry> out;
  for (const RunData& run : runs) {
    for (const MethodData& m : run.methods) {
      const auto it = kMethodColor.find(m.method);
      const std::size_t k = runs.size() == 1 && it != kMethodColor.end() ? static_cast<std::size_t>(it->second)
                                                                          : out.size();
      out.push_back({&run, &m, SeriesColor(k)});
    }
  }
  return out;
}

/// The time origin of the figures: the first folder's start.
double TimeOrigin(const std::vector<RunData>& runs) {
  const double t0 = runs.front().t_start_s;
  return std::isfinite(t0) ? t0 : 0.0;
}

std::string TimeLabel(double t0) {
  return t0 == 0.0 ? "time [s]" : "time since " + GnuplotNumber("%.3f", t0) + " s [s]";
}

std::vector<double> Shifted(const std::vector<double>& t, double t0) {
  std::vector<double> out(t);
  for (double& x : out) x -= t0;
  return out;
}

/// Grey rectangles behind every panel over the folders' outages.
std::string OutageShading(const std::vector<RunData>& runs, double t0) {
  std::string s;
  int k = 1;
  for (const RunData& run : runs) {
    for (const Outage& o : run.outages) {
      s += "set object " + std::to_string(k++) + " rect from " + GnuplotNumber("%.9g", o.start_s - t0) + ", graph 0 to " +
           GnuplotNumber("%.9g", o.end_s - t0) + ", graph 1 fc rgb '#e4e4e4' fs solid 1.0 noborder behind\n";
    }
  }
  return s;
}

std::string OutageNote(const std::vector<RunData>& runs) {
  for (const RunData& r : runs) {
    if (!r.outages.empty()) return " Grey spans: injected GNSS outages.";
  }
  return "";
}

/// Percentile q of the finite |values|.
double AbsPercentile(std::vector<double> v, double q) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return std::nan("");
  for (double& x : v) x = std::abs(x);
  const std::size_t k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

bool AnyTrack(const std::vector<RunData>& runs) {
  for (const RunData& r : runs) {
    if (r.has_gnss && !r.gnss.t.empty()) return true;
    for (const MethodData& m : r.methods) {
      if (!m.track.t.empty()) return true;
    }
  }
  return false;
}

wgs84::Geodetic TrackOrigin(const std::vector<RunData>& runs) {
  for (const RunData& r : runs) {
    if (r.has_gnss && !r.gnss.t.empty()) return {r.gnss.y[0][0] * kDegToRad, r.gnss.y[1][0] * kDegToRad, 0.0};
  }
  for (const RunData& r : runs) {
    for (const MethodData& m : r.methods) {
      if (!m.track.t.empty()) return {m.track.y[0][0] * kDegToRad, m.track.y[1][0] * kDegToRad, 0.0};
    }
  }
  return {};
}

/// East and north (m) of lat/lon points (deg) from the origin, for rows where keep(i).
template <typename Keep>
std::vector<std::vector<double>> EastNorth(const std::vector<double>& lat_deg, const std::vector<double>& lon_deg,
                                           const wgs84::Geodetic& origin, Keep keep) {
  std::vector<std::vector<double>> out(2);
  for (std::size_t i = 0; i < lat_deg.size(); ++i) {
    if (!keep(i)) continue;
    const Eigen::Vector3d ned = wgs84::GeodeticToNed({lat_deg[i] * kDegToRad, lon_deg[i] * kDegToRad, 0.0}, origin);
    out[0].push_back(ned.y());
    out[1].push_back(ned.x());
  }
  return out;
}

Figure TrackFigure(const std::vector<RunData>& runs, const std::vector<Entry>& entries) {
  Figure f;
  f.id = "track";
  f.title = "Horizontal track";
  f.width_px = 1000;
  f.height_px = 760;
  const wgs84::Geodetic origin = TrackOrigin(runs);
  std::string plots;
  int block = 0;
  for (const RunData& r : runs) {
    if (!r.has_gnss || r.gnss.t.empty()) continue;
    const std::string prefix = runs.size() > 1 ? r.label + ": " : "";
    for (int removed = 0; removed < 2; ++removed) {
      const auto cols = EastNorth(r.gnss.y[0], r.gnss.y[1], origin,
                                  [&](std::size_t i) { return (r.gnss.y[2][i] == 1.0) == (removed == 1); });
      if (cols[0].empty()) continue;
      const std::string name = "g" + std::to_string(block++);
      AppendDatablock(&f.script, name, cols);
      plots += (plots.empty() ? "" : ", ") + std::string("$") + name +
               (removed ? " u 1:2 w p pt 2 ps 0.7 lc rgb '#d62728' title " + GnuplotQuote(prefix + "GNSS fixes removed by outages")
                        : " u 1:2 w p pt 7 ps 0.35 lc rgb '#9a9a9a' title " + GnuplotQuote(prefix + "GNSS fixes used"));
      ++f.series;
    }
  }
  for (const Entry& e : entries) {
    if (e.m->track.t.empty()) continue;
    const std::string name = "t" + std::to_string(block++);
    AppendDatablock(&f.script, name, EastNorth(e.m->track.y[0], e.m->track.y[1], origin, [](std::size_t) { return true; }));
    plots += ", $" + name + " u 1:2 w l lw 1.5 lc rgb '" + e.color + "' title " + GnuplotQuote(e.m->label);
    ++f.series;
  }
  if (plots.rfind(", ", 0) == 0) plots = plots.substr(2);
  f.script += GnuplotCommon() + "set size ratio -1\nset xlabel 'east [m]'\nset ylabel 'north [m]'\n"
              "set key outside right top\nplot " + plots + "\n";
  bool fixes = false;
  for (const RunData& r : runs) fixes = fixes || (r.has_gnss && !r.gnss.t.empty());
  f.caption = "East and north of each method's navigation solution (nav.csv) and of the GNSS fixes (gnss.csv), in "
              "metres from the first " + std::string(fixes ? "GNSS fix" : "navigation epoch (no gnss.csv)") + " (" + GnuplotNumber("%.7f", origin.lat_rad * kRadToDeg) + "°, " +
              GnuplotNumber("%.7f", origin.lon_rad * kRadToDeg) + "°). Red crosses: fixes removed by the injected outages "
              "(the outage spans). Points thinned uniformly to at most a few thousand per series.";
  return f;
}

struct ComponentGroup {
  const char* id;
  const char* title;
  const char* unit;
  const char* what;
  int first;
  const char* names[3];
};

constexpr ComponentGroup kGroups[3] = {
    {"pos_errors", "Position errors", "m", "position", 0, {"north", "east", "down"}},
    {"vel_errors", "Velocity errors", "m/s", "velocity", 3, {"north", "east", "down"}},
    {"att_errors", "Attitude errors", "deg", "attitude", 6, {"roll", "pitch", "yaw"}}};

/// One panel of an error figure: per method the ±3σ band and the error.
std::string ErrorPanel(const std::vector<Entry>& entries, int c, double t0, Figure* f) {
  std::vector<BandedSeries> list;
  for (const Entry& e : entries) {
    const MethodData& m = *e.m;
    if (!m.has_errors || !m.compared[c]) continue;
    list.push_back({m.label, e.color, Shifted(m.errors[c].t, t0), m.errors[c].y[0], m.errors[c].y[1]});
  }
  return BandedErrorPlot(list, "e" + std::to_string(c) + "_", f);
}

bool ComponentPlotted(const std::vector<Entry>& entries, int c) {
  for (const Entry& e : entries) {
    if (e.m->has_errors && e.m->compared[c]) return true;
  }
  return false;
}

void ErrorFigures(const std::vector<RunData>& runs, const std::vector<Entry>& entries, FigureSet* out) {
  const double t0 = TimeOrigin(runs);
  bool any_errors = false;
  for (const Entry& e : entries) any_errors = any_errors || e.m->has_errors;
  for (const ComponentGroup& g : kGroups) {
    if (!any_errors) {
      out->left_out.push_back(std::string(g.title) + ": no errors.csv in any folder (run without --truth)");
      continue;
    }
    if (!ComponentPlotted(entries, g.first)) {
      out->left_out.push_back(std::string(g.title) + ": the reference has no " + g.what);
      continue;
    }
    Figure f;
    f.id = g.id;
    f.title = g.title;
    f.height_px = 820;
    f.script = GnuplotCommon() + OutageShading(runs, t0) + "set multiplot layout 3,1\nset lmargin 12\n";
    for (int k = 0; k < 3; ++k) {
      f.script += "set ylabel " + GnuplotQuote(std::string(g.names[k]) + " error [" + g.unit + "]") + "\n";
      f.script += k == 2 ? "set xlabel " + GnuplotQuote(TimeLabel(t0)) + "\n" : "unset xlabel\n";
      f.script += k == 0 ? "" : "set key off\n";
      f.script += ErrorPanel(entries, g.first + k, t0, &f);
    }
    f.script += "unset multiplot\n";
    f.caption = std::string(g.what) + " error (estimate minus reference, errors.csv) of each method, with its ±3σ "
                "band shaded in the same colour (σ of the solution, combined with the reference's σ when the "
                "reference has one). The y range is clipped to 1.15 × the 99th percentile of max(|error|, 3σ); "
                "series thinned keeping each bucket's minimum and maximum." + OutageNote(runs);
    out->figures.push_back(std::move(f));
  }
}

Figure SigmaFigure(const std::vector<RunData>& runs, const std::vector<Entry>& entries) {
  const double t0 = TimeOrigin(runs);
  Figure f;
  f.id = "sigma";
  f.title = "Standard deviations";
  f.height_px = 820;
  f.script = GnuplotCommon() + OutageShading(runs, t0) + "set multiplot layout 3,1\nset lmargin 12\nset logscale y\n";
  static const char* const kLabels[3] = {"position σ [m]", "velocity σ [m/s]", "attitude σ [deg]"};
  for (int g = 0; g < 3; ++g) {
    f.script += "set ylabel " + GnuplotQuote(kLabels[g]) + "\n";
    f.script += g == 2 ? "set xlabel " + GnuplotQuote(TimeLabel(t0)) + "\n" : "unset xlabel\n";
    if (g > 0) f.script += "set key off\n";
    std::string plots;
    for (std::size_t i = 0; i < entries.size(); ++i) {
      const Series& s = entries[i].m->sigma;
      if (s.t.empty()) continue;
      const std::string name = "s" + std::to_string(g) + "_" + std::to_string(i);
      AppendDatablock(&f.script, name, {Shifted(s.t, t0), s.y[2 * g], s.y[2 * g + 1]});
      plots += (plots.empty() ? "" : ", ") + std::string("$") + name + " u 1:2 w l lw 1.3 lc rgb '" + entries[i].color +
               "' title " + GnuplotQuote(entries[i].m->label) + ", $" + name + " u 1:3 w l lw 1.3 dt 2 lc rgb '" +
               entries[i].color + "' notitle";
      f.series += 2;
    }
    f.script += "plot " + plots + "\n";
  }
  f.script += "unset multiplot\n";
  f.caption = "σ of each method's solution (std.csv), log scale. Solid: horizontal (position, velocity: "
              "sqrt(σN² + σE²)) and tilt (sqrt(σ² of φN, φE)); dashed: down and heading (φD). Thinned keeping each "
              "bucket's extremes of the horizontal σ." + OutageNote(runs);
  return f;
}

struct SensorEntry {
  const Entry* entry;
  const NisSeries* nis;
};

std::string BoundsText(const BoundsCount& c) {
  if (c.values == 0) return "no values";
  const double outside = 100.0 * static_cast<double>(c.below + c.above) / static_cast<double>(c.values);
  return GnuplotNumber("%.1f %% outside", outside) + " (" + std::to_string(c.below) + " below, " + std::to_string(c.above) +
         " above, of " + std::to_string(c.values) + ")";
}

Figure NisFigure(const std::string& sensor, const std::vector<SensorEntry>& list, double t0,
                 const std::vector<RunData>& runs) {
  Figure f;
  f.id = "nis_" + sensor;
  f.title = "Residuals: " + sensor;
  f.script = GnuplotCommon() + OutageShading(runs, t0) + "set logscale y\nset ylabel 'NIS / whitened χ² per update'\n" +
             "set xlabel " + GnuplotQuote(TimeLabel(t0)) + "\n";
  std::string plots, counts;
  std::vector<int> dofs;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const NisSeries& n = *list[i].nis;
    const std::string name = "n" + std::to_string(i);
    AppendDatablock(&f.script, name, {Shifted(n.accepted.t, t0), n.accepted.y[0]});
    plots += (plots.empty() ? "" : ", ") + std::string("$") + name + " u 1:2 w p pt 7 ps 0.3 lc rgb '" +
             list[i].entry->color + "' title " + GnuplotQuote(list[i].entry->m->label);
    ++f.series;
    if (!n.rejected.t.empty()) {
      AppendDatablock(&f.script, name + "r", {Shifted(n.rejected.t, t0), n.rejected.y[0]});
      plots += ", $" + name + "r u 1:2 w p pt 2 ps 0.8 lc rgb '" + list[i].entry->color + "' title " +
               GnuplotQuote(list[i].entry->m->label + " rejected");
      ++f.series;
    }
    for (int d : n.dofs) {
      if (std::find(dofs.begin(), dofs.end(), d) == dofs.end()) dofs.push_back(d);
    }
    counts += (counts.empty() ? "" : "; ") + list[i].entry->m->label + ": " + BoundsText(n.counts) +
              (n.rejected_count > 0 ? ", " + std::to_string(n.rejected_count) + " rejected by the gate" : "");
  }
  std::sort(dofs.begin(), dofs.end());
  const std::size_t shown = std::min<std::size_t>(dofs.size(), 4);
  static const int kDash[4] = {2, 4, 5, 3};
  for (std::size_t k = 0; k < shown; ++k) {
    const std::array<double, 2> b = ChiSquareBounds95(dofs[k]);
    const std::string style = " w l lw 1.5 dt " + std::to_string(kDash[k]) + " lc rgb '#000000' ";
    plots += ", " + GnuplotNumber("%.6g", b[0]) + style + "title " +
             GnuplotQuote("χ²(" + std::to_string(dofs[k]) + ") 95 % bounds") + ", " + GnuplotNumber("%.6g", b[1]) + style +
             "notitle";
    f.series += 2;
  }
  f.script += "plot " + plots + "\n";
  f.caption = "χ² of each " + sensor + " update (residuals.csv: the filter's NIS, the batch's whitened residuals), "
              "log scale, with the two-sided 95 % bounds of χ² for the update's dof (5 % of the updates outside "
              "when the noise is right). " + counts + "." +
              (dofs.size() > shown ? " Bounds drawn for the " + std::to_string(shown) + " smallest dof only." : "") +
              " Thinned keeping each bucket's extremes; the counts are over every update." + OutageNote(runs);
  return f;
}

void NisFigures(const std::vector<RunData>& runs, const std::vector<Entry>& entries, FigureSet* out) {
  std::vector<std::string> sensors;
  std::map<std::string, std::vector<SensorEntry>> by_sensor;
  for (const Entry& e : entries) {
    for (const NisSeries& n : e.m->nis) {
      if (by_sensor.find(n.sensor) == by_sensor.end()) sensors.push_back(n.sensor);
      by_sensor[n.sensor].push_back({&e, &n});
    }
  }
  if (sensors.empty()) {
    out->left_out.push_back("Residuals / NIS: no residuals.csv in any method folder");
    return;
  }
  for (const std::string& s : sensors) out->figures.push_back(NisFigure(s, by_sensor[s], TimeOrigin(runs), runs));
}

void NeesFigure(const std::vector<RunData>& runs, const std::vector<Entry>& entries, FigureSet* out) {
  const double t0 = TimeOrigin(runs);
  Figure f;
  f.id = "nees";
  f.title = "Position NEES";
  f.script = GnuplotCommon() + OutageShading(runs, t0) + "set logscale y\nset ylabel 'position NEES'\nset xlabel " +
             GnuplotQuote(TimeLabel(t0)) + "\n";
  std::string plots, counts;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const MethodData& m = *entries[i].m;
    if (!m.has_errors) continue;
    const std::string name = "v" + std::to_string(i);
    AppendDatablock(&f.script, name, {Shifted(m.nees.t, t0), m.nees.y[0]});
    plots += (plots.empty() ? "" : ", ") + std::string("$") + name + " u 1:2 w l lw 1.1 lc rgb '" + entries[i].color +
             "' title " + GnuplotQuote(m.label);
    counts += (counts.empty() ? "" : "; ") + m.label + ": " + BoundsText(m.nees_counts);
    ++f.series;
  }
  if (plots.empty()) {
    out->left_out.push_back("Position NEES: no errors.csv in any folder (run without --truth)");
    return;
  }
  const std::array<double, 2> b = ChiSquareBounds95(3);
  plots += ", " + GnuplotNumber("%.6g", b[0]) + " w l lw 1.5 dt 2 lc rgb '#000000' title 'χ²(3) 95 % bounds', " +
           GnuplotNumber("%.6g", b[1]) + " w l lw 1.5 dt 2 lc rgb '#000000' notitle";
  f.series += 2;
  f.script += "plot " + plots + "\n";
  f.caption = "Position NEES at every compared epoch: Σ (error/σ)² over north, east, down with diagonal σ (combined "
              "with the reference's σ when it has one), log scale, against the two-sided 95 % bounds of χ²(3) (" +
              GnuplotNumber("%.3f", b[0]) + ", " + GnuplotNumber("%.3f", b[1]) + "). " + counts +
              ". Thinned keeping each bucket's extremes; the counts are over every epoch." + OutageNote(runs);
  out->figures.push_back(std::move(f));
}

void DriftFigure(const std::vector<RunData>& runs, const std::vector<Entry>& entries, FigureSet* out) {
  const double t0 = TimeOrigin(runs);
  std::vector<Outage> spans;
  for (const RunData& r : runs) {
    for (const Outage& o : r.outages) {
      const bool known = std::any_of(spans.begin(), spans.end(), [&](const Outage& s) {
        return std::abs(s.start_s - o.start_s) < 1e-6 && std::abs(s.end_s - o.end_s) < 1e-6;
      });
      if (!known) spans.push_back(o);
    }
  }
  std::vector<const Entry*> plotted;
  for (const Entry& e : entries) {
    if (e.m->has_errors && !e.run->outages.empty()) plotted.push_back(&e);
  }
  if (spans.empty() || plotted.empty()) {
    out->left_out.push_back(spans.empty() ? "Drift per outage: no injected outages (--outage_start_s, --outage_len_s)"
                                          : "Drift per outage: no errors.csv (run without --truth)");
    return;
  }
  Figure f;
  f.id = "drift";
  f.title = "Drift per outage";
  f.script = GnuplotCommon() + "set style data histogram\nset style histogram clustered gap 1\n"
             "set style fill solid 0.85 noborder\nset boxwidth 0.9\nset yrange [0:*]\n"
             "set ylabel 'max horizontal error in the outage [m]'\nset xlabel " +
             GnuplotQuote("outage: start – end [s]" + (t0 == 0.0 ? "" : " since " + GnuplotNumber("%.3f", t0) + " s")) + "\nset xtics rotate by -30\n";
  f.script += "$d << EOD\n";
  for (const Outage& o : spans) {
    f.script += "\"" + GnuplotNumber("%.1f", o.start_s - t0) + "–" + GnuplotNumber("%.1f", o.end_s - t0) + "\"";
    for (const Entry* e : plotted) {
      double v = std::nan("");
      for (std::size_t k = 0; k < e->run->outages.size(); ++k) {
        if (std::abs(e->run->outages[k].start_s - o.start_s) < 1e-6) v = e->m->outage_max_horizontal_m[k];
      }
      f.script += std::isfinite(v) ? " " + GnuplotNumber("%.9g", v) : " NaN";
    }
    f.script += "\n";
  }
  f.script += "EOD\nplot ";
  for (std::size_t i = 0; i < plotted.size(); ++i) {
    f.script += (i ? ", " : "") + std::string("$d u ") + std::to_string(i + 2) + (i == 0 ? ":xtic(1)" : "") +
                " lc rgb '" + plotted[i]->color + "' title " + GnuplotQuote(plotted[i]->m->label);
    ++f.series;
  }
  f.script += "\n";
  f.caption = "Largest horizontal error of each method inside each injected GNSS outage (errors.csv rows with "
              "in_outage = 1 inside the outage's span from summary.json), over every epoch, unthinned.";
  out->figures.push_back(std::move(f));
}

}  // namespace

std::string BandedErrorPlot(const std::vector<BandedSeries>& list, const std::string& prefix, Figure* f) {
  std::string plots;
  double limit = 0.0;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const BandedSeries& b = list[i];
    const bool band = !b.sigma.empty();
    const std::string name = prefix + std::to_string(i);
    AppendDatablock(&f->script, name, band ? std::vector<std::vector<double>>{b.x, b.y, b.sigma}
                                           : std::vector<std::vector<double>>{b.x, b.y});
    std::vector<double> envelope(b.y.size());
    for (std::size_t k = 0; k < envelope.size(); ++k) {
      envelope[k] = band ? std::max(std::abs(b.y[k]), 3.0 * b.sigma[k]) : b.y[k];
    }
    const double p = AbsPercentile(envelope, 0.99);
    if (std::isfinite(p)) limit = std::max(limit, p);
    if (band) {
      plots += (plots.empty() ? "" : ", ") + std::string("$") + name + " u 1:(-3*$3):(3*$3) w filledcurves fc rgb '" +
               b.color + "' fs transparent solid 0.12 noborder notitle";
      ++f->series;
    }
    plots += (plots.empty() ? "" : ", ") + std::string("$") + name + " u 1:2 w l lw 1.2 lc rgb '" + b.color +
             "' title " + GnuplotQuote(b.label);
    ++f->series;
  }
  std::string s = limit > 0.0 ? "set yrange [" + GnuplotNumber("%.6g", -1.15 * limit) + ":" +
                                    GnuplotNumber("%.6g", 1.15 * limit) + "]\n"
                              : "set autoscale y\n";
  return s + "plot " + plots + "\n";
}

FigureSet BuildFigures(const std::vector<RunData>& runs) {
  FigureSet out;
  if (runs.empty()) return out;
  const std::vector<Entry> entries = Entries(runs);
  if (AnyTrack(runs)) {
    out.figures.push_back(TrackFigure(runs, entries));
  } else {
    out.left_out.push_back("Horizontal track: no nav.csv and no gnss.csv in any folder");
  }
  ErrorFigures(runs, entries, &out);
  bool any_sigma = false;
  for (const Entry& e : entries) any_sigma = any_sigma || !e.m->sigma.t.empty();
  if (any_sigma) {
    out.figures.push_back(SigmaFigure(runs, entries));
  } else {
    out.left_out.push_back("Standard deviations: no std.csv for any method");
  }
  NeesFigure(runs, entries, &out);
  DriftFigure(runs, entries, &out);
  NisFigures(runs, entries, &out);
  return out;
}

}  // namespace navtwin::report
