// The report of a GNSS/INS run (run.h): summary.json (WriteRunSummary) and the text a
// person reads (RunTable): inputs, per method the errors, err/sigma, the estimated
// parameters (auxiliary states, IMU scale factors), residual statistics, the adapted noise
// and the warnings.
#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <string>
#include <vector>

#include "core/units.h"
#include "problems/gnss_ins/run.h"

namespace navtwin::gnss_ins {
namespace {
double VelocityRms_mps(const NavErrorStats& s) {
  return std::sqrt(s.Rms(3) * s.Rms(3) + s.Rms(4) * s.Rms(4) + s.Rms(5) * s.Rms(5));
}

void WriteStats(JsonWriter& w, const NavErrorStats& s, const ScoreReport& r) {
  static const char* const kKeys[9] = {"pos_n_m",   "pos_e_m",   "pos_d_m",   "vel_n_mps", "vel_e_mps",
                                       "vel_d_mps", "roll_deg",  "pitch_deg", "yaw_deg"};
  w.BeginObject().Field("epochs", s.count());
  for (int c = 0; c < 9; ++c) {
    if (c >= 3 && c < 6 && !r.has_velocity) continue;
    if (c >= 6 && !r.has_attitude) continue;
    const double scale = c >= 6 ? kRadToDeg : 1.0;
    w.Key(kKeys[c]).BeginObject().Field("rms", s.Rms(c) * scale).Field("max", s.Max(c) * scale).EndObject();
  }
  w.Key("horizontal_m").BeginObject().Field("rms", s.HorizontalRms_m()).Field("max", s.HorizontalMax_m()).EndObject();
  w.Key("vertical_m").BeginObject().Field("rms", s.Rms(2)).Field("max", s.Max(2)).EndObject();
  if (r.has_velocity) w.Field("velocity_rms_mps", VelocityRms_mps(s));
  w.EndObject();
}

/// Whether component c (scoring.h order) is compared against this reference.
bool Compared(const ScoreReport& r, int c) { return c < 3 || (c < 6 ? r.has_velocity : r.has_attitude); }

/// RMS(err/sigma) per compared component, the diagonal position NEES, and per component
/// the epochs left out for want of a sigma.
void WriteConsistencyStats(JsonWriter& w, const ConsistencyStats& c, const ScoreReport& r) {
  static const char* const kKeys[kScoredComponents] = {"pos_n", "pos_e", "pos_d", "vel_n", "vel_e",
                                                       "vel_d", "roll",  "pitch", "yaw"};
  w.BeginObject().Field("epochs", c.epochs());
  for (int k = 0; k < kScoredComponents; ++k) {
    if (Compared(r, k)) w.Field(kKeys[k], c.RmsRatio(k));
  }
  w.Field("pos_nees_mean", c.PosNeesMean()).Field("pos_nees_epochs", c.nees_count());
  w.Key("left_out_without_sigma").BeginObject();
  for (int k = 0; k < kScoredComponents; ++k) {
    if (Compared(r, k)) w.Field(kKeys[k], c.missing(k));
  }
  w.EndObject().EndObject();
}

void WriteConsistency(JsonWriter& w, const ScoreReport& r) {
  w.Key("consistency")
      .BeginObject()
      .Field("sigma", r.reference_has_std ? "sqrt(solution^2 + reference^2)" : "solution")
      .Field("pos_nees", "diagonal sigmas only")
      .Field("pos_nees_expected", ConsistencyStats::kPosNeesExpected);
  w.Key("all");
  WriteConsistencyStats(w, r.consistency_all, r);
  if (!r.outages.empty()) {
    w.Key("outside_outages");
    WriteConsistencyStats(w, r.consistency_outside, r);
    w.Key("inside_outages");
    WriteConsistencyStats(w, r.consistency_inside, r);
  }
  w.EndObject();
}

void WriteScore(JsonWriter& w, const ScoreReport& r) {
  w.BeginObject().Field("reference", r.has_attitude ? "navigation" : "gnss");
  w.Key("all");
  WriteStats(w, r.all, r);
  if (!r.outages.empty()) {
    w.Key("outside_outages");
    WriteStats(w, r.outside, r);
    w.Key("inside_outages");
    WriteStats(w, r.inside, r);
    w.Key("outages").BeginArray();
    for (const OutageDrift& d : r.outages) {
      w.BeginObject()
          .Field("start_s", d.start_s)
          .Field("end_s", d.end_s)
          .Field("epochs", d.epochs)
          .Field("max_horizontal_m", d.max_horizontal_m)
          .Field("max_vertical_m", d.max_vertical_m)
          .EndObject();
    }
    w.EndArray();
    w.Field("outage_horizontal_rms_m", r.outage_horizontal_rms_m);
    w.Field("outage_vertical_rms_m", r.outage_vertical_rms_m);
  }
  WriteConsistency(w, r);
  w.EndObject();
}

void WriteInputs(JsonWriter& w, const RunOptions& options, const InputSummary& in) {
  w.Key("inputs")
      .BeginObject()
      .Field("imu", in.paths.imu)
      .Field("gnss", in.paths.gnss)
      .Field("mag", in.paths.mag)
      .Field("baro", in.paths.baro)
      .Field("config", options.config_path)
      .Field("imu_samples", in.imu_samples)
      .Field("gnss_epochs", in.gnss_epochs)
      .Field("mag_samples", in.mag_samples)
      .Field("baro_samples", in.baro_samples)
      .Field("bridged_imu_gaps", in.bridged_imu_gaps)
      .Field("gnss_removed_by_outages", in.gnss_removed_by_outages)
      .Field("t_start_s", in.t_start_s)
      .Field("t_end_s", in.t_end_s)
      .EndObject();
  w.Key("outages").BeginArray();
  for (const auto& o : in.outages) w.BeginArray().Value(o.first).Value(o.second).EndArray();
  w.EndArray();
}

/// printf into a string.
void Append(std::string* s, const char* format, ...) __attribute__((format(printf, 2, 3)));
void Append(std::string* s, const char* format, ...) {
  char buf[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buf, sizeof buf, format, args);
  va_end(args);
  *s += buf;
}

void AppendErrorRow(std::string* s, const MethodRun& m, bool outages) {
  const ScoreReport& r = *m.errors;
  const NavErrorStats& e = r.all;
  const auto cell = [s](bool have, double x) {
    if (have) {
      Append(s, " %10.3f", x);
    } else {
      Append(s, " %10s", "-");
    }
  };
  Append(s, "%-14s", m.name.c_str());
  cell(true, e.HorizontalRms_m());
  cell(true, e.Rms(2));
  cell(r.has_velocity, VelocityRms_mps(e));
  cell(r.has_attitude, e.Rms(6) * kRadToDeg);
  cell(r.has_attitude, e.Rms(7) * kRadToDeg);
  cell(r.has_attitude, e.Rms(8) * kRadToDeg);
  if (outages) Append(s, " %10.3f %10.3f", r.outage_horizontal_rms_m, r.outage_vertical_rms_m);
  Append(s, " %10.2f\n", m.solution.run_time_s);
}

/// One row of the err/sigma table: the compared components' RMS ratios and the NEES.
void AppendConsistencyRow(std::string* s, const std::string& method, const char* where, const ConsistencyStats& c,
                          const ScoreReport& r) {
  Append(s, "%-14s %-8s", method.c_str(), where);
  for (int k = 0; k < kScoredComponents; ++k) {
    if (Compared(r, k)) Append(s, " %6.2f", c.RmsRatio(k));
  }
  Append(s, " %8.2f\n", c.PosNeesMean());
}

/// The err/sigma table (per method over all epochs and, with outages, inside them), and
/// a line per method whose sigma was missing at some epochs (left out of the ratios).
void AppendConsistencyTable(std::string* s, const GnssInsRun& run) {
  const ScoreReport& first = *run.methods.front().errors;
  const bool outages = !first.outages.empty();
  Append(s, "err/sigma (RMS; 1 = honest sigma; sigma = %s; NEES: position, diagonal sigmas, expected 3):\n",
         first.reference_has_std ? "sqrt(solution^2 + reference^2)" : "the solution's");
  static const char* const kHeads[kScoredComponents] = {"pos N", "pos E", "pos D", "vel N", "vel E",
                                                        "vel D", "roll",  "pitch", "yaw"};
  Append(s, "%-14s %-8s", "method", "epochs");
  for (int k = 0; k < kScoredComponents; ++k) {
    if (Compared(first, k)) Append(s, " %6s", kHeads[k]);
  }
  Append(s, " %8s\n", "NEES pos");
  for (const MethodRun& m : run.methods) {
    AppendConsistencyRow(s, m.name, "all", m.errors->consistency_all, *m.errors);
    if (outages) AppendConsistencyRow(s, m.name, "outages", m.errors->consistency_inside, *m.errors);
  }
  for (const MethodRun& m : run.methods) {
    const ConsistencyStats& c = m.errors->consistency_all;
    std::size_t missing = 0;
    for (int k = 0; k < kScoredComponents; ++k) {
      if (Compared(*m.errors, k)) missing = std::max(missing, c.missing(k));
    }
    if (missing > 0) {
      Append(s, "%s: no sigma at up to %zu of %zu compared epochs per component (left out of err/sigma)\n",
             m.name.c_str(), missing, c.epochs());
    }
  }
}

/// A parameter whose posterior std at the end of the record is at least this fraction of its
/// prior std is not observable from the record: the data hardly moved its uncertainty.
constexpr double kUnobservableSigmaRatio = 0.9;

/// A parameter estimated over the record (an auxiliary state or an IMU scale factor) at the
/// end of a solution: value, posterior std (NaN when not computed), prior std and whether
/// the record observed it (posterior std below kUnobservableSigmaRatio times the prior; a
/// parameter held at its prior or without a computed std counts as observed: nothing to
/// say). SI values; the text shows them times to_unit in `unit`.
struct ParameterEnd {
  std::string name;
  double value = std::nan("");
  double std = std::nan("");
  double prior_std = 0.0;
  bool observable = true;
  std::string observed_by;  ///< what in a record makes it observable
  double to_unit = 1.0;
  const char* unit = "";
};

void JudgeObservability(ParameterEnd* p) {
  p->observable = !(p->prior_std > 0.0 && p->std >= kUnobservableSigmaRatio * p->prior_std);
}

/// The auxiliary states (the aiding sources' parameters) at the end of a solution.
std::vector<ParameterEnd> AuxStatesAtEnd(const Solution& solution) {
  std::vector<ParameterEnd> out;
  if (solution.epochs.empty()) return out;
  const NavEpoch& last = solution.epochs.back();
  for (std::size_t i = 0; i < solution.aux_states.size(); ++i) {
    const Eigen::Index k = static_cast<Eigen::Index>(i);
    ParameterEnd p;
    p.name = solution.aux_states[i].name;
    if (k < last.aux.size()) p.value = last.aux[k];
    if (k < last.aux_std.size()) p.std = last.aux_std[k];
    p.prior_std = solution.aux_states[i].initial_std;
    p.observed_by = solution.aux_states[i].observed_by;
    JudgeObservability(&p);
    out.push_back(p);
  }
  return out;
}

/// The IMU scale factors at the end of a solution with the 21-state model (none otherwise),
/// judged against the configured prior std (run.prior_std).
std::vector<ParameterEnd> ScaleFactorsAtEnd(const Solution& solution, const Eigen::VectorXd& prior_std) {
  std::vector<ParameterEnd> out;
  if (solution.epochs.empty()) return out;
  const NavEpoch& last = solution.epochs.back();
  if (last.std.size() != ins::err::kSize21 || prior_std.size() != ins::err::kSize21) return out;
  static const char* const kAxes[3] = {"x", "y", "z"};
  static const char* const kGyroNeeds[3] = {"rotation about the body x axis (roll changes)",
                                            "rotation about the body y axis (pitch changes)",
                                            "rotation about the body z axis (turns)"};
  static const char* const kAccelNeeds[3] = {
      "specific force along the body x axis that changes (accelerations and decelerations)",
      "specific force along the body y axis that changes (side forces, or tilts to the side)",
      "changes of the load along the body z axis (banked turns, pull-ups, tilts)"};
  for (int sensor = 0; sensor < 2; ++sensor) {
    const int index = sensor == 0 ? ins::err::kSg : ins::err::kSa;
    const Eigen::Vector3d& value = sensor == 0 ? last.state.imu.sg : last.state.imu.sa;
    for (int axis = 0; axis < 3; ++axis) {
      ParameterEnd p;
      p.name = std::string(sensor == 0 ? "gyro_scale_" : "accel_scale_") + kAxes[axis];
      p.value = value[axis];
      p.std = last.std[index + axis];
      p.prior_std = prior_std[index + axis];
      p.observed_by = sensor == 0 ? kGyroNeeds[axis] : kAccelNeeds[axis];
      p.to_unit = 1.0 / kPpm;
      p.unit = " ppm";
      JudgeObservability(&p);
      out.push_back(p);
    }
  }
  return out;
}

std::vector<ParameterEnd> ParametersAtEnd(const Solution& solution, const Eigen::VectorXd& prior_std) {
  std::vector<ParameterEnd> out = AuxStatesAtEnd(solution);
  for (ParameterEnd& p : ScaleFactorsAtEnd(solution, prior_std)) out.push_back(p);
  return out;
}

/// One JSON object of parameters, dimensionless SI values.
void WriteParameters(JsonWriter& w, const char* key, const std::vector<ParameterEnd>& parameters) {
  if (parameters.empty()) return;
  w.Key(key).BeginObject();
  for (const ParameterEnd& p : parameters) {
    w.Key(p.name)
        .BeginObject()
        .Field("value", p.value)
        .Field("std", p.std)
        .Field("prior_std", p.prior_std)
        .Field("observable", p.observable)
        .EndObject();
  }
  w.EndObject();
}

/// Per residual group: rows, dof, chi2, chi2_per_dof, and for the batch the sigma scale of
/// the variance components and chi2_per_dof with the configured noise.
void WriteResiduals(JsonWriter& w, const Solution& solution) {
  if (solution.residuals.empty()) return;
  w.Key("residuals").BeginObject();
  for (const auto& [group, r] : solution.residuals) {
    w.Key(group)
        .BeginObject()
        .Field("rows", r.rows)
        .Field("dof", r.dof)
        .Field("chi2", r.chi2)
        .Field("chi2_per_dof", r.ChiSquarePerDof())
        .Field("configured_chi2_per_dof", r.configured_chi2_per_dof)
        .Field("sigma_scale", r.sigma_scale)
        .Field("adapted", r.adapted)
        .EndObject();
  }
  w.EndObject();
}

/// One line per parameter (auxiliary states, IMU scale factors): each method's value at the
/// end +- its std, or "not observable" when the record left its std near the prior,
/// followed by the reason.
void AppendParameters(std::string* s, const GnssInsRun& run) {
  std::vector<std::vector<ParameterEnd>> per_method;
  std::vector<std::string> names;
  for (const MethodRun& m : run.methods) {
    per_method.push_back(ParametersAtEnd(m.solution, run.prior_std));
    for (const ParameterEnd& p : per_method.back()) {
      if (std::find(names.begin(), names.end(), p.name) == names.end()) names.push_back(p.name);
    }
  }
  for (const std::string& name : names) {
    Append(s, "%s at the end:", name.c_str());
    const ParameterEnd* unobserved = nullptr;
    for (std::size_t m = 0; m < run.methods.size(); ++m) {
      for (const ParameterEnd& p : per_method[m]) {
        if (p.name != name) continue;
        if (p.observable) {
          Append(s, " %s %.6g +- %.2g%s", run.methods[m].name.c_str(), p.value * p.to_unit, p.std * p.to_unit, p.unit);
        } else {
          Append(s, " %s not observable", run.methods[m].name.c_str());
          unobserved = &p;
        }
      }
    }
    Append(s, "\n");
    if (unobserved != nullptr) {
      Append(s, "  not observable from this record: posterior sigma >= %.1f x prior sigma %.4g%s; it needs %s\n",
             kUnobservableSigmaRatio, unobserved->prior_std * unobserved->to_unit, unobserved->unit,
             unobserved->observed_by.c_str());
    }
  }
}

/// Below this many degrees of freedom a group's chi2 / dof says nothing (a bias process that
/// its own rows determine has almost none); the table shows "-".
constexpr double kMinReportedDof = 1.0;

/// Per method, per residual group: rows, chi2 / dof (with the configured noise and, after
/// variance-component estimation, the adapted one) and the sigma scale.
void AppendResidualStats(std::string* s, const GnssInsRun& run) {
  bool any = false;
  for (const MethodRun& m : run.methods) any = any || !m.solution.residuals.empty();
  if (!any) return;
  Append(s, "residuals (whitened; chi2/dof near 1 when the noise fits; batch: sigma scale from variance components):\n");
  Append(s, "%-14s %-22s %8s %8s %10s %10s %10s %10s\n", "method", "group", "rows", "dof", "rejected", "chi2/dof",
         "sigma x", "chi2/dof");
  Append(s, "%-14s %-22s %8s %8s %10s %10s %10s %10s\n", "", "", "", "", "", "configured", "", "adapted");
  for (const MethodRun& m : run.methods) {
    for (const auto& [name, r] : m.solution.residuals) {
      const auto count = m.solution.counts.find(name);
      const std::size_t rejected = count == m.solution.counts.end() ? 0 : count->second.rejected;
      const double configured = std::isnan(r.configured_chi2_per_dof) ? r.ChiSquarePerDof() : r.configured_chi2_per_dof;
      Append(s, "%-14s %-22s %8zu %8.1f %10zu", m.name.c_str(), name.c_str(), r.rows, r.dof, rejected);
      if (r.dof >= kMinReportedDof) {
        Append(s, " %10.3f", configured);
      } else {
        Append(s, " %10s", "-");
      }
      if (r.adapted) {
        Append(s, " %10.3f %10.3f\n", r.sigma_scale, r.ChiSquarePerDof());
      } else {
        Append(s, " %10s %10s\n", "-", "-");
      }
    }
  }
}

void AppendAdaptedNoise(std::string* s, const GnssInsRun& run) {
  if (run.adapted_noise.empty()) return;
  Append(s, "noise adapted by the batch's variance components (filter_adapted and rts_adapted use it):\n");
  for (const std::string& line : run.adapted_noise) Append(s, "  %s\n", line.c_str());
}

void AppendWarnings(std::string* s, const GnssInsRun& run) {
  if (run.warnings.empty()) return;
  Append(s, "warnings (%zu):\n", run.warnings.size());
  for (const std::string& w : run.warnings) Append(s, "  %s\n", w.c_str());
}

}  // namespace

void WriteRunSummary(JsonWriter& w, const RunOptions& options, const GnssInsRun& run) {
  w.BeginObject().Field("command", options.command).Field("output_method", run.output_method);
  WriteInputs(w, options, run.inputs);
  w.Key("output")
      .BeginObject()
      .Field("dir", options.out_dir)
      .Field("epochs", run.output_epochs)
      .Field("output_rate_hz", run.output_rate_hz)
      .EndObject();
  if (!options.truth.empty()) w.Field("truth", options.truth);
  w.Key("methods").BeginObject();
  for (const MethodRun& m : run.methods) {
    w.Key(m.name).BeginObject().Field("run_time_s", m.solution.run_time_s).Field("knots", m.solution.epochs.size() + m.solution.knots_not_kept);
    w.Key("counts").BeginObject();
    for (const auto& [key, count] : m.solution.counts) {
      w.Key(key).BeginObject().Field("used", count.used).Field("rejected", count.rejected).EndObject();
    }
    w.EndObject();
    WriteParameters(w, "aux", AuxStatesAtEnd(m.solution));
    WriteParameters(w, "imu_scale_factors", ScaleFactorsAtEnd(m.solution, run.prior_std));
    WriteResiduals(w, m.solution);
    if (!m.solution.solver_report.empty()) w.Field("solver_report", m.solution.solver_report);
    if (m.errors) {
      w.Key("errors");
      WriteScore(w, *m.errors);
      w.Field("errors_csv", m.errors_csv);
    }
    w.EndObject();
  }
  w.EndObject();
  w.Key("adapted_noise").BeginArray();
  for (const std::string& text : run.adapted_noise) w.Value(text);
  w.EndArray();
  w.Key("warnings").BeginArray();
  for (const std::string& text : run.warnings) w.Value(text);
  w.EndArray();
  w.Field("total_run_time_s", run.total_run_time_s);
  w.EndObject();
}

std::string RunTable(const RunOptions& options, const GnssInsRun& run) {
  const InputSummary& in = run.inputs;
  std::string s;
  Append(&s,
         "%s: %zu IMU samples, %zu GNSS epochs (%zu removed by %zu injected outages), %zu mag, %zu baro; "
         "%.1f .. %.1f s\n",
         options.command.c_str(), in.imu_samples, in.gnss_epochs, in.gnss_removed_by_outages, in.outages.size(),
         in.mag_samples, in.baro_samples, in.t_start_s, in.t_end_s);
  const bool scored = !run.methods.empty() && run.methods.front().errors.has_value();
  Append(&s, "solution (%s): %s/{nav.nav, nav.csv, std.csv, imu_errors.csv, summary.json}, %zu epochs",
         run.output_method.c_str(), options.out_dir.c_str(), run.output_epochs);
  if (scored) {
    std::string names;
    for (const MethodRun& m : run.methods) names += (names.empty() ? "" : ",") + m.name;
    Append(&s, "; errors per compared epoch: %s/{%s}/errors.csv", options.out_dir.c_str(), names.c_str());
  }
  Append(&s, "\n");
  if (!scored) {
    Append(&s, "%-14s %9s %9s\n", "method", "knots", "run [s]");
    for (const MethodRun& m : run.methods) {
      Append(&s, "%-14s %9zu %9.2f\n", m.name.c_str(), m.solution.epochs.size() + m.solution.knots_not_kept, m.solution.run_time_s);
    }
    AppendParameters(&s, run);
    AppendResidualStats(&s, run);
    AppendAdaptedNoise(&s, run);
    AppendWarnings(&s, run);
    return s;
  }
  const ScoreReport& first = *run.methods.front().errors;
  const bool outages = !first.outages.empty();
  Append(&s, "errors against %s (RMS over %zu reference epochs%s):\n", options.truth.c_str(), first.all.count(),
         outages ? "; drift = per-outage max, RMS over outages" : "");
  Append(&s, "%-14s %10s %10s %10s %10s %10s %10s", "method", "horiz [m]", "vert [m]", "vel [m/s]", "roll [deg]",
         "pitch[deg]", "yaw [deg]");
  if (outages) Append(&s, " %10s %10s", "drift H[m]", "drift V[m]");
  Append(&s, " %10s\n", "run [s]");
  for (const MethodRun& m : run.methods) AppendErrorRow(&s, m, outages);
  AppendConsistencyTable(&s, run);
  AppendParameters(&s, run);
  AppendResidualStats(&s, run);
  AppendAdaptedNoise(&s, run);
  AppendWarnings(&s, run);
  return s;
}

}  // namespace navtwin::gnss_ins
