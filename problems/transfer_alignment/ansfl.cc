// Transfer alignment on the ANSFL quadrotor flights (ansfl.h): the coarse clock offset and
// mounting of each Xsens DOT from its gyro and the DJI solution's attitude, then the
// transfer-alignment filter or batch for the fine mounting and the delay.
//
// Frames: n = local NED; b = the drone's body FRD (the DJI attitude q_n_b); s = the DOT's own
// axes (z up at rest: Acc_Z ~ +9.8 m/s^2, so s is NOT FRD and R_b_s is near a 180 deg turn
// about x, times a yaw). R_b_s maps DOT vectors into body axes: omega_b = R_b_s omega_s.
//
// Time scales: t_gt (GT.csv) and t_dot (IMU_k.csv), both "seconds from the path start" but
// not synchronised. clock_offset_s = o puts the DOT on the GT scale: t_gt = t_dot + o.
#include "problems/transfer_alignment/ansfl.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/io/ansfl.h"
#include "core/io/input_error.h"
#include "core/rotation.h"

namespace navtwin::transfer {
namespace {

namespace fs = std::filesystem;
using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

// ---------------------------------------------------------------------------------------
// Rates at the GT epochs.
//
// GT.csv gives the attitude at 10 Hz, each Euler angle rounded to 0.1 deg (uniform rounding
// error: sigma = 0.1 / sqrt(12) = 0.029 deg = 0.5 mrad). The body rate at epoch k is the
// CENTRAL difference over records k-1 .. k+1:
//   omega_nb^b(t_k) ~ Log(R_n_b(k-1)^T R_n_b(k+1)) / (t_{k+1} - t_{k-1}),
// which is exactly the mean body rate over (t_{k-1}, t_{k+1}] to first order (the rotation
// vector of the body-frame increment over the window, divided by its length), centred on t_k
// (no lag). Its rounding noise: two independent 0.029 deg errors over 0.2 s give
// 0.041 deg / 0.2 s = 0.2 deg/s per axis. A forward difference (one interval) would double
// that; a wider window would halve it but smear the drone's attitude changes (about 1 Hz).
// The DOT gyro is averaged over the SAME window (the difference of its integrated angle),
// so the two series go through the same box filter and its attenuation of fast motion cannot
// bias the fit. The DOT measures omega_ib, the GT difference gives omega_nb; they differ by
// the Earth and transport rates (< 0.005 deg/s here), neglected.

struct GtRate {
  double t0_s = 0.0, t1_s = 0.0;  ///< window (GT time)
  Vector3d omega_b_radps = Vector3d::Zero();
};

std::vector<GtRate> GtBodyRates(const std::vector<NavState>& gt) {
  std::vector<GtRate> rates;
  if (gt.size() < 3) return rates;
  std::vector<double> dts;
  for (std::size_t k = 1; k < gt.size(); ++k) dts.push_back(gt[k].t_s - gt[k - 1].t_s);
  std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
  const double nominal_dt_s = dts[dts.size() / 2];
  for (std::size_t k = 1; k + 1 < gt.size(); ++k) {
    const NavState& a = gt[k - 1];
    const NavState& b = gt[k + 1];
    const double span_s = b.t_s - a.t_s;
    // A gap in the GT log: the difference would no longer be a local rate.
    if (!(span_s > 0.0) || span_s > 2.5 * nominal_dt_s) continue;
    const Matrix3d R_a = a.q_n_b.normalized().toRotationMatrix();
    const Matrix3d R_b = b.q_n_b.normalized().toRotationMatrix();
    GtRate r;
    r.t0_s = a.t_s;
    r.t1_s = b.t_s;
    r.omega_b_radps = LogSO3<double>(Matrix3d(R_a.transpose() * R_b)) / span_s;
    rates.push_back(r);
  }
  return rates;
}

/// The DOT's integrated angle Theta(t) = sum of dtheta up to t (sensor axes), linear between
/// sample times, so that the mean rate over any window is (Theta(b) - Theta(a)) / (b - a).
/// Summing rotation vectors in a turning frame ignores coning: over a 0.2 s window at
/// 30 deg/s that is (0.1 rad)^2 / 12 relative, below 1e-3.
class IntegratedRate {
 public:
  explicit IntegratedRate(const std::vector<ImuSample>& imu) {
    t_.reserve(imu.size() + 1);
    theta_.reserve(imu.size() + 1);
    t_.push_back(imu.front().t_s - imu.front().dt_s);
    theta_.push_back(Vector3d::Zero());
    for (const ImuSample& s : imu) {
      t_.push_back(s.t_s);
      theta_.push_back(theta_.back() + s.dtheta_b_rad);
    }
  }
  bool Covers(double a_s, double b_s) const { return a_s >= t_.front() && b_s <= t_.back(); }
  Vector3d MeanRate(double a_s, double b_s) const { return (At(b_s) - At(a_s)) / (b_s - a_s); }
  double start_s() const { return t_.front(); }
  double end_s() const { return t_.back(); }

 private:
  Vector3d At(double t_s) const {
    const auto it = std::upper_bound(t_.begin(), t_.end(), t_s);
    std::size_t i = static_cast<std::size_t>(it - t_.begin());
    if (i == 0) i = 1;
    if (i >= t_.size()) i = t_.size() - 1;
    const double u = (t_s - t_[i - 1]) / (t_[i] - t_[i - 1]);
    return theta_[i - 1] + u * (theta_[i] - theta_[i - 1]);
  }
  std::vector<double> t_;
  std::vector<Vector3d> theta_;
};

/// GT windows inside the DOT record at a clock offset, and the DOT's mean rates over them.
struct RatePairs {
  std::vector<Vector3d> omega_s, omega_b;
};

RatePairs PairsAt(const std::vector<GtRate>& gt, const IntegratedRate& dot, double offset_s,
                  const Vector3d& bias_s_radps) {
  RatePairs p;
  for (const GtRate& g : gt) {
    const double a = g.t0_s - offset_s, b = g.t1_s - offset_s;  // DOT time of the window
    if (!dot.Covers(a, b)) continue;
    p.omega_s.push_back(dot.MeanRate(a, b) - bias_s_radps);
    p.omega_b.push_back(g.omega_b_radps);
  }
  return p;
}

/// At least this many GT windows (3 s at 10 Hz) must overlap the DOT record at a lag.
constexpr std::size_t kMinPairs = 30;

/// Pearson correlation of |omega_s| and |omega_b| (NaN with too few pairs or no variation).
double MagnitudeCorrelation(const RatePairs& p) {
  const std::size_t n = p.omega_s.size();
  if (n < kMinPairs) return std::nan("");
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = p.omega_s[i].norm(), y = p.omega_b[i].norm();
    sx += x;
    sy += y;
    sxx += x * x;
    syy += y * y;
    sxy += x * y;
  }
  const double cxx = sxx - sx * sx / n, cyy = syy - sy * sy / n, cxy = sxy - sx * sy / n;
  if (!(cxx > 0.0) || !(cyy > 0.0)) return std::nan("");
  return cxy / std::sqrt(cxx * cyy);
}

// ---------------------------------------------------------------------------------------
// Mounting and gyro bias: Wahba's problem by SVD (Kabsch with a centroid).
//
// Find R = R_b_s and the DOT gyro bias b minimising  sum_k |omega_b_k - R (omega_s_k - b)|^2
// over the paired window rates. For any R the optimal b makes the residuals zero-mean,
// b = mean(omega_s) - R^T mean(omega_b), so the problem is Kabsch's on the centred rates:
// with B = sum_k (omega_b_k - mean_b) (omega_s_k - mean_s)^T = U S V^T, the minimiser is
// R = U diag(1, 1, det(U V^T)) V^T. The bias is not small: the four DOTs read 0.5-2 deg/s
// at zero rate, the same on every path to 0.02-0.1 deg/s; left in, it tilts the fitted
// rotation by bias / rate, i.e. by degrees on the gentle StraightLine flights.
// The vectors enter unnormalised: epoch k weighs in B with |omega_b_k| |omega_s_k| times its
// pair of unit directions, i.e. each DIRECTION is weighted by the rate magnitude squared,
// which is the maximum-likelihood weighting when the rate errors (DOT vibration, GT
// rounding) have a constant sigma: a direction's error is sigma / |omega|. Slow epochs,
// whose directions are noise, thus barely count.
//
// Observability: the Fisher information of a small rotation delta (R = R_hat Exp(delta)) is
// sum |w|^2 I - w w^T (w the centred rates), whose eigenvalues are (s2 + s3, s1 + s3,
// s1 + s2) for the singular values s1 >= s2 >= s3 of B (B ~ R sum w_s w_s^T up to noise).
// The angle about the dominant rate axis is fixed only by s2 + s3; its sigma relative to the
// best-determined axis is sqrt((s1 + s2) / (s2 + s3)) ~ 1 / sqrt(s2 / s1). We reject below
// s2 / s1 = 0.01, where that angle is 10 times worse than the others (the rates lie within
// atan(0.1) = 6 deg RMS of one line) and is decided by a few off-axis excursions, where any
// systematic rate error (DOT scale factor, residual timing) is as large as the signal. The
// limit sits below what the data need: the Horizontal flights, spinning in yaw, have
// s2 / s1 = 0.03-0.15 and their mounting yaw repeats within 0.3 deg (max - min). Rate NOISE
// cannot fake a second axis: the noises of omega_s and omega_b are uncorrelated, so they
// enter B only as a fluctuation of order sigma |omega| sqrt(N), s2 / s1 ~ sigma / (|omega|
// sqrt(N)) ~ 1e-3 for a one-axis rotation with the noise of these data (the test's yaw-only
// flight gives 4e-4 and is rejected).
constexpr double kMinSecondSingularRatio = 0.01;

struct WahbaFit {
  Matrix3d R_b_s = Matrix3d::Identity();
  Vector3d bias_s_radps = Vector3d::Zero();
  Vector3d singular_values = Vector3d::Zero();
  double residual_rms_radps = 0.0;
};

WahbaFit SolveWahba(const RatePairs& p) {
  const double n = static_cast<double>(p.omega_s.size());
  Vector3d mean_s = Vector3d::Zero(), mean_b = Vector3d::Zero();
  for (std::size_t k = 0; k < p.omega_s.size(); ++k) {
    mean_s += p.omega_s[k] / n;
    mean_b += p.omega_b[k] / n;
  }
  Matrix3d B = Matrix3d::Zero();
  for (std::size_t k = 0; k < p.omega_s.size(); ++k) {
    B += (p.omega_b[k] - mean_b) * (p.omega_s[k] - mean_s).transpose();
  }
  const Eigen::JacobiSVD<Matrix3d> svd(B, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Matrix3d& U = svd.matrixU();
  const Matrix3d& V = svd.matrixV();
  const Vector3d d(1.0, 1.0, (U * V.transpose()).determinant() > 0.0 ? 1.0 : -1.0);
  WahbaFit fit;
  fit.R_b_s = U * d.asDiagonal() * V.transpose();
  fit.bias_s_radps = mean_s - fit.R_b_s.transpose() * mean_b;
  fit.singular_values = svd.singularValues();
  double sse = 0.0;
  for (std::size_t k = 0; k < p.omega_s.size(); ++k) {
    sse += (p.omega_b[k] - fit.R_b_s * (p.omega_s[k] - fit.bias_s_radps)).squaredNorm();
  }
  fit.residual_rms_radps = std::sqrt(sse / std::max(1.0, n));
  return fit;
}

std::string Fmt(const char* format, double a, double b = 0.0, double c = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, a, b, c);
  return buf;
}

struct OffsetSearch {
  double offset_s = 0.0;
  double correlation = 0.0;
};

/// Clock offset: the lag maximising corr(|omega_s - bias|, |omega_b|) on a grid of the DOT
/// sample interval (the norms need no mounting), then the vertex of the parabola through the
/// best grid point and its two neighbours: c(x) ~ c0 + (c+ - c-) x / 2 + (c+ - 2 c0 + c-) x^2 / 2
/// peaks at x = (c- - c+) / (2 (c- - 2 c0 + c+)) grid steps.
OffsetSearch SearchOffset(const std::vector<GtRate>& gt_rates, const IntegratedRate& dot, std::size_t samples,
                          const Vector3d& bias_s_radps, double max_offset_s) {
  const double step_s = (dot.end_s() - dot.start_s()) / static_cast<double>(samples);
  const int half = static_cast<int>(std::floor(max_offset_s / step_s));
  std::vector<double> corr(2 * half + 1);
  int best = -1;
  for (int i = -half; i <= half; ++i) {
    const double c = MagnitudeCorrelation(PairsAt(gt_rates, dot, i * step_s, bias_s_radps));
    corr[i + half] = c;
    if (std::isfinite(c) && (best < 0 || c > corr[best])) best = i + half;
  }
  if (best < 0) {
    throw std::runtime_error("coarse alignment: the DOT and GT records overlap by fewer than " +
                             std::to_string(kMinPairs) + " GT windows at every lag within +-" +
                             Fmt("%.2f s", max_offset_s));
  }
  if (best == 0 || best == 2 * half || !std::isfinite(corr[best - 1]) || !std::isfinite(corr[best + 1])) {
    throw std::runtime_error(
        Fmt("coarse alignment: the |omega| correlation peaks at the search limit (%.3f s of +-%.2f s): "
            "widen max_offset_s",
            (best - half) * step_s, max_offset_s));
  }
  const double cm = corr[best - 1], c0 = corr[best], cp = corr[best + 1];
  const double curvature = cm - 2.0 * c0 + cp;
  double x = 0.0;
  if (curvature < 0.0) x = std::clamp(0.5 * (cm - cp) / curvature, -0.5, 0.5);
  OffsetSearch out;
  out.offset_s = (best - half + x) * step_s;
  out.correlation = MagnitudeCorrelation(PairsAt(gt_rates, dot, out.offset_s, bias_s_radps));
  return out;
}

}  // namespace

CoarseAlignment CoarseAlignAnsfl(const std::vector<ImuSample>& dot_imu, const std::vector<NavState>& gt,
                                 double max_offset_s) {
  if (!(max_offset_s > 0.0) || !std::isfinite(max_offset_s)) {
    throw std::invalid_argument("CoarseAlignAnsfl: max_offset_s must be positive, got " + std::to_string(max_offset_s));
  }
  if (dot_imu.size() < 10) throw std::runtime_error("coarse alignment: the DOT record has fewer than 10 samples");
  const std::vector<GtRate> gt_rates = GtBodyRates(gt);
  if (gt_rates.size() < kMinPairs) {
    throw std::runtime_error("coarse alignment: fewer than " + std::to_string(kMinPairs) +
                             " GT rate windows (GT too short or gapped)");
  }
  const IntegratedRate dot(dot_imu);

  // Two passes: the first search sees |omega_s| with the gyro bias in it (0.5-2 deg/s, against
  // rates of a few deg/s on the gentle flights); the second repeats the search and the fit
  // with the bias of the first fit removed. A third pass changes nothing measurable.
  Vector3d bias_s = Vector3d::Zero();
  CoarseAlignment out;
  for (int pass = 0; pass < 2; ++pass) {
    const OffsetSearch search = SearchOffset(gt_rates, dot, dot_imu.size(), bias_s, max_offset_s);
    // The fit takes the raw DOT rates (its centroid is the bias).
    const WahbaFit fit = SolveWahba(PairsAt(gt_rates, dot, search.offset_s, Vector3d::Zero()));
    const Vector3d& s = fit.singular_values;
    if (!(s(0) > 0.0) || s(1) < kMinSecondSingularRatio * s(0)) {
      throw std::runtime_error(
          Fmt("coarse alignment: the rotation does not excite two axes (singular values of the rate "
              "cross-covariance %.3g, %.3g: ratio %.4f",
              s(0), s(1), s(0) > 0.0 ? s(1) / s(0) : 0.0) +
          Fmt(" < %.2f): the mounting about the rotation axis is unobservable", kMinSecondSingularRatio));
    }
    bias_s = fit.bias_s_radps;
    out.clock_offset_s = search.offset_s;
    out.correlation = search.correlation;
    out.mounting = Quaterniond(fit.R_b_s).normalized();
    out.gyro_bias_s_radps = fit.bias_s_radps;
    out.rate_residual_rms_radps = fit.residual_rms_radps;
  }
  return out;
}

// ---------------------------------------------------------------------------------------
// Configuration of the DOT slaves (returned by AnsflDotConfig; docs/transfer-alignment-real.md).
//
// Slave (Xsens DOT, in flight on the Phantom 4):
//  - gyro bias 200 deg/h: the coarse fit removes each DOT's bias (0.5-2 deg/s); what is left is
//    its path-to-path scatter in the coarse estimates: 0.02-0.04 deg/s (std) on x and y, up to
//    0.1 deg/s on z, about which the Horizontal flights spin (a scale-factor error times the
//    mean yaw rate looks like a bias): 70-360 deg/h, 200 deg/h in between.
//  - gyro ARW 8 deg/sqrt(h): measured in flight from sample-to-sample differences of the DOT
//    gyro (120 Hz; the drone's motion, < 2 Hz, barely enters them): per-axis sigma 1.4-1.6
//    deg/s per sample, i.e. 0.13 deg/s/sqrt(Hz) = 8 deg/sqrt(h). The data sheet's 0.007
//    deg/s/sqrt(Hz) (0.4 deg/sqrt(h)) is at rest; the rotor vibration dominates in flight.
//  - accelerometer bias 10 mg: consumer MEMS after the factory calibration (the order-2
//    filter covers the biases by process noise; the history filter and the batch estimate
//    them with these priors).
//  - VRW 7 m/s/sqrt(h): likewise measured in flight, 1.1-1.3 m/s^2 per sample and per axis
//    (0.1-0.12 m/s^2/sqrt(Hz), white: the 12-sample means scale as 1/sqrt(12)); the data
//    sheet's 120 ug/sqrt(Hz) (0.07 m/s/sqrt(h)) is 100 times smaller.
// Master (the DJI solution as logged): attitude rounded to 0.1 deg per Euler angle, uniform,
// sigma 0.1 / sqrt(12) = 0.029 deg = 0.5 mrad; velocity rounded to 0.1 m/s (GTExtended) or
// differenced from positions (Horizontal), 0.05 m/s.
// Initial: velocity from the master record (0.1 m/s rounding) -> 0.2 m/s; attitude from the
// master times the coarse mounting -> 1 deg; the coarse mounting scatters over the paths by
// 0.3 deg (max - min) in yaw on the Horizontal flights, 1-2 deg in roll and pitch (the same
// for the four DOTs, hence from the GT rates) and on the gentle StraightLine ones -> 2 deg;
// the delay left after the coarse offset: a few ms (the grid is 8 ms) -> 0.05 s around 0.
// settle_s 5 s: the paths last 13-55 s.
TransferConfig AnsflDotConfig() {
  TransferConfig c;
  c.gyro_bias_radps = 200.0 * kDegPerHour_radps;
  c.gyro_arw_rad_per_sqrt_s = 8.0 * kDegPerSqrtHour_radpsqrts;
  c.accel_bias_mps2 = 10000.0 * kMicroG_mps2;
  c.accel_vrw_mps_per_sqrt_s = 7.0 * kMpsPerSqrtHour_mpspsqrts;
  c.initial_velocity_mps = 0.2;
  c.initial_attitude_rad = 1.0 * kDegToRad;
  c.misalignment_rad = 2.0 * kDegToRad;
  c.delay_s = 0.05;
  c.delay_initial_s = 0.0;
  c.master_attitude_rad = 0.5 * kMrad_rad;
  c.master_velocity_mps = 0.05;
  c.settle_s = 5.0;
  c.batch_state_interval_s = 0.1;
  // The DOTs' scale factors and axis misalignments are not estimated: no specification to
  // take a prior from, and the paths' rotations are mostly about one axis.
  c.gyro_scale_factor = 0.0;
  c.accel_scale_factor = 0.0;
  c.gyro_axis_misalignment_rad = 0.0;
  c.accel_axis_misalignment_rad = 0.0;
  return c;
}

namespace {

/// "StraightLine/path_1" from ".../StraightLine/path_1".
std::string PathLabel(const fs::path& dir) { return (dir.parent_path().filename() / dir.filename()).generic_string(); }

/// Path folders of one flight type, in numeric order (path_2 before path_10).
std::vector<fs::path> PathDirs(const fs::path& type_dir) {
  std::vector<std::pair<int, fs::path>> found;
  if (!fs::is_directory(type_dir)) return {};
  for (const fs::directory_entry& e : fs::directory_iterator(type_dir)) {
    const std::string name = e.path().filename().string();
    if (!e.is_directory() || name.rfind("path_", 0) != 0) continue;
    const std::string number = name.substr(5);
    if (number.empty() || number.find_first_not_of("0123456789") != std::string::npos) continue;
    found.emplace_back(std::stoi(number), e.path());
  }
  std::sort(found.begin(), found.end());
  std::vector<fs::path> out;
  for (const auto& f : found) out.push_back(f.second);
  return out;
}

/// RMS over the epochs after settle_s of |Log(R_n_b_est(t) R_n_b_gt(t + tau)^T)|, mrad: the
/// slave attitude brought into body axes by the estimated mounting against the GT attitude
/// at the data time t + tau of the record (GT slerped). RunMethod scores against `truth`
/// (here the GT records) as ZYX Euler differences e = wrap(Euler(R_n_s M^T) - Euler(R_gt(t)));
/// R_n_b_est(t) = DcmFromEuler(Euler(R_gt(t)) + e) exactly (DcmFromEuler is 2 pi periodic in
/// each angle), so the estimate is recovered and compared with the GT at t + tau.
double ResidualAttitudeMrad(const std::vector<NavState>& gt, const TransferResult& r, double t0_s, double settle_s) {
  const auto slerp_at = [&](double t_s, Quaterniond* q) {
    const auto hi = std::lower_bound(gt.begin(), gt.end(), t_s, [](const NavState& s, double t) { return s.t_s < t; });
    if (hi == gt.end() || hi == gt.begin()) return false;
    const NavState& a = *(hi - 1);
    const NavState& b = *hi;
    *q = a.q_n_b.slerp((t_s - a.t_s) / (b.t_s - a.t_s), b.q_n_b).normalized();
    return true;
  };
  double sum2 = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < r.t_s.size(); ++i) {
    if (r.t_s[i] < t0_s + settle_s - 1e-9) continue;
    Quaterniond q_gt_t, q_gt_data;
    if (!slerp_at(r.t_s[i], &q_gt_t) || !slerp_at(r.t_s[i] + r.delay_s, &q_gt_data)) continue;
    const Vector3d euler_est = EulerFromDcm(Matrix3d(q_gt_t.toRotationMatrix())) + r.error_mrad[i] * kMrad_rad;
    const Matrix3d R_est = DcmFromEuler(euler_est.x(), euler_est.y(), euler_est.z());
    sum2 += LogSO3<double>(Matrix3d(R_est * q_gt_data.toRotationMatrix().transpose())).squaredNorm();
    ++n;
  }
  return n == 0 ? std::nan("") : std::sqrt(sum2 / static_cast<double>(n)) / kMrad_rad;
}

}  // namespace

TransferInputs LoadAnsflPath(const std::string& path_dir, int dot, CoarseAlignment* coarse) {
  if (dot < 1 || dot > 4)
    throw std::invalid_argument("LoadAnsflPath: DOT number must be 1-4, got " + std::to_string(dot));
  const fs::path dir(path_dir);
  TransferInputs in;
  in.master_path = (dir / "GT.csv").string();
  in.slave_path = (dir / ("IMU_" + std::to_string(dot) + ".csv")).string();
  // Horizontal paths (no GTExtended.csv): the reader's default origin, AnsflSiteOrigin().
  const std::unique_ptr<NavReader> gt_reader = OpenAnsflGt(in.master_path);
  in.master = ReadAll<NavState>(*gt_reader);
  const std::unique_ptr<ImuReader> imu_reader = OpenAnsflImu(in.slave_path);
  in.slave_imu = ReadAll<ImuSample>(*imu_reader);
  if (in.slave_imu.empty()) throw InputError(in.slave_path, 0, "imu", "no samples");

  const CoarseAlignment c = CoarseAlignAnsfl(in.slave_imu, in.master);
  if (coarse != nullptr) *coarse = c;
  // On the GT time scale, with the coarse gyro bias taken out of the increments (the filter
  // has no bias state; the batch estimates what is left around zero).
  for (ImuSample& s : in.slave_imu) {
    s.t_s += c.clock_offset_s;
    s.dtheta_b_rad -= c.gyro_bias_s_radps * s.dt_s;
  }
  in.misalignment_guess = c.mounting;
  // The slave starts at the first GT record inside the DOT record: R_n_s = R_n_b R_b_s.
  const double t_first = in.slave_imu.front().t_s - in.slave_imu.front().dt_s;
  const auto first =
      std::find_if(in.master.begin(), in.master.end(), [&](const NavState& m) { return m.t_s >= t_first; });
  if (first == in.master.end()) {
    throw InputError(in.master_path, 0, "t_s", "no GT record inside the DOT record " + in.slave_path);
  }
  in.slave_initial = *first;
  in.slave_initial.q_n_b = (first->q_n_b * c.mounting).normalized();
  return in;
}

namespace {

/// One path folder and DOT: coarse alignment and refinement; a failure is a note (one path
/// or DOT that cannot be aligned, a line-only rotation or a failed solve, is reported, not
/// fatal for the others).
AnsflAlignment AlignOneDot(const fs::path& dir, int dot, const TransferConfig& config, Method method) {
  AnsflAlignment a;
  a.path = PathLabel(dir);
  a.dot = dot;
  a.result.method = method;
  a.residual_attitude_mrad = std::nan("");
  std::cerr << "transfer-align-ansfl: " << a.path << " DOT" << dot << " ..." << std::flush;
  try {
    TransferInputs in = LoadAnsflPath(dir.string(), dot, &a.coarse);
    // The GT as body "truth": RunMethod then scores R_n_s M_est^T against it, from which
    // the residual against the delay-shifted GT is recovered (ResidualAttitudeMrad).
    in.truth = in.master;
    a.result = RunMethod(in, config, method);
    a.residual_attitude_mrad = ResidualAttitudeMrad(in.master, a.result, in.slave_initial.t_s, config.settle_s);
    if (std::isnan(a.residual_attitude_mrad)) a.note = "no epoch after settle_s";
    std::cerr << Fmt(" offset %.3f s, delay %.1f ms, residual %.2f mrad\n", a.coarse.clock_offset_s,
                     a.result.delay_s * 1e3, a.residual_attitude_mrad);
  } catch (const std::exception& e) {
    a.note = e.what();
    std::cerr << " skipped: " << e.what() << "\n";
  }
  return a;
}

}  // namespace

std::vector<AnsflAlignment> AlignAllAnsfl(const std::string& data_dir, const TransferConfig& config, Method method,
                                          const AnsflSelection& selection) {
  std::vector<fs::path> dirs;
  if (!selection.path.empty()) {
    const fs::path dir = fs::path(data_dir) / selection.path;
    if (!fs::exists(dir / "GT.csv")) {
      throw InputError((dir / "GT.csv").string(), 0, "path", "no such path folder (give e.g. Horizontal/path_4)");
    }
    dirs.push_back(dir);
  } else {
    for (const char* type : {"StraightLine", "Horizontal"}) {
      const std::vector<fs::path> d = PathDirs(fs::path(data_dir) / type);
      dirs.insert(dirs.end(), d.begin(), d.end());
    }
  }
  if (dirs.empty()) {
    throw InputError(data_dir, 0, "StraightLine/path_*, Horizontal/path_*", "no path folders under the data directory");
  }
  std::vector<AnsflAlignment> out;
  for (const fs::path& dir : dirs) {
    for (int dot = 1; dot <= 4; ++dot) {
      if (selection.dot != 0 && dot != selection.dot) continue;
      const fs::path imu = dir / ("IMU_" + std::to_string(dot) + ".csv");
      if (!fs::exists(imu)) {
        if (selection.dot != 0) throw InputError(imu.string(), 0, "dot", "no such DOT file in this path folder");
        continue;
      }
      out.push_back(AlignOneDot(dir, dot, config, method));
    }
  }
  return out;
}

CalibrationFile AnsflCalibrationFile(const AnsflAlignment& a, const std::string& created_by) {
  if (!AnsflRefined(a)) {
    throw std::invalid_argument("no calibration for " + a.path + " DOT" + std::to_string(a.dot) + ": " + a.note);
  }
  const auto sigma_or_nan = [](double s) { return s > 0.0 && std::isfinite(s) ? s : std::nan(""); };
  CalibrationFile f;
  f.created_by = created_by;
  ImuCalibration imu;
  imu.gyro.tail<3>() = a.coarse.gyro_bias_s_radps;
  f.imu = imu;
  ImuInstallation inst;
  inst.mounting_rpy_rad = a.result.misalignment_deg * kDegToRad;
  inst.time_offset_s = a.coarse.clock_offset_s + a.result.delay_s;
  Vector3d mounting_sigma_rad;
  for (int i = 0; i < 3; ++i) mounting_sigma_rad[i] = sigma_or_nan(a.result.misalignment_sigma_mrad[i] * kMrad_rad);
  inst.mounting_sigma_rad = mounting_sigma_rad;
  inst.time_offset_sigma_s = sigma_or_nan(a.result.delay_sigma_s);
  f.installation = inst;
  return f;
}

bool AnsflCoarseOk(const AnsflAlignment& a) { return a.coarse.correlation > 0.0; }

bool AnsflRefined(const AnsflAlignment& a) { return a.note.empty() || a.note == "no epoch after settle_s"; }

SampleSpread SpreadOf(const std::vector<double>& values, bool angle_rad) {
  SampleSpread s;
  s.n = static_cast<int>(values.size());
  if (values.empty()) return s;
  std::vector<double> u;
  for (const double v : values) u.push_back(angle_rad ? values[0] + WrapPi(v - values[0]) : v);
  double sum = 0.0;
  for (const double v : u) sum += v;
  s.mean = sum / static_cast<double>(u.size());
  double ss = 0.0;
  for (const double v : u) ss += (v - s.mean) * (v - s.mean);
  if (u.size() > 1) s.std = std::sqrt(ss / static_cast<double>(u.size() - 1));
  s.range = *std::max_element(u.begin(), u.end()) - *std::min_element(u.begin(), u.end());
  if (angle_rad) s.mean = WrapPi(s.mean);
  return s;
}

namespace {

DotRepeatability RepeatabilityOf(int dot, const std::string& group, const std::vector<const AnsflAlignment*>& list) {
  DotRepeatability r;
  r.dot = dot;
  r.group = group;
  for (int i = 0; i < 3; ++i) {
    std::vector<double> coarse, refined;
    for (const AnsflAlignment* a : list) {
      if (AnsflCoarseOk(*a)) coarse.push_back(EulerFromQuat(a->coarse.mounting)[i]);
      if (AnsflRefined(*a)) refined.push_back(a->result.misalignment_deg[i] * kDegToRad);
    }
    r.coarse_rad[i] = SpreadOf(coarse, true);
    r.mounting_rad[i] = SpreadOf(refined, true);
  }
  std::vector<double> delay, residual;
  for (const AnsflAlignment* a : list) {
    if (!AnsflRefined(*a)) continue;
    delay.push_back(a->result.delay_s);
    if (std::isfinite(a->residual_attitude_mrad)) residual.push_back(a->residual_attitude_mrad * 1e-3);
  }
  r.delay_s = SpreadOf(delay, false);
  r.residual_rad = SpreadOf(residual, false);
  return r;
}

}  // namespace

std::vector<DotRepeatability> AnsflRepeatability(const std::vector<AnsflAlignment>& runs) {
  std::map<std::pair<int, std::string>, std::vector<const AnsflAlignment*>> by_dot;
  for (const AnsflAlignment& a : runs) {
    by_dot[{a.dot, "all"}].push_back(&a);
    by_dot[{a.dot, a.path.substr(0, a.path.find('/'))}].push_back(&a);
  }
  std::vector<DotRepeatability> out;
  for (const auto& [key, list] : by_dot) out.push_back(RepeatabilityOf(key.first, key.second, list));
  return out;
}

}  // namespace navtwin::transfer
