// Hand-placed IMU calibration (handheld.h).
#include "problems/calibration/handheld.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <ceres/ceres.h>
#include <Eigen/Eigenvalues>

#include "core/config/yaml_config.h"
#include "core/earth.h"
#include "core/imu_error_model.h"
#include "core/io/csv_series.h"
#include "core/io/input_error.h"
#include "core/io/open.h"
#include "core/io/rate_to_increment.h"
#include "core/units.h"
#include "problems/calibration/imu_calibration_residuals.h"

namespace navtwin::calibration {
namespace {

using Triad = Eigen::Matrix<double, kTriadParameters, 1>;

std::string Number(double x) {
  std::ostringstream s;
  s.precision(4);
  s << x;
  return s.str();
}

/// A still interval: samples [first, last], the means of the specific force and rate, and
/// the sigma of each mean's components (the initial period's noise over sqrt(count)).
struct Still {
  std::size_t first = 0, last = 0;
  Eigen::Vector3d f_mean_b = Eigen::Vector3d::Zero();
  double f_sigma = 0.0;  ///< m/s^2, per component of the mean
};

/// Per-sample specific force (dv / dt) and its windowed variance statistic s(t) (handheld.h).
struct Detector {
  std::vector<Eigen::Vector3d> f;
  std::vector<double> s;
  std::size_t half = 1;            ///< half window, samples
  std::size_t init_end = 0;        ///< one past the last sample of the initial still period
  double s_init = 0.0;
  Eigen::Vector3d init_var = Eigen::Vector3d::Zero();  ///< per-axis variance of f at rest
};

/// Variance per axis of f over [a, b) from prefix sums.
Eigen::Vector3d WindowVariance(const std::vector<Eigen::Vector3d>& sum, const std::vector<Eigen::Vector3d>& sum2,
                               std::size_t a, std::size_t b) {
  const double n = static_cast<double>(b - a);
  const Eigen::Vector3d mean = (sum[b] - sum[a]) / n;
  return ((sum2[b] - sum2[a]) / n - mean.cwiseProduct(mean)).cwiseMax(0.0);
}

Detector Detect(const HandheldData& data, const HandheldOptions& options) {
  const std::vector<ImuSample>& imu = data.imu;
  Detector d;
  const std::size_t n = imu.size();
  std::vector<Eigen::Vector3d> sum(n + 1, Eigen::Vector3d::Zero()), sum2(n + 1, Eigen::Vector3d::Zero());
  for (std::size_t k = 0; k < n; ++k) {
    d.f.push_back(imu[k].dv_b_mps / imu[k].dt_s);
    sum[k + 1] = sum[k] + d.f.back();
    sum2[k + 1] = sum2[k] + d.f.back().cwiseProduct(d.f.back());
  }
  const double dt = (imu.back().t_s - imu.front().t_s) / static_cast<double>(n - 1);
  d.half = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(0.5 * options.window_s / dt)));
  const double t_init = imu.front().t_s + options.initial_still_s;
  while (d.init_end < n && imu[d.init_end].t_s <= t_init) ++d.init_end;
  if (d.init_end < 4 * d.half) {
    throw std::runtime_error("handheld calibration: the record has " + std::to_string(d.init_end) +
                             " samples in the initial still period (initial_still_s " +
                             std::to_string(options.initial_still_s) + " s); at least two variance windows are needed");
  }
  d.init_var = WindowVariance(sum, sum2, 0, d.init_end);
  d.s_init = d.init_var.norm();
  d.s.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t a = k >= d.half ? k - d.half : 0, b = std::min(n, k + d.half + 1);
    d.s[k] = WindowVariance(sum, sum2, a, b).norm();
  }
  return d;
}

/// The still intervals below `threshold`, at least min_still_s long, trimmed by half a window.
std::vector<Still> StillIntervals(const HandheldData& data, const Detector& d, double threshold,
                                  const HandheldOptions& options) {
  std::vector<Still> out;
  const std::vector<ImuSample>& imu = data.imu;
  const Eigen::Vector3d noise_std = d.init_var.cwiseSqrt();
  std::size_t k = 0;
  while (k < imu.size()) {
    if (!(d.s[k] < threshold)) {
      ++k;
      continue;
    }
    std::size_t end = k;
    while (end + 1 < imu.size() && d.s[end + 1] < threshold) ++end;
    if (imu[end].t_s - imu[k].t_s >= options.min_still_s && end - k > 2 * d.half + 2) {
      Still s;
      s.first = k + d.half;
      s.last = end - d.half;
      const double count = static_cast<double>(s.last - s.first + 1);
      for (std::size_t j = s.first; j <= s.last; ++j) s.f_mean_b += d.f[j];
      s.f_mean_b /= count;
      s.f_sigma = noise_std.norm() / std::sqrt(3.0 * count);
      out.push_back(s);
    }
    k = end + 1;
  }
  return out;
}

/// |K_a^-1 (mean f_m - b_a)| - g, over the mean's sigma.
class GravityMagnitudeResidual {
 public:
  GravityMagnitudeResidual(const Eigen::Vector3d& f_mean_b, double g_mps2, double sigma_mps2)
      : f_mean_b_(f_mean_b), g_(g_mps2), inv_sigma_(1.0 / sigma_mps2) {}
  template <typename T>
  bool operator()(const T* accel, T* residual) const {
    residual[0] = (CorrectedSpecificForce(accel, Eigen::Matrix<T, 3, 1>(f_mean_b_.cast<T>())).norm() - T(g_)) *
                  T(inv_sigma_);
    return true;
  }

 private:
  Eigen::Vector3d f_mean_b_;
  double g_, inv_sigma_;
};

/// A turn between two still intervals: u_b - R^T u_a over sigma (handheld.h, step 3).
class GravityTurnResidual {
 public:
  GravityTurnResidual(std::vector<ImuSample> samples, const Eigen::Vector3d& u_a, const Eigen::Vector3d& u_b,
                      double sigma)
      : samples_(std::move(samples)), u_a_(u_a), u_b_(u_b), inv_sigma_(1.0 / sigma) {}
  template <typename T>
  bool operator()(const T* gyro, T* residual) const {
    const Eigen::Matrix<T, 3, 3> R = IntegrateCompensatedGyro(samples_, gyro, Eigen::Matrix<T, 3, 3>::Zero().eval());
    const Eigen::Matrix<T, 3, 1> r = (u_b_.cast<T>() - R.transpose() * u_a_.cast<T>()) * T(inv_sigma_);
    for (int i = 0; i < 3; ++i) residual[i] = r(i);
    return true;
  }

 private:
  std::vector<ImuSample> samples_;
  Eigen::Vector3d u_a_, u_b_;
  double inv_sigma_;
};

/// Solves `problem`, and its covariance of `block` (size 12) scaled by the variance factor
/// cost / (dof); throws naming `what` when the solver or the covariance fails.
Eigen::Matrix<double, 12, 12> SolveWithCovariance(ceres::Problem* problem, double* block, int dof, const char* what,
                                                  double* variance_factor) {
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = 100;
  solver.function_tolerance = 1e-14;
  solver.parameter_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, problem, &summary);
  if (!summary.IsSolutionUsable()) throw std::runtime_error(std::string(what) + ": the solver failed: " + summary.message);
  *variance_factor = dof > 0 ? 2.0 * summary.final_cost / dof : 1.0;
  ceres::Covariance::Options options;
  options.algorithm_type = ceres::DENSE_SVD;
  ceres::Covariance covariance(options);
  const std::vector<std::pair<const double*, const double*>> blocks = {{block, block}};
  if (!covariance.Compute(blocks, problem)) {
    throw std::runtime_error(std::string(what) + ": the covariance cannot be computed (rank deficient): the still "
                                                 "orientations or the turns do not determine every parameter");
  }
  Eigen::Matrix<double, 12, 12, Eigen::RowMajor> c;
  covariance.GetCovarianceBlock(block, block, c.data());
  return c * *variance_factor;
}

struct AccelFit {
  Triad accel = Triad::Zero();
  Eigen::Matrix<double, 12, 12> covariance = Eigen::Matrix<double, 12, 12>::Zero();
  std::vector<Still> still;
  double multiple = 0.0, rms_before_mps2 = 0.0, rms_after_mps2 = 0.0;
};

/// The held accelerometer misalignments (the triad's rotation, invisible to magnitudes).
std::vector<int> HeldAccelIndices() {
  return {MisalignmentIndex(0, 1), MisalignmentIndex(0, 2), MisalignmentIndex(1, 2)};
}

AccelFit FitAccelerometer(std::vector<Still> still, double g) {
  AccelFit fit;
  fit.still = std::move(still);
  ceres::Problem problem;
  double before = 0.0;
  for (const Still& s : fit.still) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<GravityMagnitudeResidual, 1, kTriadParameters>(
                                 new GravityMagnitudeResidual(s.f_mean_b, g, s.f_sigma)),
                             nullptr, fit.accel.data());
    before += (s.f_mean_b.norm() - g) * (s.f_mean_b.norm() - g);
  }
  problem.SetManifold(fit.accel.data(), new ceres::SubsetManifold(kTriadParameters, HeldAccelIndices()));
  double s0_sq = 1.0;
  fit.covariance = SolveWithCovariance(&problem, fit.accel.data(), static_cast<int>(fit.still.size()) - 9,
                                       "handheld accelerometer calibration", &s0_sq);
  double after = 0.0;
  for (const Still& s : fit.still) {
    const double r = CorrectedSpecificForce(fit.accel.data(), Eigen::Vector3d(s.f_mean_b)).norm() - g;
    after += r * r;
  }
  const double m = static_cast<double>(fit.still.size());
  fit.rms_before_mps2 = std::sqrt(before / m);
  fit.rms_after_mps2 = std::sqrt(after / m);
  return fit;
}

/// The threshold multiple whose accelerometer fit leaves the smallest residual RMS, among
/// those giving at least 10 intervals (9 unknowns and one degree of freedom).
/// The smallest eigenvalue of the scatter of the still intervals' gravity directions (1/3
/// for directions all over the sphere, 0 when they lie in one plane or are all alike).
double DirectionSpread(const std::vector<Still>& still) {
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Still& s : still) scatter += s.f_mean_b.normalized() * s.f_mean_b.normalized().transpose();
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter / static_cast<double>(still.size())).eigenvalues()(0);
}

/// Directions whose scatter's smallest eigenvalue is below this (a cone of about 10 deg
/// about one plane) cannot separate the 9 accelerometer unknowns.
constexpr double kMinDirectionSpread = 0.01;

AccelFit BestAccelerometerFit(const HandheldData& data, const Detector& d, const HandheldOptions& options, double g) {
  AccelFit best;
  best.rms_after_mps2 = std::numeric_limits<double>::infinity();
  std::size_t most = 0;
  double widest = 0.0;
  for (const double k : options.threshold_multiples) {
    std::vector<Still> still = StillIntervals(data, d, k * d.s_init, options);
    most = std::max(most, still.size());
    if (still.size() < 10) continue;
    const double spread = DirectionSpread(still);
    widest = std::max(widest, spread);
    if (spread < kMinDirectionSpread) continue;
    AccelFit fit = FitAccelerometer(std::move(still), g);
    fit.multiple = k;
    if (fit.rms_after_mps2 < best.rms_after_mps2) best = std::move(fit);
  }
  if (most < 10) {
    throw std::runtime_error("handheld calibration: at most " + std::to_string(most) +
                             " still intervals found; at least 10 orientations are needed (the accelerometer has 9 "
                             "unknowns): put the sensor down in more orientations, each still for 2 s or more");
  }
  if (best.still.empty()) {
    throw std::runtime_error("handheld calibration: " + std::to_string(most) +
                             " still intervals, but in too few distinct orientations (the smallest eigenvalue of "
                             "their gravity directions' scatter is " + Number(widest) + ", below " +
                             Number(kMinDirectionSpread) + "): put the sensor down with every axis up and down");
  }
  return best;
}

struct GyroFit {
  Triad gyro = Triad::Zero();
  Eigen::Matrix<double, 12, 12> covariance = Eigen::Matrix<double, 12, 12>::Zero();
  int turns = 0;
  double rms_before_rad = 0.0, rms_after_rad = 0.0;
};

/// The gravity direction seen by the calibrated accelerometer in a still interval.
Eigen::Vector3d GravityDirection(const Triad& accel, const Still& s) {
  return CorrectedSpecificForce(accel.data(), Eigen::Vector3d(s.f_mean_b)).normalized();
}

GyroFit FitGyroscope(const HandheldData& data, const Detector& d, const AccelFit& accel, double g) {
  GyroFit fit;
  const std::vector<ImuSample>& imu = data.imu;
  // Bias: the mean rate over the initial still period; its sigma the noise over sqrt(N).
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum2 = Eigen::Vector3d::Zero();
  double time = 0.0;
  for (std::size_t k = 0; k < d.init_end; ++k) {
    const Eigen::Vector3d w = imu[k].dtheta_b_rad / imu[k].dt_s;
    sum += imu[k].dtheta_b_rad;
    sum2 += w.cwiseProduct(w);
    time += imu[k].dt_s;
  }
  const double n_init = static_cast<double>(d.init_end);
  const Eigen::Vector3d bias = sum / time;
  const Eigen::Vector3d rate_var = (sum2 / n_init - bias.cwiseProduct(bias)).cwiseMax(0.0);
  fit.gyro.tail<3>() = bias;
  ceres::Problem problem;
  const Triad start = fit.gyro;
  double before = 0.0;
  for (std::size_t i = 0; i + 1 < accel.still.size(); ++i) {
    const Still& a = accel.still[i];
    const Still& b = accel.still[i + 1];
    std::vector<ImuSample> turn(imu.begin() + static_cast<long>(a.last) + 1, imu.begin() + static_cast<long>(b.first));
    if (turn.empty()) continue;
    const double turn_s = imu[b.first].t_s - imu[a.last].t_s;
    // Direction noise of both means, and the gyro's white noise integrated over the turn.
    const double sigma = std::sqrt((a.f_sigma * a.f_sigma + b.f_sigma * b.f_sigma) / (g * g) +
                                   rate_var.mean() * imu[a.last].dt_s * turn_s);
    const Eigen::Vector3d u_a = GravityDirection(accel.accel, a), u_b = GravityDirection(accel.accel, b);
    auto* residual = new GravityTurnResidual(std::move(turn), u_a, u_b, sigma);
    Eigen::Vector3d r0;
    (*residual)(start.data(), r0.data());
    before += (r0 * sigma).squaredNorm();
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<GravityTurnResidual, 3, kTriadParameters>(residual),
                             nullptr, fit.gyro.data());
    ++fit.turns;
  }
  if (fit.turns < 6) {
    throw std::runtime_error("handheld calibration: " + std::to_string(fit.turns) +
                             " turns between still intervals; at least 6 are needed for the gyroscope's 9 unknowns");
  }
  problem.SetManifold(fit.gyro.data(), new ceres::SubsetManifold(kTriadParameters, {9, 10, 11}));
  double s0_sq = 1.0;
  fit.covariance = SolveWithCovariance(&problem, fit.gyro.data(), 2 * fit.turns - 9,
                                       "handheld gyroscope calibration", &s0_sq);
  for (int i = 0; i < 3; ++i) fit.covariance(9 + i, 9 + i) = rate_var(i) / n_init;  // the bias's own sigma
  double after = 0.0;
  for (std::size_t i = 0; i + 1 < accel.still.size(); ++i) {
    const Still& a = accel.still[i];
    const Still& b = accel.still[i + 1];
    const std::vector<ImuSample> turn(imu.begin() + static_cast<long>(a.last) + 1, imu.begin() + static_cast<long>(b.first));
    if (turn.empty()) continue;
    const Eigen::Matrix3d R = IntegrateCompensatedGyro(turn, fit.gyro.data(), Eigen::Matrix3d::Zero().eval());
    after += (GravityDirection(accel.accel, b) - R.transpose() * GravityDirection(accel.accel, a)).squaredNorm();
  }
  fit.rms_before_rad = std::sqrt(before / (2.0 * fit.turns));
  fit.rms_after_rad = std::sqrt(after / (2.0 * fit.turns));
  return fit;
}

/// The result in the shared layout: estimated names, their covariance, the held ones named.
ImuCalibrationResult MakeHandheldResult(const AccelFit& a, const GyroFit& gfit) {
  ImuCalibrationResult r;
  r.calibration.accel = a.accel;
  r.calibration.gyro = gfit.gyro;
  Triad accel_sigma = a.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (const int i : HeldAccelIndices()) accel_sigma(i) = std::numeric_limits<double>::quiet_NaN();
  r.calibration.accel_sigma = accel_sigma;
  r.calibration.gyro_sigma = Triad(gfit.covariance.diagonal().cwiseMax(0.0).cwiseSqrt());
  std::vector<std::pair<int, int>> estimated;  // (block 0 accel / 1 gyro, index)
  for (int i = 0; i < kTriadParameters; ++i) {
    if (std::isfinite(accel_sigma(i))) estimated.push_back({0, i});
  }
  for (int i = 0; i < kTriadParameters; ++i) estimated.push_back({1, i});
  r.covariance = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(estimated.size()),
                                       static_cast<Eigen::Index>(estimated.size()));
  for (std::size_t p = 0; p < estimated.size(); ++p) {
    r.estimated.push_back(TriadParameterName(estimated[p].first == 0 ? "accel" : "gyro", estimated[p].second));
    for (std::size_t q = 0; q < estimated.size(); ++q) {
      if (estimated[p].first != estimated[q].first) continue;  // the two fits are separate
      const auto& c = estimated[p].first == 0 ? a.covariance : gfit.covariance;
      r.covariance(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(q)) = c(estimated[p].second, estimated[q].second);
    }
  }
  for (const int i : HeldAccelIndices()) {
    r.unobservable.push_back(TriadParameterName("accel", i) +
                             ": a rotation of the accelerometer triad is invisible to gravity magnitudes (held at 0: "
                             "the body axes are the accelerometer's)");
  }
  r.unobservable.push_back("g_sensitivity.*: not estimated by the handheld method (held at 0)");
  r.positions = static_cast<int>(a.still.size());
  r.accel_residual_rms_mps2 = a.rms_after_mps2;
  r.gyro_residual_rms_rad_per_s = std::numeric_limits<double>::quiet_NaN();  // turns give directions, not rates
  r.notes.push_back("gravity magnitude residual RMS over " + std::to_string(a.still.size()) + " still intervals: before " +
                    Number(a.rms_before_mps2 / kMilliG_mps2) + " mg, after " + Number(a.rms_after_mps2 / kMilliG_mps2) +
                    " mg");
  r.notes.push_back("gravity direction after " + std::to_string(gfit.turns) +
                    " turns (gyro integration residual), RMS per component: before (bias only) " +
                    Number(gfit.rms_before_rad * 1e3) + " mrad, after " + Number(gfit.rms_after_rad * 1e3) + " mrad");
  return r;
}

/// The raw-count CSV of a record's `counts` (ReadHandheldRecord) as increments.
std::vector<ImuSample> ReadCountsCsv(const std::string& path, double gyro_rad_s_per_count, double accel_mps2_per_count) {
  std::vector<ScalarSeries> columns;
  for (const char* stem : {"gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z"}) {
    columns.push_back(ReadScalarSeriesCsv(path, stem, {{"_counts", 1.0}}));
  }
  std::vector<ImuSample> out;
  RateToIncrement increments;
  for (std::size_t k = 0; k < columns.front().t_s.size(); ++k) {
    RateSample r;
    r.t_s = columns.front().t_s[k];
    for (int i = 0; i < 3; ++i) {
      r.gyro_radps(i) = columns[i].value[k] * gyro_rad_s_per_count;
      r.acc_mps2(i) = columns[3 + i].value[k] * accel_mps2_per_count;
    }
    ImuSample s;
    if (increments.Add(r, &s)) out.push_back(s);
  }
  return out;
}

}  // namespace

HandheldData ReadHandheldRecord(const std::string& record_path, HandheldOptions* options) {
  const ConfigNode root = LoadYamlFile(record_path);
  root.RequireKeys({"imu", "latitude_deg", "height_m", "initial_still_s", "counts"});
  if (!root.Has("imu")) root.Fail("imu", "missing: the IMU file of the hand-placed sequence");
  if (!root.Has("latitude_deg")) root.Fail("latitude_deg", "missing: the latitude of the place (local gravity)");
  HandheldData data;
  data.latitude_rad = root.Double("latitude_deg", 0.0, -90.0, 90.0) * kDegToRad;
  data.height_m = root.Double("height_m", 0.0, -1e4, 1e5);
  options->initial_still_s = root.Positive("initial_still_s", options->initial_still_s);
  std::filesystem::path imu(root.String("imu", ""));
  if (imu.is_relative()) imu = std::filesystem::path(record_path).parent_path() / imu;
  data.imu_path = imu.string();
  if (root.Has("counts")) {
    const ConfigNode counts = root.Child("counts");
    counts.RequireKeys({"gyro_rad_s_per_count", "accel_mps2_per_count"});
    for (const char* key : {"gyro_rad_s_per_count", "accel_mps2_per_count"}) {
      if (!counts.Has(key)) counts.Fail(key, "required: the sensor's nominal sensitivity");
    }
    data.imu = ReadCountsCsv(data.imu_path, counts.Positive("gyro_rad_s_per_count", 1.0),
                             counts.Positive("accel_mps2_per_count", 1.0));
  } else {
    data.imu = ReadAll(*OpenImu(data.imu_path));
  }
  return data;
}

ImuCalibrationResult CalibrateHandheld(const HandheldData& data, const HandheldOptions& options,
                                       StillDetection* detection) {
  if (data.imu.size() < 100) {
    throw InputError(data.imu_path, 0, "", "a handheld calibration needs a record of minutes, got " +
                                               std::to_string(data.imu.size()) + " IMU samples");
  }
  const double g = wgs84::NormalGravity(data.latitude_rad, data.height_m);
  const Detector d = Detect(data, options);
  const AccelFit accel = BestAccelerometerFit(data, d, options, g);
  const GyroFit gyro = FitGyroscope(data, d, accel, g);
  ImuCalibrationResult r = MakeHandheldResult(accel, gyro);
  r.notes.insert(r.notes.begin(), "still detector: threshold " + Number(accel.multiple) + " x the initial period's " +
                                      Number(d.s_init) + " (m/s^2)^2 (window " + Number(options.window_s) + " s), " +
                                      std::to_string(accel.still.size()) + " still intervals");
  if (detection != nullptr) *detection = {accel.multiple * d.s_init, accel.multiple, static_cast<int>(accel.still.size())};
  return r;
}

}  // namespace navtwin::calibration
