#include "problems/gnss_ins/monte_carlo.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
#include <stdexcept>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/io/atomic_file.h"
#include "core/io/open.h"
#include "core/rotation.h"
#include "core/sim/scenario.h"
#include "core/sim/simulator.h"
#include "core/units.h"
#include "problems/gnss_ins/adapted_noise.h"
#include "problems/gnss_ins/batch.h"
#include "problems/gnss_ins/config.h"
#include "problems/gnss_ins/filter.h"
#include "problems/gnss_ins/initial_state.h"
#include "problems/gnss_ins/inputs.h"
#include "problems/gnss_ins/sim_config.h"
#include "problems/ins/ins_state.h"
#include "problems/ins/nav_error.h"

namespace navtwin::gnss_ins {

namespace {

constexpr double kMradPerRad = 1.0 / kMrad_rad;  // display scale
constexpr double kKnotMatch_s = 1e-6;
const std::vector<std::string> kMethods = {"filter", "rts", "batch", "filter_adapted", "rts_adapted"};

/// A simulated record read back as `navtwin smooth` reads it.
struct McRecord {
  GnssInsConfig config;
  Inputs inputs;
  std::vector<NavState> truth;
};

McRecord SimulateMcRecord(const GnssInsMcSetup& setup, std::uint64_t seed, bool perfect) {
  const sim::Scenario scenario = sim::LoadScenario(setup.scenario);
  if (!scenario.gnss) throw std::invalid_argument("scenario " + setup.scenario + " has no GNSS");
  sim::SimulationOptions options;
  options.seed = seed;
  options.perfect = perfect;
  const sim::TemporarySimulation simulated(scenario, options, "navtwin_mc_");
  AtomicFile yaml(simulated.path("navtwin.yaml"));
  yaml.stream() << ConfigYamlForSimulation(scenario, simulated.dir(), seed, setup.mag_mode);
  yaml.Commit();
  McRecord r;
  r.config = LoadGnssInsConfig(simulated.path("navtwin.yaml"));
  InputPaths paths;
  paths.imu = simulated.path("imu.txt");
  paths.gnss = simulated.path("gnss.txt");
  if (scenario.mag && setup.mag_mode != "off") paths.mag = simulated.path("mag.csv");
  r.inputs = LoadInputs(paths, r.config);
  const std::unique_ptr<NavReader> truth = OpenNav(simulated.path("truth.nav"));
  NavState s;
  while (truth->Next(&s)) r.truth.push_back(s);
  return r;
}

std::vector<double> McGrid(const Inputs& inputs) {
  return mc::WholeSecondGrid(inputs.imu.begin_s(), inputs.imu.known_end_s());
}

struct NavQuantities {
  mc::Quantity position, velocity, attitude;
  explicit NavQuantities(const std::vector<double>& grid)
      : position(mc::Quantity::Empty("position", "m", 1.0, "t_s", {"n", "e", "d"}, grid)),
        velocity(mc::Quantity::Empty("velocity", "m/s", 1.0, "t_s", {"n", "e", "d"}, grid)),
        attitude(mc::Quantity::Empty("attitude", "mrad", kMradPerRad, "t_s", {"n", "e", "d"}, grid)) {}
  std::vector<mc::Quantity> Take() { return {std::move(position), std::move(velocity), std::move(attitude)}; }
};

/// Errors of the knots against the truth on the grid; covariances from `covariances` (full
/// n x n per knot) when given, else diag(std^2).
std::vector<mc::Quantity> QuantitiesOf(const Solution& s, const std::vector<Eigen::MatrixXd>* covariances,
                                       const std::vector<NavState>& truth, const std::vector<double>& grid) {
  NavQuantities q(grid);
  std::size_t k = 0;
  for (int p = 0; p < static_cast<int>(grid.size()); ++p) {
    while (k < s.epochs.size() && s.epochs[k].state.nav.t_s <= grid[p] + kKnotMatch_s) ++k;
    if (k == 0) continue;
    const NavEpoch& knot = s.epochs[k - 1];
    const std::optional<NavState> t = NavAt(truth, knot.state.nav.t_s);
    if (!t || knot.std.size() < ins::err::kBa + 3) continue;
    const NavError e = CompareNav(knot.state.nav, *t);
    const Eigen::Vector3d e_att = AttitudeError(knot.state.nav.q_n_b, t->q_n_b);  // Log(R_n_b_est R_n_b_true^T)
    const bool full = covariances != nullptr && k - 1 < covariances->size();
    const auto block = [&](int at) -> Eigen::Matrix<double, 3, 3, Eigen::RowMajor> {
      if (full) return (*covariances)[k - 1].block<3, 3>(at, at);
      return knot.std.segment<3>(at).array().square().matrix().asDiagonal();
    };
    const auto pos = block(ins::err::kPos), vel = block(ins::err::kVel), att = block(ins::err::kAtt);
    q.position.Set(p, e.pos_ned_m.data(), pos.data());
    q.velocity.Set(p, e.vel_ned_mps.data(), vel.data());
    q.attitude.Set(p, e_att.data(), att.data());
  }
  return q.Take();
}

bool Wants(const GnssInsMcSetup& setup, const std::string& method) {
  return std::find(setup.methods.begin(), setup.methods.end(), method) != setup.methods.end();
}

/// The filter and its RTS smoother again with the noise the batch's variance components
/// found (adapted_noise.h), as `navtwin smooth` runs them; the plain ones when nothing changed.
void RunAdapted(const McRecord& r, const FilterStart& start, const Solution& batch, const std::vector<double>& grid,
                const mc::MethodRecord& filter, const mc::MethodRecord& rts, mc::MethodRecord* filter_adapted,
                mc::MethodRecord* rts_adapted) {
  const AdaptedNoise adapted = AdaptNoise(r.config, batch.residuals);
  if (!adapted.changed) {
    filter_adapted->quantities = filter.quantities;
    rts_adapted->quantities = rts.quantities;
    return;
  }
  FilterResult fr = RunFilter(r.inputs, adapted.config, start, true, {}, nullptr, FilterKnots::kAllWithCovariances);
  filter_adapted->run_time_s = fr.filter.run_time_s;
  filter_adapted->quantities = QuantitiesOf(fr.filter, &fr.filter_covariances, r.truth, grid);
  if (!fr.rts) throw std::runtime_error("the filter returned no RTS solution");
  rts_adapted->run_time_s = fr.rts->run_time_s;
  rts_adapted->quantities = QuantitiesOf(*fr.rts, &fr.rts_covariances, r.truth, grid);
}

}  // namespace

void CheckGnssInsMcSetup(const GnssInsMcSetup& setup) {
  for (const std::string& m : setup.methods) {
    if (std::find(kMethods.begin(), kMethods.end(), m) == kMethods.end()) {
      throw std::invalid_argument("gnss_ins Monte Carlo: unknown method '" + m +
                                  "' (filter, rts, batch, filter_adapted, rts_adapted)");
    }
  }
  if (setup.methods.empty()) throw std::invalid_argument("gnss_ins Monte Carlo: no method");
  for (const char* mode : {"off", "vector", "heading", "heading_2axis"}) {
    if (setup.mag_mode == mode) return;
  }
  throw std::invalid_argument("gnss_ins Monte Carlo: unknown magnetometer mode '" + setup.mag_mode + "'");
}

mc::RunRecord GnssInsMcRun(const GnssInsMcSetup& setup, std::uint64_t seed, int run) {
  mc::RunRecord record;
  record.run = run;
  record.seed = seed;
  const McRecord r = SimulateMcRecord(setup, seed, false);
  const std::vector<double> grid = McGrid(r.inputs);
  std::vector<mc::MethodRecord> m(kMethods.size());
  for (std::size_t i = 0; i < kMethods.size(); ++i) m[i].method = kMethods[i];
  mc::MethodRecord &filter = m[0], &rts = m[1], &batch = m[2];
  const bool adapted = Wants(setup, "filter_adapted") || Wants(setup, "rts_adapted");
  std::size_t failing_from = 0;  // methods from here on fail with the exception below
  try {
    const FilterStart start = InitialFilterState(r.inputs, r.config, nullptr);
    const bool smooth = Wants(setup, "rts") || Wants(setup, "batch") || adapted;
    FilterResult fr = RunFilter(r.inputs, r.config, start, smooth, {}, nullptr, FilterKnots::kAllWithCovariances);
    filter.run_time_s = fr.filter.run_time_s;
    filter.quantities = QuantitiesOf(fr.filter, &fr.filter_covariances, r.truth, grid);
    failing_from = 1;
    if (fr.rts) {
      rts.run_time_s = fr.rts->run_time_s;
      rts.quantities = QuantitiesOf(*fr.rts, &fr.rts_covariances, r.truth, grid);
    }
    failing_from = 2;
    if (Wants(setup, "batch") || adapted) {
      const Solution b = RunBatch(r.inputs, r.config, *fr.rts, &start, nullptr);
      batch.run_time_s = b.run_time_s;
      batch.quantities = QuantitiesOf(b, nullptr, r.truth, grid);
      failing_from = 3;
      if (adapted) RunAdapted(r, start, b, grid, filter, rts, &m[3], &m[4]);
    }
  } catch (const std::exception& e) {
    for (std::size_t i = failing_from; i < m.size(); ++i) m[i].failure = e.what();
  }
  for (mc::MethodRecord& method : m) {
    if (Wants(setup, method.method)) record.methods.push_back(std::move(method));
  }
  return record;
}

mc::MethodRecord GnssInsBound(const GnssInsMcSetup& setup, std::uint64_t seed) {
  McRecord r = SimulateMcRecord(setup, seed, true);
  r.config.batch.variance_components = false;
  r.config.batch.covariance = true;
  const std::vector<double> grid = McGrid(r.inputs);
  const FilterStart start = InitialFilterState(r.inputs, r.config, nullptr);
  FilterResult fr = RunFilter(r.inputs, r.config, start, true, {}, nullptr);
  if (!fr.rts) throw std::runtime_error("the filter returned no RTS solution");
  const Solution b = RunBatch(r.inputs, r.config, *fr.rts, &start, nullptr);
  mc::MethodRecord bound;
  bound.method = "bound";
  bound.run_time_s = b.run_time_s;
  bound.quantities = QuantitiesOf(b, nullptr, r.truth, grid);
  return bound;
}

}  // namespace navtwin::gnss_ins
