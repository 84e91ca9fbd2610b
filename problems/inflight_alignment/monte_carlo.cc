#include "problems/inflight_alignment/monte_carlo.h"

#include <chrono>
#include <cmath>
#include <exception>
#include <stdexcept>

#include "core/io/atomic_file.h"
#include "core/rotation.h"
#include "problems/inflight_alignment/inputs.h"
#include "solvers/monte_carlo.h"

namespace navtwin::inflight {
namespace {

constexpr double kRadToArcmin = kRadToDeg * 60.0;

std::string KmLabel(double km) {
  const double rounded = std::round(km);
  if (std::abs(km - rounded) < 1e-9) return std::to_string(static_cast<long long>(rounded));
  std::string s = std::to_string(km);
  while (!s.empty() && s.back() == '0') s.pop_back();
  return s;
}

/// The heading quantities of one method's result (see InflightMcRun).
std::vector<mc::Quantity> HeadingQuantities(const MethodResult& r, const std::vector<double>& at_km) {
  mc::Quantity along = mc::Quantity::Empty("heading", "arcmin", kRadToArcmin, "distance_km", {"yaw"}, at_km);
  for (std::size_t k = 0; k < at_km.size() && k < r.error_at_km_rad.size(); ++k) {
    along.SetDiagonal(static_cast<int>(k), &r.error_at_km_rad[k], &r.sigma_at_km_rad[k]);
  }
  mc::Quantity at_end = mc::Quantity::Empty("heading_final", "arcmin", kRadToArcmin, "final", {"yaw"}, {1.0});
  at_end.SetDiagonal(0, &r.final_error_rad, &r.final_sigma_rad);
  return {along, at_end};
}

}  // namespace

mc::RunRecord InflightMcRun(const sim::Scenario& scenario, const InflightConfig& config,
                            const std::vector<Method>& methods, const std::vector<double>& at_km,
                            std::uint64_t seed, int run) {
  mc::RunRecord record;
  record.run = run;
  record.seed = seed;
  const InflightInputs inputs = SimulateInflightInputs(scenario, seed);
  for (const Method m : methods) {
    mc::MethodRecord mr;
    mr.method = MethodName(m);
    try {
      const MethodResult r = RunMethod(inputs, config, m, at_km);
      mr.run_time_s = r.run_time_s;
      mr.quantities = HeadingQuantities(r, at_km);
    } catch (const std::exception& e) {
      mr.failure = e.what();
    }
    record.methods.push_back(std::move(mr));
  }
  return record;
}

mc::MethodRecord InflightBound(const sim::Scenario& scenario, const InflightConfig& config,
                               const std::vector<double>& at_km, std::uint64_t seed) {
  const InflightInputs inputs = SimulateInflightInputs(scenario, seed, /*perfect=*/true);
  // Noise-free fixes would estimate a zero GPS sigma: the bound takes the receiver's.
  InflightConfig bound_config = config;
  double& gps_sigma_m = bound_config.sensors.gps_sigma_m;
  if (gps_sigma_m == 0.0) gps_sigma_m = scenario.gnss->position_sigma_ned_m.head<2>().mean();
  const MethodResult r = RunMethod(inputs, bound_config, Method::kBatch, at_km);
  mc::MethodRecord bound;
  bound.method = "bound";
  bound.run_time_s = r.run_time_s;
  bound.quantities = HeadingQuantities(r, at_km);
  return bound;
}

McRunNumbers NumbersOf(const MethodResult& result) {
  McRunNumbers n;
  n.error_at_km_rad = result.error_at_km_rad;
  n.final_error_rad = result.final_error_rad;
  n.final_sigma_rad = result.final_sigma_rad;
  n.run_time_s = result.run_time_s;
  return n;
}

Moments MomentsOf(const std::vector<double>& values) {
  Moments m;
  double sum = 0.0, sum2 = 0.0;
  for (const double v : values) {
    if (!std::isfinite(v)) continue;
    ++m.count;
    sum += v;
    sum2 += v * v;
  }
  if (m.count == 0) return m;
  m.mean = sum / m.count;
  m.rms = std::sqrt(sum2 / m.count);
  if (m.count > 1) {
    double dev2 = 0.0;
    for (const double v : values) {
      if (std::isfinite(v)) dev2 += (v - m.mean) * (v - m.mean);
    }
    m.sigma = std::sqrt(dev2 / (m.count - 1));
  }
  return m;
}

McMethodStats StatsOf(Method method, const std::vector<McRunNumbers>& runs) {
  McMethodStats s;
  s.method = method;
  const auto column = [&](auto get) {
    std::vector<double> v;
    for (const McRunNumbers& r : runs) v.push_back(get(r));
    return MomentsOf(v);
  };
  const std::size_t distances = runs.empty() ? 0 : runs.front().error_at_km_rad.size();
  for (std::size_t k = 0; k < distances; ++k) {
    s.error_at_km_rad.push_back(column([k](const McRunNumbers& r) {
      return k < r.error_at_km_rad.size() ? r.error_at_km_rad[k] : McRunNumbers::kNaN;
    }));
  }
  s.final_error_rad = column([](const McRunNumbers& r) { return r.final_error_rad; });
  s.final_sigma_rad = column([](const McRunNumbers& r) { return r.final_sigma_rad; });
  s.run_time_s = column([](const McRunNumbers& r) { return r.run_time_s; });
  for (const McRunNumbers& r : runs) {
    if (r.failure.empty()) continue;
    if (s.failures++ == 0) s.first_failure = r.failure;
  }
  return s;
}

McResult RunInflightMonteCarlo(const sim::Scenario& scenario, const InflightConfig& config,
                               const McOptions& options) {
  if (options.runs < 1) throw std::invalid_argument("inflight Monte Carlo: runs must be >= 1");
  if (options.threads < 0) throw std::invalid_argument("inflight Monte Carlo: threads must be >= 0");
  if (options.methods.empty()) throw std::invalid_argument("inflight Monte Carlo: no method");
  McResult result;
  result.options = options;
  result.workers = MonteCarloWorkers(options.runs, options.threads);
  const std::size_t methods = options.methods.size();
  result.runs.assign(options.runs, std::vector<McRunNumbers>(methods));
  const auto start = std::chrono::steady_clock::now();
  RunParallel(
      options.runs, options.threads,
      [&](int run, int /*worker*/) {
        const std::uint64_t seed = options.seed + static_cast<std::uint64_t>(run);
        const InflightInputs inputs = SimulateInflightInputs(scenario, seed);
        for (std::size_t m = 0; m < methods; ++m) {
          McRunNumbers& slot = result.runs[run][m];
          try {
            slot = NumbersOf(RunMethod(inputs, config, options.methods[m], options.at_km));
          } catch (const std::exception& e) {
            slot = McRunNumbers();
            slot.error_at_km_rad.assign(options.at_km.size(), McRunNumbers::kNaN);
            slot.failure = "seed " + std::to_string(seed) + ": " + e.what();
          }
        }
      },
      options.progress);
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t m = 0; m < methods; ++m) {
    std::vector<McRunNumbers> column;
    for (const auto& run : result.runs) column.push_back(run[m]);
    result.stats.push_back(StatsOf(options.methods[m], column));
  }
  return result;
}

void WriteMcErrorsCsv(const McResult& result, const std::string& path) {
  const McOptions& o = result.options;
  AtomicFile f(path);
  std::ostream& out = f.stream();
  out << "run,seed,method";
  for (const double km : o.at_km) out << ",error_" << KmLabel(km) << "km_arcmin";
  out << ",final_error_arcmin,final_sigma_arcmin,run_time_s\n";
  for (std::size_t run = 0; run < result.runs.size(); ++run) {
    for (std::size_t m = 0; m < o.methods.size(); ++m) {
      const McRunNumbers& n = result.runs[run][m];
      out << run << "," << o.seed + run << "," << MethodName(o.methods[m]);
      for (const double x : n.error_at_km_rad) out << "," << x * kRadToArcmin;
      out << "," << n.final_error_rad * kRadToArcmin << "," << n.final_sigma_rad * kRadToArcmin << ","
          << n.run_time_s << "\n";
    }
  }
  f.Commit();
}

}  // namespace navtwin::inflight
