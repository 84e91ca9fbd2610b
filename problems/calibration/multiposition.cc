// Multi-position IMU calibration: the batch (Ceres) and recursive (information-form Kalman
// filter) estimators of multiposition.h, the observability analysis shared by both, and the
// record reader. Method and maths: docs/calibration-imu.md.
#include "problems/calibration/multiposition.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Cholesky>

#include "core/earth.h"
#include "core/io/input_error.h"
#include "core/io/open.h"
#include "core/linalg.h"
#include "core/rotation.h"
#include "problems/calibration/imu_calibration_residuals.h"

namespace navtwin::calibration {
namespace {

constexpr int kMinPositions = 6;
constexpr int kAccel0 = 0;                          ///< accel triad in the 33-vector
constexpr int kGyro0 = kTriadParameters;            ///< gyro triad
constexpr int kG0 = 2 * kTriadParameters;           ///< g-sensitivity
constexpr int kAll = kG0 + kGSensitivityParameters; ///< 33
using VectorP = Eigen::Matrix<double, kAll, 1>;
using MatrixP = Eigen::Matrix<double, kAll, kAll>;

/// Per-sample scatter floors (noise-free data): they only set the relative weight of the
/// accelerometer and gyro residuals, in the ratio of a good tactical IMU's noise.
constexpr double kAccelScatterFloor_mps2 = 1e-7;
constexpr double kGyroScatterFloor_radps = 1e-9;
/// A direction of the column-normalised information matrix with a relative eigenvalue
/// below this is not observed (condition number 1e10: sigma amplified by 1e5).
constexpr double kNullEigenvalueRatio = 1e-10;
/// Scale factors and misalignments whose a-priori sigma from the data exceeds this
/// (1 %, 10 mrad) are reported as not observed rather than as numbers that mean nothing.
constexpr double kMaxMeaningfulSigma = 1e-2;
/// Prior sigmas of the recursive filter (far above any real IMU error, so that the prior
/// carries no weight once a parameter is observed): scale/misalignment 10 %, accel bias
/// 1 m/s^2, gyro bias 0.01 rad/s (2000 deg/h), g-sensitivity 1e-3 (rad/s)/(m/s^2).
/// Gauss-Newton passes over the moves so far at each new position of the recursive form.
constexpr int kRelinearisations = 2;
constexpr double kPriorScale = 0.1, kPriorAccelBias = 1.0, kPriorGyroBias = 1e-2, kPriorG = 1e-3;

const char* const kAxisName[3] = {"x", "y", "z"};

std::string ParameterName(int i) {
  if (i < kGyro0) return TriadParameterName("accel", i - kAccel0);
  if (i < kG0) return TriadParameterName("gyro", i - kGyro0);
  return GSensitivityParameterName(i - kG0);
}

bool IsBias(int i) { return i < kG0 && (i % kTriadParameters) >= 9; }
bool IsScaleOrMisalignment(int i) { return i < kG0 && (i % kTriadParameters) < 9; }

/// The input axis (column of K or G) a parameter multiplies; -1 for biases.
int InputAxis(int i) {
  if (i >= kG0) return (i - kG0) % 3;
  const int k = i % kTriadParameters;
  if (k < 3) return k;
  if (k >= 9) return -1;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (c != r && MisalignmentIndex(r, c) == k) return c;
  return -1;
}

double PriorSigma(int i) {
  if (IsScaleOrMisalignment(i)) return kPriorScale;
  if (i >= kG0) return kPriorG;
  return i < kGyro0 ? kPriorAccelBias : kPriorGyroBias;
}

/// One static position: the window used and the means over it.
struct Hold {
  double t0_s = 0.0, t1_s = 0.0;     ///< window (trimmed by settle_s)
  std::size_t first = 0, last = 0;   ///< sample indices of the window (inclusive)
  int used = 0;                      ///< samples in the means (saturated ones left out)
  Eigen::Matrix3d R_n_b = Eigen::Matrix3d::Identity();
  Eigen::Vector3d f_true_b, omega_true_b, f_mean_b, omega_mean_b;
};

enum class Kind { kAccel, kGyro, kMove };

/// One weighted residual block and the position it belongs to.
struct Measurement {
  Kind kind;
  int position;
  std::unique_ptr<ceres::CostFunction> cost;
  int move = -1;  ///< index into Residuals::moves for kMove
};

/// Everything both estimators need: holds, moves, the residual blocks in schedule order.
struct Residuals {
  std::vector<Hold> holds;
  std::vector<std::unique_ptr<GyroMove>> moves;
  std::vector<Measurement> measurements;
  std::vector<std::string> notes;
  bool estimate_g = true;
};

std::string Seconds(double t) {
  std::ostringstream s;
  s.precision(6);
  s << t;
  return s.str();
}

Residuals BuildResiduals(const MultiPositionData& data, const MultiPositionOptions& options) {
  if (!(options.settle_s >= 0.0) || !std::isfinite(options.settle_s)) {
    throw std::invalid_argument("CalibrateMultiPosition: settle_s must be finite and >= 0");
  }
  const sim::MultiPositionRig rig(data.schedule);
  const std::vector<sim::StaticInterval>& intervals = rig.static_intervals();
  const int count = static_cast<int>(intervals.size());
  if (count < kMinPositions) {
    throw std::runtime_error("multi-position calibration: the schedule has " + std::to_string(count) +
                             " static positions; at least " + std::to_string(kMinPositions) +
                             " are needed (12 accelerometer unknowns, 3 per position)");
  }
  const std::vector<ImuSample>& imu = data.imu;
  const std::string source = data.imu_path.empty() ? std::string("the IMU data") : data.imu_path;
  if (imu.empty()) throw std::runtime_error("multi-position calibration: no IMU samples in " + source);

  Residuals res;
  res.estimate_g = options.estimate_g_sensitivity;
  const double g = wgs84::NormalGravity(data.latitude_rad, data.height_m);
  const Eigen::Vector3d g_n(0.0, 0.0, g);
  const Eigen::Vector3d omega_ie_n = wgs84::EarthRateNed(data.latitude_rad);
  const auto saturated = [&options](const ImuSample& s) {
    // A sensor's range is per axis: any axis at or beyond it.
    return (options.accel_saturation_mps2 > 0.0 &&
            s.dv_b_mps.cwiseAbs().maxCoeff() >= options.accel_saturation_mps2 * s.dt_s) ||
           (options.gyro_saturation_rad_per_s > 0.0 &&
            s.dtheta_b_rad.cwiseAbs().maxCoeff() >= options.gyro_saturation_rad_per_s * s.dt_s);
  };

  // Holds: the samples whose interval (t - dt, t] lies inside the trimmed window.
  constexpr double kEps_s = 1e-9;
  int saturated_total = 0;
  Eigen::Vector3d ss_a = Eigen::Vector3d::Zero(), ss_g = Eigen::Vector3d::Zero();
  double dof = 0.0;
  for (int j = 0; j < count; ++j) {
    Hold h;
    h.t0_s = intervals[j].start_s + options.settle_s;
    h.t1_s = intervals[j].end_s - options.settle_s;
    const auto begin = std::partition_point(imu.begin(), imu.end(), [&h](const ImuSample& s) {
      return s.t_s - s.dt_s < h.t0_s - kEps_s;
    });
    const auto end = std::partition_point(begin, imu.end(), [&h](const ImuSample& s) { return s.t_s <= h.t1_s + kEps_s; });
    const std::string where = "position " + std::to_string(j + 1) + " (hold " + Seconds(intervals[j].start_s) + " to " +
                              Seconds(intervals[j].end_s) + " s, " + Seconds(options.settle_s) + " s settling at each end)";
    if (!(h.t1_s > h.t0_s) || begin == end) {
      throw std::runtime_error("multi-position calibration: no IMU samples in " + source + " within " + where);
    }
    h.first = static_cast<std::size_t>(begin - imu.begin());
    h.last = static_cast<std::size_t>(end - imu.begin()) - 1;
    Eigen::Vector3d dv = Eigen::Vector3d::Zero(), dth = Eigen::Vector3d::Zero();
    double T = 0.0;
    for (std::size_t i = h.first; i <= h.last; ++i) {
      if (saturated(imu[i])) {
        ++saturated_total;
        continue;
      }
      dv += imu[i].dv_b_mps;
      dth += imu[i].dtheta_b_rad;
      T += imu[i].dt_s;
      ++h.used;
    }
    if (h.used == 0 || !(T > 0.0)) {
      throw std::runtime_error("multi-position calibration: every sample of " + where + " in " + source +
                               " is saturated");
    }
    h.f_mean_b = dv / T;
    h.omega_mean_b = dth / T;
    for (std::size_t i = h.first; i <= h.last; ++i) {
      if (saturated(imu[i]) || !(imu[i].dt_s > 0.0)) continue;
      ss_a += (imu[i].dv_b_mps / imu[i].dt_s - h.f_mean_b).cwiseAbs2();
      ss_g += (imu[i].dtheta_b_rad / imu[i].dt_s - h.omega_mean_b).cwiseAbs2();
    }
    dof += h.used - 1;
    const StaticTruth truth = StaticTruthAt(intervals[j].euler_rad, data.latitude_rad, data.height_m);
    h.R_n_b = truth.R_n_b;
    h.f_true_b = truth.f_b_mps2;
    h.omega_true_b = truth.omega_ib_b_rad_per_s;
    res.holds.push_back(h);
  }
  if (saturated_total > 0) {
    res.notes.push_back(std::to_string(saturated_total) + " saturated samples left out of the position means");
  }
  // Per-sample noise of each axis, pooled over the holds (within-hold scatter).
  const Eigen::Vector3d s_a = dof > 0.0 ? Eigen::Vector3d((ss_a / dof).cwiseSqrt()) : Eigen::Vector3d::Zero();
  const Eigen::Vector3d s_g = dof > 0.0 ? Eigen::Vector3d((ss_g / dof).cwiseSqrt()) : Eigen::Vector3d::Zero();
  const Eigen::Vector3d sa = s_a.cwiseMax(kAccelScatterFloor_mps2);
  const Eigen::Vector3d sg = s_g.cwiseMax(kGyroScatterFloor_radps);
  const double sg_rms = std::sqrt(sg.squaredNorm() / 3.0);

  for (int j = 0; j < count; ++j) {
    const Hold& h = res.holds[j];
    if (j > 0) {
      // The move from hold j-1 to hold j: samples over (t_a, t_b].
      const Hold& prev = res.holds[j - 1];
      auto move = std::make_unique<GyroMove>();
      bool usable = prev.last + 1 < h.first;
      double sum_dt2 = 0.0;
      for (std::size_t i = prev.last + 1; usable && i < h.first; ++i) {
        if (saturated(imu[i])) {
          usable = false;
          res.notes.push_back("move " + std::to_string(j) + " -> " + std::to_string(j + 1) +
                              " left out: a saturated sample at t = " + Seconds(imu[i].t_s) + " s");
        }
        // G multiplies the true specific force: at the table centre f_b = -R_b_n g_n.
        ImuSample m = imu[i];
        const Eigen::Vector3d e = rig.Euler_rad(m.t_s - 0.5 * m.dt_s);
        m.dv_b_mps = -DcmFromEuler(e.x(), e.y(), e.z()).transpose() * g_n * m.dt_s;
        move->samples.push_back(m);
        sum_dt2 += m.dt_s * m.dt_s;
      }
      if (usable) {
        const double t_a = imu[prev.last].t_s, t_b = imu[h.first - 1].t_s;
        move->R_true = prev.R_n_b.transpose() * ExpSO3(Eigen::Vector3d(omega_ie_n * (t_b - t_a))) * h.R_n_b;
        move->sigma_rad = sg_rms * std::sqrt(sum_dt2);  // white rate noise integrated over the move
        Measurement m{Kind::kMove, j, std::make_unique<GyroMoveCost>(move.get()), static_cast<int>(res.moves.size())};
        res.moves.push_back(std::move(move));
        res.measurements.push_back(std::move(m));
      }
    }
    const double root_n = std::sqrt(static_cast<double>(h.used));
    res.measurements.push_back(
        {Kind::kAccel, j,
         std::make_unique<ceres::AutoDiffCostFunction<StaticAccelResidual, 3, kTriadParameters>>(
             new StaticAccelResidual(h.f_true_b, h.f_mean_b, sa / root_n)),
         -1});
    res.measurements.push_back(
        {Kind::kGyro, j,
         std::make_unique<ceres::AutoDiffCostFunction<StaticGyroResidual, 3, kTriadParameters, kGSensitivityParameters>>(
             new StaticGyroResidual(h.omega_true_b, h.f_true_b, h.omega_mean_b, sg / root_n)),
         -1});
  }
  return res;
}

/// The parameter blocks of a measurement within the 33-vector.
std::vector<int> BlockOffsets(Kind kind) {
  if (kind == Kind::kAccel) return {kAccel0};
  return {kGyro0, kG0};
}

/// Weighted residual and its Jacobian (3 x 33) at x.
void Linearize(const Measurement& m, const VectorP& x, Eigen::Vector3d* r, Eigen::Matrix<double, 3, kAll>* H) {
  const std::vector<int> offsets = BlockOffsets(m.kind);
  std::vector<const double*> params;
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor>> jac;
  std::vector<double*> jac_ptr;
  const std::vector<int32_t>& sizes = m.cost->parameter_block_sizes();
  for (std::size_t b = 0; b < offsets.size(); ++b) {
    params.push_back(x.data() + offsets[b]);
    jac.emplace_back(3, sizes[b]);
  }
  for (auto& j : jac) jac_ptr.push_back(j.data());
  m.cost->Evaluate(params.data(), r->data(), H != nullptr ? jac_ptr.data() : nullptr);
  if (H == nullptr) return;
  H->setZero();
  for (std::size_t b = 0; b < offsets.size(); ++b) H->block(0, offsets[b], 3, sizes[b]) = jac[b];
}

/// Parameters to hold at 0 and why (shared by the batch and the recursive form).
/// candidates: parameters estimated at all; J: the weighted Jacobian of every residual.
struct Observability {
  std::vector<bool> held = std::vector<bool>(kAll, false);
  std::vector<std::string> reasons;
};

Observability AnalyseObservability(const Eigen::MatrixXd& J, const std::vector<bool>& candidate) {
  Observability o;
  for (int i = 0; i < kAll; ++i) o.held[i] = !candidate[i];
  const Eigen::VectorXd norms = J.colwise().norm();
  // 1. Parameters no residual depends on: nothing excites their input axis.
  for (int i = 0; i < kAll; ++i) {
    if (o.held[i] || norms(i) > 0.0) continue;
    o.held[i] = true;
    const std::string axis = InputAxis(i) >= 0 ? kAxisName[InputAxis(i)] : "?";
    if (i >= kGyro0 && i < kG0) {
      o.reasons.push_back(ParameterName(i) + ": no position or move turns the IMU about " + axis);
    } else {
      o.reasons.push_back(ParameterName(i) + ": no position puts gravity on " + axis);
    }
  }
  const auto active = [&o]() {
    std::vector<int> a;
    for (int i = 0; i < kAll; ++i)
      if (!o.held[i]) a.push_back(i);
    return a;
  };
  // 2. Directions the data cannot separate (column-normalised information matrix).
  for (;;) {
    const std::vector<int> a = active();
    if (a.empty()) break;
    Eigen::MatrixXd Jn(J.rows(), static_cast<Eigen::Index>(a.size()));
    for (std::size_t k = 0; k < a.size(); ++k) Jn.col(k) = J.col(a[k]) / norms(a[k]);
    const SymmetricEigen eig = SymmetricEigenDecomposition(Jn.transpose() * Jn);
    const double largest = eig.values.maxCoeff();
    if (!(eig.values(0) < kNullEigenvalueRatio * largest)) break;
    const Eigen::VectorXd v = eig.vectors.col(0);
    const double vmax = v.cwiseAbs().maxCoeff();
    // Hold a scale factor, misalignment or g-sensitivity before a bias.
    int pick = -1;
    for (int pass = 0; pass < 2 && pick < 0; ++pass) {
      double best = 0.0;
      for (std::size_t k = 0; k < a.size(); ++k) {
        if (pass == 0 && IsBias(a[k])) continue;
        if (std::abs(v(k)) > 0.1 * vmax && std::abs(v(k)) > best) {
          best = std::abs(v(k));
          pick = static_cast<int>(k);
        }
      }
    }
    std::string with;
    for (std::size_t k = 0; k < a.size(); ++k) {
      if (static_cast<int>(k) != pick && std::abs(v(k)) > 0.1 * vmax) with += (with.empty() ? "" : ", ") + ParameterName(a[k]);
    }
    o.held[a[pick]] = true;
    o.reasons.push_back(ParameterName(a[pick]) + ": not separable from " + (with.empty() ? "the others" : with) +
                        " with these positions");
  }
  // 3. Scale factors and misalignments the data hardly excite (a-priori sigma > 1 %).
  for (;;) {
    const std::vector<int> a = active();
    if (a.empty()) break;
    Eigen::MatrixXd Ja(J.rows(), static_cast<Eigen::Index>(a.size()));
    for (std::size_t k = 0; k < a.size(); ++k) Ja.col(k) = J.col(a[k]) / norms(a[k]);
    const Eigen::MatrixXd C = (Ja.transpose() * Ja).ldlt().solve(Eigen::MatrixXd::Identity(a.size(), a.size()));
    int worst = -1;
    double worst_sigma = kMaxMeaningfulSigma;
    for (std::size_t k = 0; k < a.size(); ++k) {
      const double sigma = std::sqrt(std::max(0.0, C(k, k))) / norms(a[k]);
      if (IsScaleOrMisalignment(a[k]) && sigma > worst_sigma) {
        worst_sigma = sigma;
        worst = static_cast<int>(k);
      }
    }
    if (worst < 0) break;
    o.held[a[worst]] = true;
    std::ostringstream why;
    why.precision(3);
    const bool scale = a[worst] % kTriadParameters < 3;
    why << ParameterName(a[worst]) << ": hardly excited (sigma " << worst_sigma * (scale ? 100.0 : 1e3)
        << (scale ? " %" : " mrad") << " from these data, limit " << kMaxMeaningfulSigma * (scale ? 100.0 : 1e3)
        << (scale ? " %" : " mrad") << "); turn the IMU about " << kAxisName[InputAxis(a[worst])];
    o.reasons.push_back(why.str());
  }
  return o;
}

std::vector<bool> Candidates(bool estimate_g) {
  std::vector<bool> c(kAll, true);
  for (int i = kG0; i < kAll; ++i) c[i] = estimate_g;
  return c;
}

/// Dense weighted Jacobian of the given measurements at x.
Eigen::MatrixXd StackJacobian(const std::vector<const Measurement*>& ms, const VectorP& x) {
  Eigen::MatrixXd J(3 * static_cast<Eigen::Index>(ms.size()), kAll);
  for (std::size_t k = 0; k < ms.size(); ++k) {
    Eigen::Vector3d r;
    Eigen::Matrix<double, 3, kAll> H;
    Linearize(*ms[k], x, &r, &H);
    J.block<3, kAll>(3 * static_cast<Eigen::Index>(k), 0) = H;
  }
  return J;
}

/// Fills the estimates, sigmas (NaN where not estimated), residual RMS and counts.
ImuCalibrationResult MakeResult(const Residuals& res, const std::vector<const Measurement*>& ms, const VectorP& x,
                                const MatrixP& covariance, const Observability& o, int positions) {
  ImuCalibrationResult out;
  out.calibration.accel = x.segment<kTriadParameters>(kAccel0);
  out.calibration.gyro = x.segment<kTriadParameters>(kGyro0);
  out.calibration.g_sensitivity = x.segment<kGSensitivityParameters>(kG0);
  VectorP sigma = VectorP::Constant(std::numeric_limits<double>::quiet_NaN());
  std::vector<int> est;
  for (int i = 0; i < kAll; ++i) {
    if (o.held[i]) continue;
    est.push_back(i);
    sigma(i) = std::sqrt(std::max(0.0, covariance(i, i)));
    out.estimated.push_back(ParameterName(i));
  }
  out.covariance.resize(static_cast<Eigen::Index>(est.size()), static_cast<Eigen::Index>(est.size()));
  for (std::size_t a = 0; a < est.size(); ++a)
    for (std::size_t b = 0; b < est.size(); ++b) out.covariance(a, b) = covariance(est[a], est[b]);
  out.calibration.accel_sigma = sigma.segment<kTriadParameters>(kAccel0);
  out.calibration.gyro_sigma = sigma.segment<kTriadParameters>(kGyro0);
  if (res.estimate_g) out.calibration.g_sensitivity_sigma = sigma.segment<kGSensitivityParameters>(kG0);
  out.unobservable = o.reasons;
  double ss_a = 0.0, ss_g = 0.0;
  int n_a = 0, n_g = 0;
  for (const Measurement* m : ms) {
    if (m->kind == Kind::kMove) continue;
    const Hold& h = res.holds[m->position];
    if (m->kind == Kind::kAccel) {
      ss_a += (MeasuredSpecificForce(x.data() + kAccel0, h.f_true_b) - h.f_mean_b).squaredNorm();
      n_a += 3;
    } else {
      ss_g += (MeasuredRate(x.data() + kGyro0, x.data() + kG0, h.omega_true_b, h.f_true_b) - h.omega_mean_b).squaredNorm();
      n_g += 3;
    }
  }
  out.accel_residual_rms_mps2 = n_a > 0 ? std::sqrt(ss_a / n_a) : 0.0;
  out.gyro_residual_rms_rad_per_s = n_g > 0 ? std::sqrt(ss_g / n_g) : 0.0;
  out.positions = positions;
  out.notes = res.notes;
  for (int i = 0; i < positions && i < static_cast<int>(res.holds.size()); ++i) {
    const Hold& h = res.holds[i];
    StaticPosition p;
    p.t0_s = h.t0_s;
    p.t1_s = h.t1_s;
    p.f_true_b_mps2 = h.f_true_b;
    p.f_mean_b_mps2 = h.f_mean_b;
    p.omega_true_b_radps = h.omega_true_b;
    p.omega_mean_b_radps = h.omega_mean_b;
    out.static_positions.push_back(p);
  }
  out.residuals = StaticResiduals(out.calibration, out.static_positions);
  return out;
}

/// Sum of squared weighted residuals at x.
double SumOfSquares(const std::vector<const Measurement*>& ms, const VectorP& x) {
  double ss = 0.0;
  for (const Measurement* m : ms) {
    Eigen::Vector3d r;
    Linearize(*m, x, &r, nullptr);
    ss += r.squaredNorm();
  }
  return ss;
}

/// A-posteriori variance factor sum r^2 / (m - n) (1 when there is no redundancy).
double VarianceFactor(double ss, int residuals, int estimated, std::vector<std::string>* notes) {
  if (residuals <= estimated) {
    notes->push_back("no redundancy (" + std::to_string(residuals) + " residuals for " + std::to_string(estimated) +
                     " parameters): sigma from the within-hold noise alone");
    return 1.0;
  }
  return ss / (residuals - estimated);
}

std::vector<const Measurement*> Pointers(const Residuals& res) {
  std::vector<const Measurement*> ms;
  for (const Measurement& m : res.measurements) ms.push_back(&m);
  return ms;
}

}  // namespace

StaticTruth StaticTruthAt(const Eigen::Vector3d& euler_rad, double latitude_rad, double height_m) {
  StaticTruth truth;
  truth.R_n_b = DcmFromEuler(euler_rad.x(), euler_rad.y(), euler_rad.z());
  const Eigen::Vector3d g_n(0.0, 0.0, wgs84::NormalGravity(latitude_rad, height_m));
  truth.f_b_mps2 = -truth.R_n_b.transpose() * g_n;  // at rest f_n = -g_n
  truth.omega_ib_b_rad_per_s = truth.R_n_b.transpose() * wgs84::EarthRateNed(latitude_rad);
  return truth;
}

// ------------------------------------------------------------------------ batch

ImuCalibrationResult CalibrateMultiPosition(const MultiPositionData& data, const MultiPositionOptions& options) {
  Residuals res = BuildResiduals(data, options);
  const std::vector<const Measurement*> ms = Pointers(res);
  VectorP x = VectorP::Zero();
  const Observability o = AnalyseObservability(StackJacobian(ms, x), Candidates(res.estimate_g));

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  double* accel = x.data() + kAccel0;
  double* gyro = x.data() + kGyro0;
  double* g9 = x.data() + kG0;
  for (const Measurement& m : res.measurements) {
    if (m.kind == Kind::kAccel) {
      problem.AddResidualBlock(m.cost.get(), nullptr, accel);
    } else {
      problem.AddResidualBlock(m.cost.get(), nullptr, gyro, g9);
    }
  }
  // Held parameters stay at 0: a SubsetManifold per block, or the whole block constant.
  const std::vector<std::pair<double*, int>> blocks = {
      {accel, kAccel0}, {gyro, kGyro0}, {g9, kG0}};
  int estimated = 0;
  for (const auto& [ptr, offset] : blocks) {
    const int size = offset == kG0 ? kGSensitivityParameters : kTriadParameters;
    std::vector<int> held;
    for (int k = 0; k < size; ++k) {
      if (o.held[offset + k]) {
        held.push_back(k);
      } else {
        ++estimated;
      }
    }
    if (static_cast<int>(held.size()) == size) {
      problem.SetParameterBlockConstant(ptr);
    } else if (!held.empty()) {
      problem.SetManifold(ptr, new ceres::SubsetManifold(size, held));
    }
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = 50;
  solver.function_tolerance = 1e-14;
  solver.gradient_tolerance = 1e-16;
  solver.parameter_tolerance = 1e-14;
  solver.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  if (!summary.IsSolutionUsable() || !x.allFinite()) {
    throw std::runtime_error("multi-position calibration: the solver failed: " + summary.message);
  }

  const double s0_sq =
      VarianceFactor(2.0 * summary.final_cost, 3 * static_cast<int>(ms.size()), estimated, &res.notes);
  MatrixP cov = MatrixP::Zero();
  if (estimated > 0) {
    ceres::Covariance::Options cov_options;
    cov_options.algorithm_type = ceres::DENSE_SVD;
    cov_options.num_threads = 1;
    ceres::Covariance covariance(cov_options);
    std::vector<std::pair<const double*, const double*>> pairs;
    std::vector<const double*> variable;
    for (const auto& [ptr, offset] : blocks) {
      if (!problem.IsParameterBlockConstant(ptr)) variable.push_back(ptr);
    }
    for (std::size_t a = 0; a < variable.size(); ++a)
      for (std::size_t b = a; b < variable.size(); ++b) pairs.emplace_back(variable[a], variable[b]);
    if (!covariance.Compute(pairs, &problem)) {
      throw std::runtime_error(
          "multi-position calibration: the covariance of the parameters cannot be computed (rank deficient); "
          "add positions that put gravity and rotations on every axis");
    }
    for (const auto& [pa, pb] : pairs) {
      const int oa = static_cast<int>(pa - x.data()), ob = static_cast<int>(pb - x.data());
      const int na = oa == kG0 ? kGSensitivityParameters : kTriadParameters;
      const int nb = ob == kG0 ? kGSensitivityParameters : kTriadParameters;
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> block(na, nb);
      covariance.GetCovarianceBlock(pa, pb, block.data());
      cov.block(oa, ob, na, nb) = block;
      cov.block(ob, oa, nb, na) = block.transpose();
    }
    cov *= s0_sq;
  }
  if (!cov.allFinite()) throw std::runtime_error("multi-position calibration: the covariance is not finite");
  return MakeResult(res, ms, x, cov, o, static_cast<int>(res.holds.size()));
}

// ------------------------------------------------------------------------ recursive

// Information form of the Kalman filter over the constant parameter vector x (33): prior
// Lambda = diag(1 / prior_sigma^2), eta = 0. The static residuals are linear in x: each adds
// Lambda += H^T H, eta += H^T (H x0 - r(x0)) once (exact for any x0). The move residuals are
// not: a single-pass EKF linearises the early moves at estimates whose g-sensitivity and
// gyro scale factors are still poor and ends hundreds of sigma from the batch (measured:
// 254 sigma in the 24-position test), so the filter keeps the moves so far and
// re-linearises them at each new estimate (kRelinearisations Gauss-Newton passes per
// position; a move costs ~0.2 ms). The estimate is x = Lambda^-1 eta.
struct RecursiveMultiPosition::State {
  Residuals res;
  std::size_t next = 0;  ///< next measurement
  int positions_done = 0;
  MatrixP Lambda_static = MatrixP::Zero();  ///< prior + static positions
  VectorP eta_static = VectorP::Zero();
  std::vector<const Measurement*> moves;    ///< moves so far
  VectorP x = VectorP::Zero();
  std::vector<bool> candidate;

  /// The linearisation of one residual at x0, columns of parameters not estimated zeroed.
  void Add(const Measurement& m, const VectorP& x0, MatrixP* Lambda, VectorP* eta) const {
    Eigen::Vector3d r;
    Eigen::Matrix<double, 3, kAll> H;
    Linearize(m, x0, &r, &H);
    for (int i = 0; i < kAll; ++i)
      if (!candidate[i]) H.col(i).setZero();
    *Lambda += H.transpose() * H;
    *eta += H.transpose() * (H * x0 - r);
  }

  /// Lambda and eta with every move linearised at x0.
  std::pair<MatrixP, VectorP> Information(const VectorP& x0) const {
    MatrixP Lambda = Lambda_static;
    VectorP eta = eta_static;
    for (const Measurement* m : moves) Add(*m, x0, &Lambda, &eta);
    return {Lambda, eta};
  }

  /// x = Lambda_OO^-1 eta_O with the parameters outside `use` at 0; returns Lambda_OO^-1.
  static MatrixP Solve(const MatrixP& Lambda, const VectorP& eta, const std::vector<bool>& use, VectorP* x_out) {
    std::vector<int> idx;
    for (int i = 0; i < kAll; ++i)
      if (use[i]) idx.push_back(i);
    const int n = static_cast<int>(idx.size());
    Eigen::MatrixXd L(n, n);
    Eigen::VectorXd e(n);
    for (int a = 0; a < n; ++a) {
      e(a) = eta(idx[a]);
      for (int b = 0; b < n; ++b) L(a, b) = Lambda(idx[a], idx[b]);
    }
    // Equilibrated (unit diagonal) before the factorisation: Lambda's diagonal spans ~1e14
    // (prior against data, biases against scale factors), which would cost the solution
    // most of its digits.
    const Eigen::VectorXd d = L.diagonal().cwiseSqrt().cwiseInverse();
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(d.asDiagonal() * L * d.asDiagonal());
    const Eigen::VectorXd xs = d.asDiagonal() * ldlt.solve(d.asDiagonal() * e);
    const Eigen::MatrixXd C = d.asDiagonal() * ldlt.solve(Eigen::MatrixXd(d.asDiagonal())) ;
    x_out->setZero();
    MatrixP cov = MatrixP::Zero();
    for (int a = 0; a < n; ++a) {
      (*x_out)(idx[a]) = xs(a);
      for (int b = 0; b < n; ++b) cov(idx[a], idx[b]) = C(a, b);
    }
    return cov;
  }
};

RecursiveMultiPosition::RecursiveMultiPosition(const MultiPositionData& data, const MultiPositionOptions& options)
    : state_(std::make_shared<State>()) {
  state_->res = BuildResiduals(data, options);
  state_->candidate = Candidates(state_->res.estimate_g);
  for (int i = 0; i < kAll; ++i) {
    state_->Lambda_static(i, i) = state_->candidate[i] ? 1.0 / (PriorSigma(i) * PriorSigma(i)) : 1.0;
  }
}

bool RecursiveMultiPosition::Step() {
  State& s = *state_;
  const auto& ms = s.res.measurements;
  if (s.next >= ms.size()) return false;
  const int position = ms[s.next].position;
  while (s.next < ms.size() && ms[s.next].position == position) {
    if (ms[s.next].kind == Kind::kMove) {
      s.moves.push_back(&ms[s.next]);
    } else {
      s.Add(ms[s.next], s.x, &s.Lambda_static, &s.eta_static);
    }
    ++s.next;
  }
  for (int pass = 0; pass < kRelinearisations; ++pass) {
    const auto [Lambda, eta] = s.Information(s.x);
    State::Solve(Lambda, eta, s.candidate, &s.x);
  }
  ++s.positions_done;
  return true;
}

int RecursiveMultiPosition::positions_done() const { return state_->positions_done; }

ImuCalibrationResult RecursiveMultiPosition::Current() const {
  const State& s = *state_;
  std::vector<const Measurement*> ms;
  for (std::size_t k = 0; k < s.next; ++k) ms.push_back(&s.res.measurements[k]);
  const Eigen::MatrixXd J = StackJacobian(ms, s.x);
  Observability o;
  if (ms.empty()) {
    std::fill(o.held.begin(), o.held.end(), true);
  } else {
    o = AnalyseObservability(J, s.candidate);
  }
  std::vector<bool> use(kAll);
  int estimated = 0;
  for (int i = 0; i < kAll; ++i) {
    use[i] = !o.held[i];
    estimated += use[i] ? 1 : 0;
  }
  VectorP x;
  const auto [Lambda, eta] = s.Information(s.x);
  MatrixP cov = State::Solve(Lambda, eta, use, &x);
  std::vector<std::string> notes = s.res.notes;
  const double s0_sq = VarianceFactor(SumOfSquares(ms, x), 3 * static_cast<int>(ms.size()), estimated, &notes);
  cov *= s0_sq;
  ImuCalibrationResult out = MakeResult(s.res, ms, x, cov, o, s.positions_done);
  out.notes = notes;
  return out;
}

// ------------------------------------------------------------------------ records

MultiPositionData ReadMultiPositionData(const ConfigNode& node, const std::string& base_dir) {
  node.RequireKeys({"imu", "latitude_deg", "height_m", "trajectory", "settle_s", "accel_saturation_mps2",
                    "gyro_saturation_deg_s", "g_sensitivity"});
  if (!node.Has("imu")) node.Fail("imu", "missing: the IMU file of the multi-position record");
  if (!node.Has("trajectory")) {
    node.Fail("trajectory", "missing: the table schedule {kind: multiposition, steps: [...]}");
  }
  MultiPositionData data;
  const double lat_deg = node.RequiredDouble("latitude_deg");
  if (!(std::abs(lat_deg) <= 90.0)) node.Fail("latitude_deg", "must be within [-90, 90]");
  data.latitude_rad = lat_deg * kDegToRad;
  data.height_m = node.Double("height_m", 0.0, -1e4, 1e5);
  const ConfigNode trajectory = node.Child("trajectory");
  const sim::CalibrationRigConfig rig = sim::ParseCalibrationRigConfig(trajectory);
  if (rig.kind != sim::CalibrationRigConfig::Kind::kMultiPosition) {
    trajectory.Fail("kind", "must be multiposition for a multi-position calibration");
  }
  data.schedule = rig.table;
  const std::string imu = node.String("imu", "");
  if (imu.empty()) node.Fail("imu", "must name the IMU file");
  std::filesystem::path p(imu);
  if (p.is_relative() && !base_dir.empty()) p = std::filesystem::path(base_dir) / p;
  data.imu_path = p.string();
  std::unique_ptr<ImuReader> reader = OpenImu(data.imu_path);
  data.imu = ReadAll(*reader);
  return data;
}

ImuCalibrationResult CalibrateMultiPositionRecord(const std::string& record_path) {
  const ConfigNode root = LoadYamlFile(record_path);
  const std::string base_dir = std::filesystem::path(record_path).parent_path().string();
  return CalibrateMultiPosition(ReadMultiPositionData(root, base_dir), ReadMultiPositionOptions(root));
}

ImuCalibrationResult CalibrateMultiPositionRecordRecursive(
    const std::string& record_path, const std::function<void(const ImuCalibrationResult&)>& on_position) {
  const ConfigNode root = LoadYamlFile(record_path);
  const std::string base_dir = std::filesystem::path(record_path).parent_path().string();
  RecursiveMultiPosition filter(ReadMultiPositionData(root, base_dir), ReadMultiPositionOptions(root));
  ImuCalibrationResult current;
  while (filter.Step()) {
    current = filter.Current();
    if (on_position) on_position(current);
  }
  if (filter.positions_done() == 0) {
    throw std::runtime_error("recursive multi-position calibration: the record has no static position");
  }
  return current;
}

MultiPositionOptions ReadMultiPositionOptions(const ConfigNode& node) {
  MultiPositionOptions options;
  options.settle_s = node.NonNegative("settle_s", options.settle_s);
  options.accel_saturation_mps2 = node.NonNegative("accel_saturation_mps2", 0.0);
  options.gyro_saturation_rad_per_s = node.NonNegative("gyro_saturation_deg_s", 0.0) * kDegToRad;
  options.estimate_g_sensitivity = node.Bool("g_sensitivity", options.estimate_g_sensitivity);
  return options;
}

}  // namespace navtwin::calibration
