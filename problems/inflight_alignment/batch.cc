// The robust batch of the distance method (batch.h): one Ceres problem over the fixes.
//
// Unknowns (SI, north/east): dH, eps_NE, df_NE, dw_NE, dp0_NE, dv0_NE and the level steps
// d_eps_NE,k (below), all started at zero.
// Residuals: DistanceHeadingTiltWalkResidual per fix (problems/inflight_alignment/distance_heading_residual.h;
// DistanceHeadingResidual plus the steps before the fix) under the configured robust loss,
// and zero-mean VectorPrior2 priors:
//   level       sigma = initial.level_arcmin                         (both axes)
//   level step  sigma = ARW sqrt(T)                                  (both axes, each step)
//   accel bias  sigma = sensors.accel_bias_ug (1 ug = 1e-6 x 9.80665 m/s^2)
//   gyro bias   north: sensors.gyro_bias_deg_h;
//               east:  sqrt(gyro_bias^2 + (Omega cos L sigma_psi0)^2).
//     The Earth-rate widening is on the east axis only: with a heading (down-axis) error
//     psi, the attitude-error rate -omega_ie x psi = (0, -Omega cos L psi_D, 0) in NED,
//     an east tilt rate exactly like an east gyro bias, which enters s_N through g dw_E b3;
//     so dw_E estimates the east gyro bias plus that coupling.
//   position0   sigma = initial.position_m, velocity0 sigma = initial.velocity_mps.
// A prior sigma of 0 (a sensor without that error, config.h) holds the coordinate at zero.
// The heading has no prior.
//
// Level random walk. The gyro angle random walk (sensors.gyro_arw_deg_sqrt_h, converted to
// rad/sqrt(s) as ARW) makes the level error a Wiener process eps(t) = eps0 + W(t),
// E[W W^T] = ARW^2 t I. Its position effect g * (double integral of W), of variance
// g^2 ARW^2 t^5 / 20 per axis (22 m at 545 s for the preset's 0.005 deg/sqrt(h)), is
// correlated over the flight like the Schuler terms; the constant model would take part of
// it for heading. The walk is cut at tau_k = k T (T = batch.tilt_segment_s, k >= 1,
// tau_k < the last fix's time): the step d_eps_k stands for W's increment over the
// segment of length T centred on tau_k, prior sigma ARW sqrt(T) (0.027' for the preset and
// T = 30 s); the first half segment goes into eps0 (ARW sqrt(T/2) = 0.019' next to its
// 0.34' prior: the prior would widen by 0.2 %, left as is) and the time after the last
// step's half segment, shorter than T/2, is left out (it moves the last fix by about
// g ARW (T/2)^2.5 / 2 = 6e-3 m at T = 30 s). Moving an increment inside its segment to
// tau_k leaves a position error of variance about g^2 ARW^2 T^2 t^3 / 36 (0.9 m at 545 s,
// T = 30 s), far below the GPS noise. Every fix depends on every step before it, so the Jacobian is dense in the steps:
// the solve and covariance cost grows as (11 + 2 x steps)^2 x fixes (18 steps at 545 s).
//
// Scaling. The columns of J differ by ~1e8 in SI units (a gyro bias of 1 rad/s moves a fix
// by g t^3/6 ~ 3e8 m after 545 s, a position offset of 1 m by 1 m), so J^T J would have a
// condition number ~1e16 and the dense-SVD covariance would call it rank deficient. Each
// block therefore gets a ScaledEuclidean manifold x = x0 + S delta with S its prior sigma
// (heading: its initial sigma): the tangent coordinates are in units of the prior, J's
// tangent columns are O(1 .. 1e3), and the covariance is mapped back as S P_tangent S.
//
// Loss. Residuals are whitened, so the loss scale a = loss_scale_sigma is in GPS sigmas and
// ceres::HuberLoss(a) / ceres::CauchyLoss(a) are used as constructed: Ceres' constructor
// takes a and itself uses a^2 on s = |r|^2 (rho(s) = a^2 rho_1(s / a^2), loss_function.h),
// so the Huber kink and the Cauchy half-weight point are at |r| = a sigmas.
// The Cauchy cost is not convex: from zero, a 20' heading error puts the late fixes at
// ~25 sigma, where the Cauchy weight is < 0.02, so the solve is first run with the convex
// Huber loss of the same scale and the Cauchy stage starts from its solution.
#include "problems/inflight_alignment/batch.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include "core/earth.h"
#include "core/units.h"
#include "problems/inflight_alignment/distance_heading_residual.h"
#include "solvers/batch_driver.h"

namespace navtwin::inflight {
namespace {

constexpr int kMinEpochs = 10;
constexpr double kMinGainedDisplacement_m = 100.0;
constexpr int kMaxTiltSteps = 1000;  // level random-walk steps (batch.tilt_segment_s)

/// x (+) delta = x + S delta on the coordinates with a positive scale; coordinates with
/// scale 0 are held (not in the tangent space). Tangent size = number of positive scales.
class ScaledEuclidean final : public ceres::Manifold {
 public:
  explicit ScaledEuclidean(std::vector<double> scales) : scales_(std::move(scales)) {
    for (int i = 0; i < static_cast<int>(scales_.size()); ++i) {
      if (scales_[i] > 0.0) free_.push_back(i);
    }
  }
  int AmbientSize() const override { return static_cast<int>(scales_.size()); }
  int TangentSize() const override { return static_cast<int>(free_.size()); }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    std::copy(x, x + AmbientSize(), x_plus_delta);
    for (int k = 0; k < TangentSize(); ++k) x_plus_delta[free_[k]] += scales_[free_[k]] * delta[k];
    return true;
  }
  bool PlusJacobian(const double* /*x*/, double* jacobian) const override {  // ambient x tangent
    std::fill(jacobian, jacobian + AmbientSize() * TangentSize(), 0.0);
    for (int k = 0; k < TangentSize(); ++k) jacobian[free_[k] * TangentSize() + k] = scales_[free_[k]];
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    for (int k = 0; k < TangentSize(); ++k) y_minus_x[k] = (y[free_[k]] - x[free_[k]]) / scales_[free_[k]];
    return true;
  }
  bool MinusJacobian(const double* /*x*/, double* jacobian) const override {  // tangent x ambient
    std::fill(jacobian, jacobian + AmbientSize() * TangentSize(), 0.0);
    for (int k = 0; k < TangentSize(); ++k) jacobian[k * AmbientSize() + free_[k]] = 1.0 / scales_[free_[k]];
    return true;
  }
  const std::vector<int>& free() const { return free_; }
  double scale(int i) const { return scales_[i]; }

 private:
  std::vector<double> scales_;
  std::vector<int> free_;
};

void RequireBatchConfig(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("SolveHeadingBatch: " + what);
}

/// A prior sigma from the configuration (SI): finite and >= 0 (0 holds the coordinate).
/// `key` is the configuration key the value came from.
double PriorSigma(double value, const std::string& key) {
  RequireBatchConfig(std::isfinite(value) && value >= 0.0, "config " + key + " must be finite and >= 0");
  return value;
}

void CheckEpochs(const std::vector<FreeInsEpoch>& epochs) {
  RequireBatchConfig(static_cast<int>(epochs.size()) >= kMinEpochs,
          std::to_string(epochs.size()) + " epochs, at least " + std::to_string(kMinEpochs) + " needed");
  double largest_gained_m = 0.0;
  for (std::size_t i = 0; i < epochs.size(); ++i) {
    const DistanceErrorSample& s = epochs[i].sample;
    const std::array<std::pair<const char*, double>, 5> fields = {
        {{"t_s", s.t_s}, {"dn_m", s.dn_m}, {"de_m", s.de_m}, {"err_n_m", s.err_n_m}, {"err_e_m", s.err_e_m}}};
    for (const auto& [name, value] : fields) {
      RequireBatchConfig(std::isfinite(value), "epochs[" + std::to_string(i) + "].sample." + name + " is not finite");
    }
    largest_gained_m = std::max(largest_gained_m, std::hypot(s.dn_m, s.de_m));
  }
  RequireBatchConfig(largest_gained_m > kMinGainedDisplacement_m,
          "the gained displacement never exceeds 100 m (largest " + std::to_string(largest_gained_m) +
              " m): the heading is not observable");
}

}  // namespace

double RobustWeight(RobustLoss loss, double scale_sigma, double squared_residual) {
  if (!(squared_residual >= 0.0)) {
    throw std::invalid_argument("RobustWeight: squared_residual must be >= 0, got " + std::to_string(squared_residual));
  }
  if (loss == RobustLoss::kNone) return 1.0;
  if (!(scale_sigma > 0.0) || !std::isfinite(scale_sigma)) {
    throw std::invalid_argument("RobustWeight: scale_sigma must be positive and finite");
  }
  const double a2 = scale_sigma * scale_sigma;
  if (loss == RobustLoss::kHuber) {
    // rho(s) = s (s <= a^2), 2 a sqrt(s) - a^2 (s > a^2).
    return squared_residual <= a2 ? 1.0 : scale_sigma / std::sqrt(squared_residual);
  }
  // Cauchy: rho(s) = a^2 log(1 + s / a^2).
  return 1.0 / (1.0 + squared_residual / a2);
}

BatchHeadingSolution SolveHeadingBatch(const std::vector<FreeInsEpoch>& epochs, double gps_sigma_m,
                                       double lat_rad, double schuler_rate_radps, const InflightConfig& config) {
  CheckEpochs(epochs);
  RequireBatchConfig(std::isfinite(gps_sigma_m) && gps_sigma_m > 0.0, "gps_sigma_m must be positive and finite");
  RequireBatchConfig(std::isfinite(lat_rad) && std::abs(lat_rad) <= 0.5 * M_PI, "lat_rad must be finite, |lat| <= pi/2");
  RequireBatchConfig(std::isfinite(schuler_rate_radps) && schuler_rate_radps > 0.0,
          "schuler_rate_radps must be positive and finite");
  const BatchOptions& batch = config.batch;
  RequireBatchConfig(batch.max_iterations >= 1, "config batch.max_iterations must be >= 1");
  RequireBatchConfig(batch.loss == RobustLoss::kNone || (std::isfinite(batch.loss_scale_sigma) && batch.loss_scale_sigma > 0.0),
          "config batch.loss_scale_sigma must be positive and finite");
  RequireBatchConfig(std::isfinite(batch.tilt_segment_s) && batch.tilt_segment_s >= 0.0,
          "config batch.tilt_segment_s must be finite and >= 0");

  // Prior sigmas (the comment at the top).
  const double level_sigma = PriorSigma(config.initial.level_rad, "initial.level_arcmin");
  const double accel_sigma = PriorSigma(config.sensors.accel_bias_mps2, "sensors.accel_bias_ug");
  const double gyro_sigma = PriorSigma(config.sensors.gyro_bias_radps, "sensors.gyro_bias_deg_h");
  const double heading_sigma = PriorSigma(config.initial.heading_rad, "initial.heading_arcmin");
  const double position_sigma = PriorSigma(config.initial.position_m, "initial.position_m");
  const double velocity_sigma = PriorSigma(config.initial.velocity_mps, "initial.velocity_mps");
  const double arw_rad_sqrt_s = PriorSigma(config.sensors.gyro_arw_rad_per_sqrt_s, "sensors.gyro_arw_deg_sqrt_h");
  const double earth_rate_coupling = wgs84::kOmegaIe_radps * std::cos(lat_rad) * heading_sigma;
  const Eigen::Vector2d sigma_level(level_sigma, level_sigma);
  const Eigen::Vector2d sigma_accel(accel_sigma, accel_sigma);
  const Eigen::Vector2d sigma_gyro(gyro_sigma, std::hypot(gyro_sigma, earth_rate_coupling));
  const Eigen::Vector2d sigma_position(position_sigma, position_sigma);
  const Eigen::Vector2d sigma_velocity(velocity_sigma, velocity_sigma);
  // The heading has no prior; its tangent unit is its initial sigma (1' if that is 0).
  const double heading_scale = heading_sigma > 0.0 ? heading_sigma : kArcmin_rad;

  // Gravity at the start: batch.h passes no height, and g changes by 3e-4 relative over
  // 1 km, which only rescales eps and dw (g eps, g dw are what the data see), never dH.
  const double gravity_mps2 = wgs84::NormalGravity(lat_rad, 0.0);

  // Parameter blocks (SI), started at zero.
  double heading[1] = {0.0};
  double level[2] = {0.0, 0.0}, accel[2] = {0.0, 0.0}, gyro[2] = {0.0, 0.0};
  double position0[2] = {0.0, 0.0}, velocity0[2] = {0.0, 0.0};
  struct BlockInfo {
    double* x;
    Eigen::Vector2d sigma;  // prior sigma per coordinate (heading: unused)
    int size;
    const char* name;
  };
  const std::array<BlockInfo, 6> blocks = {{{heading, Eigen::Vector2d(heading_scale, 0.0), 1, "heading"},
                                            {level, sigma_level, 2, "level"},
                                            {accel, sigma_accel, 2, "accelerometer bias"},
                                            {gyro, sigma_gyro, 2, "gyro bias"},
                                            {position0, sigma_position, 2, "initial position"},
                                            {velocity0, sigma_velocity, 2, "initial velocity"}}};

  // Level steps at tau_k = k T < the last fix's time (the comment at the top); none when
  // T = 0 (off) or the gyro has no angle random walk.
  double last_t_s = 0.0;
  for (const FreeInsEpoch& e : epochs) last_t_s = std::max(last_t_s, e.sample.t_s);
  std::vector<double> step_time_s;
  const double step_sigma = arw_rad_sqrt_s * std::sqrt(batch.tilt_segment_s);
  if (batch.tilt_segment_s > 0.0 && step_sigma > 0.0) {
    RequireBatchConfig(last_t_s / batch.tilt_segment_s <= kMaxTiltSteps,
            "config batch.tilt_segment_s = " + std::to_string(batch.tilt_segment_s) + " s cuts the " +
                std::to_string(last_t_s) + " s flight into more than " + std::to_string(kMaxTiltSteps) +
                " level steps (the dense solve grows as their square per fix): use longer segments");
    for (int k = 1; k * batch.tilt_segment_s < last_t_s; ++k) step_time_s.push_back(k * batch.tilt_segment_s);
  }
  std::vector<std::array<double, 2>> steps(step_time_s.size(), std::array<double, 2>{0.0, 0.0});  // never resized

  // Owned here (declared before the problem, destroyed after it): the manifolds and the
  // loss shared by every fix.
  std::vector<std::unique_ptr<ScaledEuclidean>> manifolds;
  std::unique_ptr<ceres::LossFunctionWrapper> loss;
  if (batch.loss != RobustLoss::kNone) {  // Huber, also the first stage of Cauchy
    loss = std::make_unique<ceres::LossFunctionWrapper>(new ceres::HuberLoss(batch.loss_scale_sigma),
                                                        ceres::TAKE_OWNERSHIP);
  }
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);

  // Per fix: its cost (owned by the problem) and its parameter blocks, the six constant
  // ones then the steps before it.
  std::vector<std::pair<ceres::CostFunction*, std::vector<double*>>> fix_costs;
  fix_costs.reserve(epochs.size());
  for (const FreeInsEpoch& e : epochs) {
    const DistanceErrorSample& s = e.sample;
    const std::array<double, kSchulerTerms> b = SchulerBasis(s.t_s, schuler_rate_radps);
    std::vector<double*> parameters = {heading, level, accel, gyro, position0, velocity0};
    std::vector<double> step_basis_s2;
    for (std::size_t k = 0; k < step_time_s.size() && step_time_s[k] < s.t_s; ++k) {
      step_basis_s2.push_back(SchulerBasis(s.t_s - step_time_s[k], schuler_rate_radps)[2]);
      parameters.push_back(steps[k].data());
    }
    ceres::CostFunction* cost = DistanceHeadingTiltWalkResidual::Create(
        b[1], b[2], b[3], Eigen::Vector2d(s.dn_m, s.de_m), Eigen::Vector2d(s.err_n_m, s.err_e_m), gps_sigma_m,
        gravity_mps2, std::move(step_basis_s2));
    problem.AddResidualBlock(cost, loss.get(), parameters);
    fix_costs.emplace_back(cost, std::move(parameters));
  }
  // The steps' priors and scaling, one manifold shared by all.
  if (!steps.empty()) {
    manifolds.push_back(std::make_unique<ScaledEuclidean>(std::vector<double>{step_sigma, step_sigma}));
  }
  for (std::array<double, 2>& step : steps) {
    problem.AddResidualBlock(VectorPrior2::Create(Eigen::Vector2d::Zero(), Eigen::Vector2d(step_sigma, step_sigma)),
                             nullptr, step.data());
    problem.SetManifold(step.data(), manifolds.back().get());
  }
  for (const BlockInfo& block : blocks) {
    std::vector<double> scales(block.sigma.data(), block.sigma.data() + block.size);
    if (block.x != heading) {
      // A held coordinate (sigma 0) gets a unit prior sigma: it stays at zero, so its prior
      // residual is zero whatever the sigma.
      const Eigen::Vector2d prior_sigma = (block.sigma.array() > 0.0).select(block.sigma, 1.0);
      problem.AddResidualBlock(VectorPrior2::Create(Eigen::Vector2d::Zero(), prior_sigma), nullptr, block.x);
    }
    if (std::none_of(scales.begin(), scales.end(), [](double v) { return v > 0.0; })) {
      problem.SetParameterBlockConstant(block.x);
    } else {
      manifolds.push_back(std::make_unique<ScaledEuclidean>(scales));
      problem.SetManifold(block.x, manifolds.back().get());
    }
  }

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = batch.max_iterations;
  options.function_tolerance = 1e-12;
  options.gradient_tolerance = 1e-12;
  options.parameter_tolerance = 1e-12;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;

  BatchHeadingSolution out;
  const auto solve = [&](const char* stage) {
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    if (!summary.IsSolutionUsable()) {
      throw std::runtime_error(std::string("SolveHeadingBatch: Ceres failed (") + stage + "): " + summary.message);
    }
    out.iterations += std::max(0, static_cast<int>(summary.iterations.size()) - 1);
  };
  solve(batch.loss == RobustLoss::kCauchy ? "Huber start" : RobustLossName(batch.loss));
  if (batch.loss == RobustLoss::kCauchy) {
    loss->Reset(new ceres::CauchyLoss(batch.loss_scale_sigma), ceres::TAKE_OWNERSHIP);
    solve("cauchy");
  }

  // Covariance (ceres::Covariance through the solvers' driver), tangent -> SI.
  std::vector<const double*> requested;
  for (const BlockInfo& block : blocks) requested.push_back(block.x);
  const CovarianceResult covariance = ComputeTangentCovariance(problem, requested);
  if (!covariance.covariance) {
    std::ostringstream text;
    text << "SolveHeadingBatch: " << covariance.message;
    if (!covariance.unobservable_blocks.empty()) {
      text << " (unobservable:";
      for (const int i : covariance.unobservable_blocks) text << ' ' << blocks[i].name;
      text << ')';
    }
    throw std::runtime_error(text.str());
  }
  std::array<Eigen::Vector2d, 6> sigma;
  int row = 0;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    sigma[b].setZero();
    const int tangent = problem.ParameterBlockTangentSize(blocks[b].x);
    if (const auto* manifold = dynamic_cast<const ScaledEuclidean*>(problem.GetManifold(blocks[b].x))) {
      for (int k = 0; k < tangent; ++k) {
        const int i = manifold->free()[k];
        sigma[b][i] = manifold->scale(i) * std::sqrt(std::max(0.0, (*covariance.covariance)(row + k, row + k)));
      }
    }  // else constant: sigma 0
    row += tangent;
  }

  out.dh_rad = heading[0];
  out.dh_sigma_rad = sigma[0][0];
  out.level_rad = Eigen::Vector2d(level[0], level[1]);
  out.level_sigma_rad = sigma[1];
  out.accel_bias_ne_mps2 = Eigen::Vector2d(accel[0], accel[1]);
  out.accel_bias_sigma_mps2 = sigma[2];
  out.gyro_bias_ne_radps = Eigen::Vector2d(gyro[0], gyro[1]);
  out.gyro_bias_sigma_radps = sigma[3];
  out.position0_ne_m = Eigen::Vector2d(position0[0], position0[1]);
  out.velocity0_ne_mps = Eigen::Vector2d(velocity0[0], velocity0[1]);
  out.gps_sigma_m = gps_sigma_m;
  out.fixes = static_cast<int>(epochs.size());
  out.tilt_steps = static_cast<int>(steps.size());
  out.loss = RobustLossName(batch.loss);

  // Robust weights and the residual RMS (m, of the 2-D |err - model|) at the solution.
  double sum_squared_m2 = 0.0;
  int inliers = 0;
  for (const auto& [cost, parameters] : fix_costs) {
    double r[2];
    if (!cost->Evaluate(parameters.data(), r, nullptr)) {
      throw std::runtime_error("SolveHeadingBatch: a fix residual could not be evaluated at the solution");
    }
    const double s = r[0] * r[0] + r[1] * r[1];
    if (RobustWeight(batch.loss, batch.loss_scale_sigma, s) < 0.5) {
      ++out.downweighted;
    } else {
      sum_squared_m2 += s * gps_sigma_m * gps_sigma_m;
      ++inliers;
    }
  }
  out.residual_rms_m = inliers > 0 ? std::sqrt(sum_squared_m2 / inliers) : 0.0;
  return out;
}

}  // namespace navtwin::inflight
