// The three methods of issue 7 behind one entry point (run.h), their heading tracks
// against the distance flown, the errors at given distances, and the outputs of
// `navtwin inflight-align`.
//
// Heading error convention (common to the project): error = yaw_est - yaw_true wrapped to
// (-pi, pi], which is -phi_D for R_n_b_true = Exp(phi_n) R_n_b_est. The preset flies south,
// where yaw is near +-pi: every difference of yaws is wrapped, and the truth's yaw is
// interpolated on its unwrapped form.
#include "problems/inflight_alignment/run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/io/atomic_file.h"
#include "core/io/json_writer.h"
#include "core/rotation.h"
#include "core/units.h"
#include "problems/inflight_alignment/distance_heading.h"

namespace navtwin::inflight {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// yaw_est - yaw_true wrapped, NaN when the truth is unknown there.
double YawError(double yaw_est_rad, double yaw_true_rad) {
  return std::isnan(yaw_true_rad) ? kNaN : WrapPi(yaw_est_rad - yaw_true_rad);
}

/// A distance in km as a JSON key and a table cell: "10", "12.5".
std::string KmText(double km) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", km);
  return buf;
}

/// The raw GPS sigma the configuration gives, or the robust estimate from the fixes.
double GpsSigma(const std::vector<GnssSample>& fixes, const InflightConfig& config) {
  return config.sensors.gps_sigma_m > 0.0 ? config.sensors.gps_sigma_m : EstimateGpsSigma(fixes);
}

/// distance, kalman: the filter's heading after each fix.
MethodResult RunFilterMethod(const InflightInputs& inputs, const InflightConfig& config, Method method,
                             const std::vector<double>& at_km) {
  MethodResult r;
  r.method = method;
  const auto start = std::chrono::steady_clock::now();
  const FilterRun run =
      RunInflightFilter(inputs, config, method == Method::kDistance ? FilterMethod::kDistance : FilterMethod::kKalman);
  r.run_time_s = Seconds(start);
  r.gps_sigma_m = GpsSigma(inputs.gnss, config);

  r.track.reserve(run.epochs.size());
  for (const FilterEpoch& e : run.epochs) {
    HeadingPoint p;
    p.t_s = e.t_s;
    p.path_length_m = e.path_length_m;
    p.yaw_rad = YawOf(e.nav);
    p.sigma_rad = e.yaw_sigma_rad;
    p.error_rad = YawError(p.yaw_rad, TruthYawAt(inputs.truth, e.t_s));
    r.track.push_back(p);
  }
  // The error at a distance: what the filter knew at the first fix at or after it.
  for (const double km : at_km) {
    const auto it = std::find_if(r.track.begin(), r.track.end(),
                                 [&](const HeadingPoint& p) { return p.path_length_m >= km * 1000.0; });
    r.at_km.push_back(km);
    r.error_at_km_rad.push_back(it == r.track.end() ? kNaN : it->error_rad);
    r.sigma_at_km_rad.push_back(it == r.track.end() ? kNaN : it->sigma_rad);
  }
  r.final_error_rad = r.track.empty() ? kNaN : r.track.back().error_rad;
  r.final_sigma_rad = r.track.empty() ? kNaN : r.track.back().sigma_rad;
  r.computations = run.computations;

  std::ostringstream note;
  const bool smoothed = method == Method::kDistance ? config.smooth_gps_distance : config.smooth_gps_kalman;
  note << run.gps_rejected << " of " << run.epochs.size() << " GPS fixes rejected by "
       << (smoothed ? "the smoother's gate (smoothed fixes)" : "the filter's gate (raw fixes)");
  if (method == Method::kDistance) {
    note << "; " << run.computations.size() << " heading computation" << (run.computations.size() == 1 ? "" : "s");
    if (!run.computations.empty() && !run.computations.back().separation.note.empty()) {
      note << " (last: " << run.computations.back().separation.note << ")";
    }
  }
  r.note = note.str();
  return r;
}

/// batch: the whole-flight solution along the flight, and the batch on each prefix.
MethodResult RunBatchMethod(const InflightInputs& inputs, const InflightConfig& config,
                            const std::vector<double>& at_km) {
  MethodResult r;
  r.method = Method::kBatch;
  const double lat_rad = inputs.initial.lat_rad;
  const double schuler_rate_radps = SchulerRate(inputs.initial.lat_rad, inputs.initial.h_m);

  // run_time_s: the free INS and the whole-flight solve, what the method costs; the
  // prefix solves below only make the figures at each distance.
  const auto start = std::chrono::steady_clock::now();
  const std::vector<FreeInsEpoch> epochs = RunFreeIns(inputs, config);
  const double gps_sigma_m = GpsSigma(inputs.gnss, config);
  r.batch = SolveHeadingBatch(epochs, gps_sigma_m, lat_rad, schuler_rate_radps, config);
  r.run_time_s = Seconds(start);
  r.gps_sigma_m = r.batch.gps_sigma_m;

  // The free INS's heading error is a constant dH of the model: the smoothed heading at
  // each fix is the free INS's yaw minus it.
  r.track.reserve(epochs.size());
  for (const FreeInsEpoch& e : epochs) {
    HeadingPoint p;
    p.t_s = e.t_s;
    p.path_length_m = e.path_length_m;
    p.yaw_rad = WrapPi(e.yaw_free_rad - r.batch.dh_rad);
    p.sigma_rad = r.batch.dh_sigma_rad;
    p.error_rad = YawError(p.yaw_rad, TruthYawAt(inputs.truth, e.t_s));
    r.track.push_back(p);
  }
  r.final_error_rad = r.track.empty() ? kNaN : r.track.back().error_rad;
  r.final_sigma_rad = r.batch.dh_sigma_rad;

  // At each distance the batch solved on the fixes flown so far (path length <= the
  // distance), as a batch run at that moment would; its dH is compared with the free
  // INS's true heading error at the prefix's last fix, yaw_free - yaw_true. The GPS sigma, when
  // estimated, comes from the fixes received by then.
  std::string failures;
  const double flown_m = epochs.empty() ? 0.0 : epochs.back().path_length_m;
  for (const double km : at_km) {
    r.at_km.push_back(km);
    double error = kNaN, sigma = kNaN;
    if (flown_m >= km * 1000.0) {
      std::vector<FreeInsEpoch> prefix;
      for (const FreeInsEpoch& e : epochs) {
        if (e.path_length_m > km * 1000.0) break;
        prefix.push_back(e);
      }
      try {
        if (prefix.empty()) throw std::invalid_argument("no GPS fix in the first " + KmText(km) + " km");
        std::vector<GnssSample> fixes;
        for (const GnssSample& g : inputs.gnss) {
          if (g.t_s <= prefix.back().t_s) fixes.push_back(g);
        }
        const BatchHeadingSolution s =
            SolveHeadingBatch(prefix, GpsSigma(fixes, config), lat_rad, schuler_rate_radps, config);
        // The prefix batch's heading at its last fix is yaw_free - dH_prefix, so its error
        // (yaw - yaw_true, the track's convention) is dH_true - dH_prefix.
        const double dh_true = YawError(prefix.back().yaw_free_rad, TruthYawAt(inputs.truth, prefix.back().t_s));
        error = std::isnan(dh_true) ? kNaN : WrapPi(dh_true - s.dh_rad);
        sigma = s.dh_sigma_rad;
      } catch (const std::exception& e) {
        failures += "; batch at " + KmText(km) + " km failed: " + e.what();
      }
    }
    r.error_at_km_rad.push_back(error);
    r.sigma_at_km_rad.push_back(sigma);
  }

  std::ostringstream note;
  note << r.batch.downweighted << " of " << r.batch.fixes << " GPS fixes down-weighted (robust weight < 0.5, "
       << r.batch.loss << " loss)" << failures;
  r.note = note.str();
  return r;
}

}  // namespace

const char* MethodName(Method m) {
  switch (m) {
    case Method::kDistance:
      return "distance";
    case Method::kKalman:
      return "kalman";
    case Method::kBatch:
      return "batch";
  }
  return "unknown";
}

Method ParseMethod(const std::string& name) {
  for (const Method m : {Method::kDistance, Method::kKalman, Method::kBatch}) {
    if (name == MethodName(m)) return m;
  }
  throw std::invalid_argument("unknown method '" + name + "' (expected distance, kalman or batch)");
}

double TruthYawAt(const std::vector<NavState>& truth, double t_s) {
  if (truth.empty() || !std::isfinite(t_s) || t_s < truth.front().t_s || t_s > truth.back().t_s) return kNaN;
  // First record after t; t is inside the span, so the pair (hi - 1, hi) brackets it.
  const auto hi = std::upper_bound(truth.begin(), truth.end(), t_s,
                                   [](double t, const NavState& s) { return t < s.t_s; });
  if (hi == truth.end()) return YawOf(truth.back());  // t equals the last record's time
  const NavState& a = *(hi - 1);
  const NavState& b = *hi;
  const double ya = YawOf(a);
  if (!(b.t_s > a.t_s)) return ya;
  // Unwrapped: the step from a to b is the short way round (records far closer in time
  // than a half turn), so a heading crossing +-180 deg interpolates through 180.
  const double step = WrapPi(YawOf(b) - ya);
  return WrapPi(ya + step * (t_s - a.t_s) / (b.t_s - a.t_s));
}

MethodResult RunMethod(const InflightInputs& inputs, const InflightConfig& config, Method method,
                       const std::vector<double>& at_km) {
  ValidateInputs(inputs);
  for (const double km : at_km) {
    if (!(km > 0.0) || !std::isfinite(km)) {
      throw std::invalid_argument("RunMethod: at_km must hold finite distances > 0");
    }
  }
  if (method == Method::kBatch) return RunBatchMethod(inputs, config, at_km);
  return RunFilterMethod(inputs, config, method, at_km);
}

std::string MethodResultJson(const MethodResult& r) {
  std::ostringstream out;
  JsonWriter w(out);
  w.BeginObject().Field("method", MethodName(r.method));
  w.Key("heading_error_arcmin_at_km").BeginObject();
  for (std::size_t i = 0; i < r.at_km.size(); ++i) w.Field(KmText(r.at_km[i]), r.error_at_km_rad[i] / kArcmin_rad);
  w.EndObject();
  w.Field("final_heading_error_arcmin", r.final_error_rad / kArcmin_rad)
      .Field("heading_sigma_arcmin", r.final_sigma_rad / kArcmin_rad)
      .Field("run_time_s", r.run_time_s);
  w.Key("heading_sigma_arcmin_at_km").BeginObject();
  for (std::size_t i = 0; i < r.at_km.size(); ++i) w.Field(KmText(r.at_km[i]), r.sigma_at_km_rad[i] / kArcmin_rad);
  w.EndObject();
  w.Field("path_length_km", r.track.empty() ? kNaN : r.track.back().path_length_m / 1000.0)
      .Field("gps_sigma_m", r.gps_sigma_m)
      .Field("fixes", r.track.size());
  if (r.method == Method::kDistance) {
    w.Key("computations").BeginArray();
    for (const HeadingComputation& c : r.computations) {
      w.BeginObject()
          .Field("t_s", c.t_s)
          .Field("path_length_km", c.path_length_m / 1000.0)
          .Field("dh_arcmin", c.dh_rad / kArcmin_rad)
          .Field("sigma_arcmin", c.sigma_rad / kArcmin_rad)
          .Field("correction_arcmin", c.correction_rad / kArcmin_rad)
          .Field("samples", c.separation.samples)
          .Field("note", c.separation.note)
          .EndObject();
    }
    w.EndArray();
  }
  if (r.method == Method::kBatch) {
    const BatchHeadingSolution& b = r.batch;
    const auto pair = [&](const std::string& key, const Eigen::Vector2d& v_ne, double scale) {
      w.Key(key).BeginArray().Value(v_ne[0] * scale).Value(v_ne[1] * scale).EndArray();
    };
    w.Key("batch").BeginObject();
    w.Field("dh_arcmin", b.dh_rad / kArcmin_rad).Field("dh_sigma_arcmin", b.dh_sigma_rad / kArcmin_rad);
    pair("level_ne_arcsec", b.level_rad, 1.0 / kArcsec_rad);
    pair("level_sigma_ne_arcsec", b.level_sigma_rad, 1.0 / kArcsec_rad);
    pair("accel_bias_ne_ug", b.accel_bias_ne_mps2, 1.0 / kMicroG_mps2);
    pair("accel_bias_sigma_ne_ug", b.accel_bias_sigma_mps2, 1.0 / kMicroG_mps2);
    pair("gyro_bias_ne_deg_h", b.gyro_bias_ne_radps, 1.0 / kDegPerHour_radps);
    pair("gyro_bias_sigma_ne_deg_h", b.gyro_bias_sigma_radps, 1.0 / kDegPerHour_radps);
    pair("position0_ne_m", b.position0_ne_m, 1.0);
    pair("velocity0_ne_mps", b.velocity0_ne_mps, 1.0);
    w.Field("fixes", b.fixes)
        .Field("downweighted", b.downweighted)
        .Field("residual_rms_m", b.residual_rms_m)
        .Field("iterations", b.iterations)
        .Field("loss", b.loss)
        .EndObject();
  }
  w.Field("note", r.note).EndObject();
  return out.str();
}

std::string MethodResultTable(const MethodResult& r) {
  std::ostringstream out;
  char line[256];
  out << "method " << MethodName(r.method) << ": heading error (yaw - yaw_true) against distance flown"
      << (r.method == Method::kBatch ? " (batch solved on the fixes up to each distance)" : "") << "\n";
  std::snprintf(line, sizeof line, "  %12s %14s %14s\n", "distance_km", "error_arcmin", "sigma_arcmin");
  out << line;
  const auto cell = [](double rad) {
    if (std::isnan(rad)) return std::string("-");
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3f", rad / kArcmin_rad);
    return std::string(buf);
  };
  for (std::size_t i = 0; i < r.at_km.size(); ++i) {
    std::snprintf(line, sizeof line, "  %12s %14s %14s\n", KmText(r.at_km[i]).c_str(),
                  cell(r.error_at_km_rad[i]).c_str(), cell(r.sigma_at_km_rad[i]).c_str());
    out << line;
  }
  const double flown_km = r.track.empty() ? 0.0 : r.track.back().path_length_m / 1000.0;
  std::snprintf(line, sizeof line, "  %12s %14s %14s   (%.1f km flown, %zu fixes)\n", "final",
                cell(r.final_error_rad).c_str(), cell(r.final_sigma_rad).c_str(), flown_km, r.track.size());
  out << line;
  std::snprintf(line, sizeof line, "  GPS sigma %.2f m, run time %.3f s\n", r.gps_sigma_m, r.run_time_s);
  out << line;
  if (!r.note.empty()) out << "  note: " << r.note << "\n";
  const bool any_missing = std::any_of(r.error_at_km_rad.begin(), r.error_at_km_rad.end(),
                                       [](double x) { return std::isnan(x); });
  if (any_missing || std::isnan(r.final_error_rad)) out << "  ('-': distance not reached, or no truth)\n";
  return out.str();
}

void WriteTrackCsv(const MethodResult& r, const std::string& path) {
  AtomicFile f(path);
  std::ostream& o = f.stream();
  o << "t_s,path_length_km,yaw_deg,sigma_arcmin,error_arcmin\n";
  for (const HeadingPoint& p : r.track) {
    o << p.t_s << "," << p.path_length_m / 1000.0 << "," << p.yaw_rad * kRadToDeg << "," << p.sigma_rad / kArcmin_rad
      << ",";
    if (!std::isnan(p.error_rad)) o << p.error_rad / kArcmin_rad;  // empty: no truth
    o << "\n";
  }
  f.Commit();
}

}  // namespace navtwin::inflight
