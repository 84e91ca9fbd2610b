// Pendulum IMU calibration (problems/calibration/pendulum.h): the swing fit, the truth
// from the fitted swing, recovery of known errors, a Monte Carlo of the sigma's honesty,
// the seed's finding that a mounting rotated about two axes makes misalignment observable
// (tables 3-5 / 3-6; docs/calibration-pendulum.md), the record path through files, and bad
// input. Runs are synthesized in memory (sim::PendulumRig + sim::SynthesizeImu +
// sim::InertialErrorModel) at 100 Hz.
#include "problems/calibration/pendulum.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/earth.h"
#include "core/io/input_error.h"
#include "core/rotation.h"
#include "core/sim/analytic_trajectory.h"
#include "core/sim/calibration_rig.h"
#include "core/sim/inertial_errors.h"
#include "core/sim/scenario.h"
#include "core/sim/simulator.h"
#include "core/sim/vibration.h"

namespace navtwin::calibration {
namespace calibration_pendulum_test {


const wgs84::Geodetic kLab{37.45 * kDegToRad, 126.65 * kDegToRad, 40.0};
constexpr double kRateHz = 100.0;
constexpr double kLength_m = 0.8;
constexpr double kDamping_per_s = 0.05;
constexpr double kGyroArw = 0.1 * kDegToRad / 60.0;  // 0.1 deg/sqrt(h), rad/sqrt(s)
constexpr double kAccelVrw = 0.05 / 60.0;            // 0.05 m/s/sqrt(h)
constexpr double kEncoderNoise_rad = 0.01 * kDegToRad;

Eigen::Matrix3d Mounting(const std::string& yaml) {
  return sim::ParsePendulumMounting(ParseYaml(yaml, "mounting.yaml"));
}

/// The seed's three mountings and the one rotated about two axes.
const std::vector<std::string>& MountingKeys() {
  static const std::vector<std::string> keys = {"mounting: NED", "mounting: DNE", "mounting: EDN",
                                                "mounting_deg: [30, 0, 30]"};
  return keys;
}

/// The exact increments and the true angle of one pendulum run (no sensor error).
struct ExactRun {
  std::vector<ImuSample> exact;  ///< dt > 0 samples
  std::vector<double> t_s;       ///< the angle's times: 0 and every sample's
  std::vector<double> theta_rad;
  Eigen::Matrix3d mounting_p_b;
  double c2_per_s2 = 0.0;
};

ExactRun MakeExactRun(const Eigen::Matrix3d& mounting_p_b, double duration_s, double initial_angle_deg = 40.0) {
  sim::PendulumConfig c;
  c.length_m = kLength_m;
  c.damping_per_s = kDamping_per_s;
  c.initial_angle_rad = initial_angle_deg * kDegToRad;
  c.mounting_p_b = mounting_p_b;
  const sim::PendulumRig rig(c);
  ExactRun run;
  run.mounting_p_b = mounting_p_b;
  run.c2_per_s2 = rig.c2_per_s2();
  sim::SynthesizeImu(rig, kLab, kRateHz, duration_s, [&](const ImuSample& s, const NavState&) {
    if (s.dt_s > 0.0) run.exact.push_back(s);
    run.t_s.push_back(s.t_s);
    run.theta_rad.push_back(rig.Angle_rad(s.t_s));
  });
  return run;
}

/// Exact runs per mounting and duration, made once (the Monte Carlo draws only errors).
const ExactRun& CachedRun(int mounting, double duration_s) {
  static std::map<std::pair<int, double>, ExactRun> cache;
  const auto key = std::make_pair(mounting, duration_s);
  auto it = cache.find(key);
  if (it == cache.end()) {
    it = cache.emplace(key, MakeExactRun(Mounting(MountingKeys()[mounting]), duration_s)).first;
  }
  return it->second;
}

/// Errors drawn per Monte Carlo run (1 sigma), white noise of a tactical-grade MEMS IMU.
sim::InertialErrorConfig DrawnErrors() {
  sim::InertialErrorConfig e;
  e.gyro.bias.sigma = 10.0 * kDegToRad / 3600.0;
  e.gyro.scale_factor.sigma = 300e-6;
  e.gyro.misalignment.sigma = 1e-3;
  e.gyro.white_noise = kGyroArw;
  e.accel.bias.sigma = 1e-3 * kStandardGravity_mps2;
  e.accel.scale_factor.sigma = 300e-6;
  e.accel.misalignment.sigma = 1e-3;
  e.accel.white_noise = kAccelVrw;
  e.g_sensitivity.sigma = 5.0 * kDegToRad / 3600.0 / kStandardGravity_mps2;
  return e;
}

/// The true parameters of a drawn model in the calibration's 33-vector layout.
Eigen::VectorXd TrueParameters(const sim::InertialErrorModel& m) {
  Eigen::VectorXd p(33);
  const auto triad = [&p](int offset, const sim::DrawnTriadErrors& d) {
    for (int r = 0; r < 3; ++r) {
      p(offset + r) = d.scale_factor(r);
      p(offset + 9 + r) = d.bias(r);
      for (int c = 0; c < 3; ++c) {
        if (c != r) p(offset + MisalignmentIndex(r, c)) = d.misalignment(r, c);
      }
    }
  };
  triad(0, m.accel().drawn());
  triad(12, m.gyro().drawn());
  for (int k = 0; k < 9; ++k) p(24 + k) = m.g_sensitivity()(k / 3, k % 3);
  return p;
}

Eigen::VectorXd Estimated(const ImuCalibration& c) {
  Eigen::VectorXd p(33);
  p << c.accel, c.gyro, c.g_sensitivity;
  return p;
}
Eigen::VectorXd Sigmas(const ImuCalibration& c) {
  Eigen::VectorXd s(33);
  s << *c.accel_sigma, *c.gyro_sigma, *c.g_sensitivity_sigma;
  return s;
}

/// Runs of one IMU (one error model, runs one after the other in its time) on the given
/// mountings, with encoder noise.
struct Simulated {
  PendulumData data;
  Eigen::VectorXd truth;
};

Simulated SimulateRuns(const std::vector<int>& mountings, double duration_s, const sim::InertialErrorConfig& errors,
                       std::uint64_t seed, double encoder_noise_rad = kEncoderNoise_rad) {
  sim::Rng rng(seed);
  sim::InertialErrorModel model(errors, rng.Stream("imu"), false);
  sim::Rng encoder = rng.Stream("encoder");
  Simulated out;
  out.truth = TrueParameters(model);
  out.data.latitude_rad = kLab.lat_rad;
  out.data.height_m = kLab.h_m;
  double offset_s = 0.0;  // the runs follow each other on the IMU's clock
  for (const int m : mountings) {
    const ExactRun& exact = CachedRun(m, duration_s);
    PendulumRun run;
    run.length_m = kLength_m;
    run.mounting_p_b = exact.mounting_p_b;
    run.imu_path = MountingKeys()[m];
    for (const ImuSample& s : exact.exact) {
      ImuSample meas = s;
      meas.t_s += offset_s;
      model.Apply(meas.t_s, s.dt_s, errors.temperature.reference_degC, s.dtheta_b_rad, s.dv_b_mps,
                  &meas.dtheta_b_rad, &meas.dv_b_mps);
      run.imu.push_back(meas);
    }
    run.angle.path = "angle of " + run.imu_path;
    for (std::size_t k = 0; k < exact.t_s.size(); ++k) {
      run.angle.t_s.push_back(exact.t_s[k] + offset_s);
      run.angle.theta_rad.push_back(exact.theta_rad[k] + encoder.Normal(encoder_noise_rad));
    }
    out.data.runs.push_back(std::move(run));
    offset_s += duration_s + 10.0;
  }
  return out;
}

AngleRecord NoisyAngle(const ExactRun& run, double noise_rad, std::uint64_t seed) {
  sim::Rng rng(seed);
  AngleRecord a;
  a.path = "angle";
  a.t_s = run.t_s;
  for (const double th : run.theta_rad) a.theta_rad.push_back(th + rng.Normal(noise_rad));
  return a;
}

// ----------------------------------------------------------------- swing fit

TEST(PendulumCalibrationTest, SwingFitRecoversC1AndC2WithinItsSigma) {
  const ExactRun& run = CachedRun(0, 60.0);
  // A perfect encoder: only the integrators differ (the rig's RK4 at 1 ms with a quintic
  // Hermite, the fit's RK4 at 5 ms); c2's sigma with a 0.01 deg encoder is 6e-6.
  const SwingFit exact = FitSwing(NoisyAngle(run, 0.0, 1));
  EXPECT_NEAR(exact.c1_per_s, kDamping_per_s, 1e-8);  // measured 1e-10
  EXPECT_NEAR(exact.c2_per_s2, run.c2_per_s2, 1e-7);  // RK4 at 5 ms: measured 1.8e-8
  EXPECT_LT(exact.residual_rms_rad, 1e-9);
  // Encoder noise 0.01 deg: the truth within 3 sigma, the residual the noise.
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const SwingFit fit = FitSwing(NoisyAngle(run, kEncoderNoise_rad, seed));
    EXPECT_LT(std::fabs(fit.c1_per_s - kDamping_per_s), 3.0 * fit.c1_sigma()) << seed;
    EXPECT_LT(std::fabs(fit.c2_per_s2 - run.c2_per_s2), 3.0 * fit.c2_sigma()) << seed;
    // 6000 residuals: their rms is within 3 % of the noise sigma (its relative sigma 0.9 %).
    EXPECT_NEAR(fit.residual_rms_rad / kEncoderNoise_rad, 1.0, 0.03) << seed;
    std::printf("seed %d: c1 = %.6f +- %.2g 1/s (true %.2f), c2 = %.7f +- %.2g 1/s^2 (true %.7f)\n",
                static_cast<int>(seed), fit.c1_per_s, fit.c1_sigma(), kDamping_per_s, fit.c2_per_s2,
                fit.c2_sigma(), run.c2_per_s2);
  }
}

TEST(PendulumCalibrationTest, TruthFromTheFittedSwingMatchesTheExactIncrements) {
  // Every mounting: the truth computed from the fitted swing (perfect encoder) against the
  // simulator's exact increments.
  for (int m = 0; m < 4; ++m) {
    const ExactRun& run = CachedRun(m, 60.0);
    const SwingFit fit = FitSwing(NoisyAngle(run, 0.0, 1));
    const std::vector<ImuSample> truth =
        TrueIncrements(fit, {kLength_m, run.mounting_p_b, kLab.lat_rad, kLab.h_m}, run.exact);
    double rate = 0.0, force = 0.0;
    for (std::size_t k = 0; k < truth.size(); ++k) {
      const double dt = run.exact[k].dt_s;
      rate = std::max(rate, (truth[k].dtheta_b_rad - run.exact[k].dtheta_b_rad).cwiseAbs().maxCoeff() / dt);
      force = std::max(force, (truth[k].dv_b_mps - run.exact[k].dv_b_mps).cwiseAbs().maxCoeff() / dt);
    }
    std::printf("%s: truth - exact: rate %.2g rad/s, specific force %.2g m/s^2\n", MountingKeys()[m].c_str(),
                rate, force);
    // 1e-7 rad/s = 0.02 deg/h and 1e-6 m/s^2 = 0.1 ug: below any calibrated sigma; what is
    // left are the neglected omega_en x v and height-dependent gravity terms.
    EXPECT_LT(rate, 1e-7) << MountingKeys()[m];
    EXPECT_LT(force, 1e-6) << MountingKeys()[m];
  }
}

TEST(PendulumCalibrationTest, ShortOrCoarseSwingsAreRefused) {
  const ExactRun& run = CachedRun(0, 60.0);
  AngleRecord a = NoisyAngle(run, 0.0, 1);
  AngleRecord short_record = a;
  short_record.t_s.resize(150);  // 1.5 s: less than one 1.8 s period
  short_record.theta_rad.resize(150);
  try {
    FitSwing(short_record);
    ADD_FAILURE() << "a swing shorter than one period was fitted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("zero crossings"), std::string::npos) << e.what();
  }
  AngleRecord coarse;
  coarse.path = "coarse";
  for (std::size_t k = 0; k < a.t_s.size(); k += 25) {  // 4 Hz: ~7 samples per period
    coarse.t_s.push_back(a.t_s[k]);
    coarse.theta_rad.push_back(a.theta_rad[k]);
  }
  EXPECT_THROW(FitSwing(coarse), std::runtime_error);
}

// ------------------------------------------------------- the shared error model

TEST(PendulumCalibrationTest, AxisRowsAreTheSharedErrorModel) {
  // The rows of the per-axis least squares (derived from core/imu_error_model.h) times a
  // random parameter vector reproduce MeasuredSpecificForce / MeasuredRate minus the truth,
  // every axis, with and without g-sensitivity; every parameter on exactly one axis.
  sim::Rng rng(42);
  for (const bool with_g : {true, false}) {
    const std::vector<detail::AxisProblem> axes = detail::AxisProblems(with_g);
    ASSERT_EQ(axes.size(), 6u);
    std::vector<int> count(33, 0);
    for (const detail::AxisProblem& axis : axes) {
      ASSERT_EQ(static_cast<std::size_t>(axis.regressors.rows()), axis.params.size());
      for (const int j : axis.params) ++count[j];
    }
    for (int j = 0; j < 33; ++j) EXPECT_EQ(count[j], j < 24 || with_g ? 1 : 0) << j;
    for (int draw = 0; draw < 20; ++draw) {
      Eigen::Matrix<double, 33, 1> p;
      for (int j = 0; j < 33; ++j) p(j) = rng.Normal(1e-2);
      if (!with_g) p.tail<9>().setZero();
      Eigen::Vector3d f, omega;
      for (int i = 0; i < 3; ++i) {
        f(i) = rng.Normal(10.0);
        omega(i) = rng.Normal(1.0);
      }
      Eigen::Matrix<double, 7, 1> z;
      z << f, omega, 1.0;
      Eigen::Matrix<double, 6, 1> model, truth;
      model << MeasuredSpecificForce(p.data(), f), MeasuredRate(p.data() + 12, with_g ? p.data() + 24 : nullptr, omega, f);
      truth << f, omega;
      for (int a = 0; a < 6; ++a) {
        double rows = 0.0;
        for (std::size_t i = 0; i < axes[a].params.size(); ++i) {
          rows += p(axes[a].params[i]) * axes[a].regressors.row(static_cast<Eigen::Index>(i)).dot(z);
        }
        // model - truth is computed from values ~|model|: rounding eps |model| ~ 1e-15 of it.
        EXPECT_NEAR(rows, model(a) - truth(a), 1e-12 * std::fabs(model(a))) << "axis " << a << " with_g " << with_g;
      }
    }
  }
}

// ------------------------------------------------------------------ calibration

TEST(PendulumCalibrationTest, RecoversKnownErrorsFromTheFourMountings) {
  const Simulated s = SimulateRuns({0, 1, 2, 3}, 60.0, DrawnErrors(), 7);
  std::vector<SwingFit> fits;
  const ImuCalibrationResult r = CalibratePendulum(s.data, {}, &fits);
  ASSERT_EQ(fits.size(), 4u);
  EXPECT_TRUE(r.unobservable.empty()) << r.unobservable.front();
  ASSERT_EQ(r.estimated.size(), 33u);
  const Eigen::VectorXd est = Estimated(r.calibration), sigma = Sigmas(r.calibration);
  ASSERT_TRUE(est.allFinite() && sigma.allFinite());
  for (int i = 0; i < 33; ++i) {
    // 33 parameters of one draw: 4 sigma keeps the chance of a false alarm below 0.3 %.
    EXPECT_LT(std::fabs(est(i) - s.truth(i)), 4.0 * sigma(i)) << r.estimated[i];
  }
  // The rig determines what it calibrates: scale factors and misalignments to better than
  // 100 ppm / 0.1 mrad, biases to 0.1 mg and 5 deg/h (measured 34 ppm, 34 ug, 2.4 deg/h:
  // the gyro bias shares the ~1 g regressor with the g-sensitivity).
  for (int i = 0; i < 9; ++i) {
    EXPECT_LT(sigma(i), 1e-4) << r.estimated[i];
    EXPECT_LT(sigma(12 + i), 1e-4) << r.estimated[12 + i];
  }
  EXPECT_LT(sigma.segment(9, 3).maxCoeff(), 1e-4 * kStandardGravity_mps2);
  EXPECT_LT(sigma.segment(21, 3).maxCoeff(), 5.0 * kDegToRad / 3600.0);
  // The swing fits' share of the sigma: without it every sigma is smaller or equal.
  PendulumOptions imu_only;
  imu_only.propagate_swing_uncertainty = false;
  const Eigen::VectorXd sigma_imu = Sigmas(CalibratePendulum(s.data, imu_only).calibration);
  for (int i = 0; i < 33; ++i) {
    std::printf("%-24s sigma %.3g, IMU noise alone %.3g (x%.2f)\n", r.estimated[i].c_str(), sigma(i), sigma_imu(i),
                sigma(i) / sigma_imu(i));
  }
  EXPECT_TRUE((sigma.array() >= sigma_imu.array()).all());
  // The residuals are the white noise over one 10 ms sample (within 5 %).
  EXPECT_NEAR(r.accel_residual_rms_mps2 / (kAccelVrw / std::sqrt(0.01)), 1.0, 0.05);
  EXPECT_NEAR(r.gyro_residual_rms_rad_per_s / (kGyroArw / std::sqrt(0.01)), 1.0, 0.05);
  // Per run and axis: the RMS after calibration is that noise too (10 %: one run's axis has
  // ~1200 samples). Before, the raw gyro errors dominate it; the accelerometer's errors
  // (mg) are of the order of its 100 Hz noise (8 mg), so they add less than a factor 2.
  ASSERT_EQ(r.residuals.size(), 4u);
  for (const CalibrationResidual& res : r.residuals) {
    EXPECT_TRUE(res.rms);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(res.accel_after_mps2(i) / (kAccelVrw / std::sqrt(0.01)), 1.0, 0.1) << "run " << res.run;
      EXPECT_NEAR(res.gyro_after_radps(i) / (kGyroArw / std::sqrt(0.01)), 1.0, 0.1) << "run " << res.run;
    }
    EXPECT_GT(res.accel_before_mps2.norm(), res.accel_after_mps2.norm());
    EXPECT_GT(res.gyro_before_radps.norm(), 2.0 * res.gyro_after_radps.norm());
  }
}

TEST(PendulumCalibrationTest, MonteCarloSigmaIsHonest) {
  // 100 IMUs, each calibrated on the four mountings (12 s each, 100 Hz).
  constexpr int kRuns = 100;
  int inside = 0, total = 0;
  for (int mc = 0; mc < kRuns; ++mc) {
    const Simulated s = SimulateRuns({0, 1, 2, 3}, 12.0, DrawnErrors(), 1000 + mc);
    const ImuCalibrationResult r = CalibratePendulum(s.data);
    const Eigen::VectorXd est = Estimated(r.calibration), sigma = Sigmas(r.calibration);
    for (int i = 0; i < 33; ++i) {
      if (!std::isfinite(sigma(i))) continue;
      ++total;
      if (std::fabs(est(i) - s.truth(i)) <= 3.0 * sigma(i)) ++inside;
    }
  }
  const double fraction = static_cast<double>(inside) / total;
  std::printf("Monte Carlo: %d of %d (run, parameter) within 3 sigma: %.2f %%\n", inside, total, 100.0 * fraction);
  EXPECT_EQ(total, kRuns * 33);
  // Honest sigma: 99.7 % expected; >= 95 % is the bar.
  EXPECT_GE(fraction, 0.95);
}

TEST(PendulumCalibrationTest, RotatedMountingMakesMisalignmentObservable) {
  // The seed's tables 3-5 / 3-6: NED, DNE, EDN alone, then with a mounting rotated about
  // two axes; and, for a fair count, the three alone with the same total time.
  const sim::InertialErrorConfig errors = DrawnErrors();
  const ImuCalibrationResult three = CalibratePendulum(SimulateRuns({0, 1, 2}, 60.0, errors, 11).data);
  const ImuCalibrationResult three_long = CalibratePendulum(SimulateRuns({0, 1, 2}, 80.0, errors, 11).data);
  const ImuCalibrationResult four = CalibratePendulum(SimulateRuns({0, 1, 2, 3}, 60.0, errors, 11).data);
  const Eigen::VectorXd before = Sigmas(three.calibration), longer = Sigmas(three_long.calibration),
                        after = Sigmas(four.calibration);
  std::printf("%-26s %12s %12s %12s  unit\n", "parameter", "NED,DNE,EDN", "same time", "+[30,0,30]");
  for (int i = 0; i < 33; ++i) {
    const double unit = i % 12 < 9 && i < 24 ? 1e6 : (i < 12 ? 1e6 / kStandardGravity_mps2
                                                             : 3600.0 / kDegToRad * (i >= 24 ? kStandardGravity_mps2 : 1.0));
    const char* name = i % 12 < 3 && i < 24 ? "ppm" : (i % 12 < 9 && i < 24 ? "urad" : (i < 12 ? "ug" : (i < 24 ? "deg/h" : "deg/h/g")));
    std::printf("%-26s %12.4g %12.4g %12.4g  %s\n", four.estimated[i].c_str(), before(i) * unit, longer(i) * unit,
                after(i) * unit, name);
  }
  // The accelerometer misalignments (and scale factors, biases, the gyro biases and
  // g-sensitivity, which share the same 1 g regressor) halve their sigma with the rotated
  // mounting, even against the three alone for the same total time (measured 0.47-0.57).
  for (int i = 0; i < 12; ++i) EXPECT_LT(after(i), 0.7 * longer(i)) << four.estimated[i];
  for (int i = 21; i < 33; ++i) EXPECT_LT(after(i), 0.7 * longer(i)) << four.estimated[i];
  // The gyro misalignments were observable before: each seed mounting turns about one IMU
  // axis with a zero-mean rate; the rotated mounting spreads its turn over the axes (within
  // 20 % either way; measured 0.97-1.09).
  for (int i = 15; i < 21; ++i) EXPECT_NEAR(after(i) / longer(i), 1.0, 0.2) << four.estimated[i];
  // Why: in every seed mounting the specific force stays along one IMU axis at about -1 g
  // (the bob's radial direction), so for accelerometer row r shifting s_r, both M_rc and
  // b_r / g by the same epsilon changes no output but through the swing's +-20 % change of
  // |f|: the direction (1, 1, 1, 1) / 2 in (s_r, M_rc1, M_rc2, b_r / g) is the weak one (the
  // same for (G_r., b_g,r / g) of the gyro). A mounting with gravity on two or three axes at
  // once breaks it.
  const auto weak_sigma = [](const ImuCalibrationResult& r, int row, bool gyro) {
    std::vector<std::string> names;
    const std::string t = gyro ? "g_sensitivity." : "accel.";
    const char* axis[3] = {"x", "y", "z"};
    for (int c = 0; c < 3; ++c) {
      names.push_back(gyro ? t + axis[row] + axis[c]
                           : (c == row ? t + "scale_factor." + axis[row] : t + "misalignment." + axis[row] + axis[c]));
    }
    names.push_back((gyro ? "gyro.bias." : "accel.bias.") + std::string(axis[row]));
    Eigen::VectorXd d = Eigen::VectorXd::Zero(r.estimated.size());
    for (std::size_t k = 0; k < names.size(); ++k) {
      const auto i = std::find(r.estimated.begin(), r.estimated.end(), names[k]) - r.estimated.begin();
      d(i) = (k == 3 ? 1.0 / kStandardGravity_mps2 : 1.0) / 2.0;
    }
    return std::sqrt(d.dot(r.covariance * d));
  };
  for (int row = 0; row < 3; ++row) {
    for (const bool gyro : {false, true}) {
      const double w_before = weak_sigma(three_long, row, gyro), w_after = weak_sigma(four, row, gyro);
      std::printf("weak direction of %s row %d: sigma %.3g -> %.3g (%s)\n", gyro ? "G + gyro bias" : "accel", row,
                  w_before * (gyro ? 3600.0 / kDegToRad * kStandardGravity_mps2 : 1e6), 
                  w_after * (gyro ? 3600.0 / kDegToRad * kStandardGravity_mps2 : 1e6), gyro ? "deg/h/g" : "ppm");
      EXPECT_LT(w_after, 0.6 * w_before) << row << gyro;  // measured 0.51 for every row
    }
  }
}

TEST(PendulumCalibrationTest, OneMountingReportsWhatItCannotObserve) {
  // NED alone: the pendulum turns about the IMU y axis and the specific force stays in x-z.
  const ImuCalibrationResult r = CalibratePendulum(SimulateRuns({0}, 30.0, DrawnErrors(), 3).data);
  const auto listed = [&r](const std::string& name) {
    for (const std::string& u : r.unobservable) {
      if (u.compare(0, name.size() + 1, name + ":") == 0) return true;
    }
    return false;
  };
  for (const char* name : {"accel.scale_factor.y", "accel.misalignment.xy", "accel.misalignment.zy",
                           "gyro.scale_factor.x", "gyro.scale_factor.z", "gyro.misalignment.xz",
                           "gyro.misalignment.yx", "gyro.misalignment.yz", "gyro.misalignment.zx",
                           "g_sensitivity.xy", "g_sensitivity.yy", "g_sensitivity.zy"}) {
    EXPECT_TRUE(listed(name)) << name;
  }
  for (const std::string& u : r.unobservable) std::printf("  %s\n", u.c_str());
  // Estimated parameters have finite sigma; the unobservable are 0 with NaN sigma.
  const Eigen::VectorXd est = Estimated(r.calibration), sigma = Sigmas(r.calibration);
  EXPECT_EQ(r.estimated.size() + r.unobservable.size(), 33u);
  EXPECT_TRUE(est.allFinite());
  for (int i = 0; i < 33; ++i) {
    if (std::isnan(sigma(i))) {
      EXPECT_EQ(est(i), 0.0);
    }
  }
}

TEST(PendulumCalibrationTest, NoRunIsRefused) {
  try {
    CalibratePendulum(PendulumData());
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no run"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------- files

class TempDir {
 public:
  TempDir() {
    std::string t = ::testing::TempDir() + "navtwin_pendulum_XXXXXX";
    if (::mkdtemp(t.data()) == nullptr) throw std::runtime_error("mkdtemp");
    dir_ = t;
  }
  ~TempDir() { std::filesystem::remove_all(dir_); }
  std::string Write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ + "/" + name) << text;
    return dir_ + "/" + name;
  }
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
};

TEST(PendulumCalibrationTest, RecordThroughSimulatedFiles) {
  // `navtwin simulate` of the four mountings (fixed errors, encoder noise and quantum),
  // then the record file that points at their imu.txt and angle.csv.
  const std::string errors =
      "imu:\n  rate_hz: 100\n  errors:\n"
      "    gyro: {bias_fixed_deg_h: [20, -10, 5], scale_factor_fixed_ppm: [500, -300, 200],\n"
      "           misalignment_fixed_arcsec: [[0, 200, -100], [150, 0, 300], [-250, 100, 0]],\n"
      "           arw_deg_sqrt_h: 0.1}\n"
      "    accel: {bias_fixed_ug: [1000, -500, 2000], scale_factor_fixed_ppm: [-400, 600, 300],\n"
      "            misalignment_fixed_arcsec: [[0, -150, 200], [100, 0, -300], [250, 50, 0]],\n"
      "            vrw_m_s_sqrt_h: 0.05}\n"
      "    g_sensitivity_fixed_deg_h_per_g: [[3, -2, 1], [0, 4, -1], [2, 1, -3]]\n";
  std::vector<std::unique_ptr<sim::TemporarySimulation>> sims;
  std::string record = "latitude_deg: 37.45\nheight_m: 40\nruns:\n";
  for (std::size_t m = 0; m < MountingKeys().size(); ++m) {
    const std::string yaml =
        "name: pendulum\nduration_s: 40\nstart: {lat_deg: 37.45, lon_deg: 126.65, h_m: 40}\n"
        "trajectory: {kind: pendulum, length_m: 0.8, damping_per_s: 0.05, initial_angle_deg: 40,"
        " angle_noise_deg: 0.01, angle_quantum_deg: 0.001, " +
        MountingKeys()[m] + "}\n" + errors;
    sim::SimulationOptions options;
    options.seed = 20 + m;
    sims.push_back(std::make_unique<sim::TemporarySimulation>(sim::ParseScenario(ParseYaml(yaml, "s.yaml")),
                                                              options, "navtwin_pendulum_sim_"));
    record += "  - {imu: " + sims.back()->path("imu.txt") + ", angle: " + sims.back()->path("angle.csv") +
              ", length_m: 0.8, " + MountingKeys()[m] + "}\n";
  }
  TempDir dir;
  const ImuCalibrationResult r = CalibratePendulumRecord(dir.Write("record.yaml", record));
  EXPECT_EQ(r.positions, 4);
  ASSERT_EQ(r.estimated.size(), 33u);
  Eigen::VectorXd truth(33);
  truth << -400e-6, 600e-6, 300e-6, -150 * kArcsec_rad, 200 * kArcsec_rad, 100 * kArcsec_rad, -300 * kArcsec_rad, 250 * kArcsec_rad,
      50 * kArcsec_rad, 1000 * kMicroG_mps2, -500 * kMicroG_mps2, 2000 * kMicroG_mps2,  //
      500e-6, -300e-6, 200e-6, 200 * kArcsec_rad, -100 * kArcsec_rad, 150 * kArcsec_rad, 300 * kArcsec_rad, -250 * kArcsec_rad,
      100 * kArcsec_rad, 20 * kDegPerHour_radps, -10 * kDegPerHour_radps, 5 * kDegPerHour_radps,  //
      3, -2, 1, 0, 4, -1, 2, 1, -3;
  truth.tail(9) *= kDegPerHour_radps / kStandardGravity_mps2;
  const Eigen::VectorXd est = Estimated(r.calibration), sigma = Sigmas(r.calibration);
  for (int i = 0; i < 33; ++i) {
    // One draw of 33 parameters: 4 sigma (false alarm < 0.3 %).
    EXPECT_LT(std::fabs(est(i) - truth(i)), 4.0 * sigma(i)) << r.estimated[i];
  }
}

TEST(PendulumCalibrationTest, BadAngleFilesNameFileLineAndField) {
  TempDir dir;
  const auto expect_input_error = [&dir](const std::string& text, long line, const std::string& field) {
    const std::string path = dir.Write("angle.csv", text);
    try {
      ReadAngleFile(path);
      ADD_FAILURE() << "no InputError for " << text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.line(), line) << e.what();
      EXPECT_EQ(e.field(), field) << e.what();
    }
  };
  expect_input_error("t_s,angle_rad\n0,0.1\n", 1, "theta_rad");
  expect_input_error("t_s,theta_rad\n0,0.1\n0.01,nan\n", 3, "theta_rad");
  expect_input_error("t_s,theta_rad\n0,0.1\n0.01,0.2\n0.005,0.3\n", 4, "t_s");
  expect_input_error("t_s,theta_rad\n0,0.1\n0.01\n", 3, "");
  // theta_deg is read in degrees.
  const AngleRecord deg = ReadAngleFile(dir.Write("deg.csv", "t_s,theta_deg\n0,90\n"));
  EXPECT_NEAR(deg.theta_rad[0], M_PI / 2, 1e-15);
}

TEST(PendulumCalibrationTest, BadRecordsNameTheKey) {
  TempDir dir;
  const auto expect_input_error = [&dir](const std::string& text, const std::string& part) {
    try {
      CalibratePendulumRecord(dir.Write("record.yaml", text));
      ADD_FAILURE() << "no InputError for " << part;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  expect_input_error("height_m: 0\nruns: []\n", "latitude_deg");
  expect_input_error("latitude_deg: 37\nruns:\n  - {imu: a.txt, angle: b.csv, length_m: 1}\n", "runs[0].mounting");
  expect_input_error("latitude_deg: 37\nruns:\n  - {imu: a.txt, angle: b.csv, length_m: 1, mounting: NEU}\n",
                     "right-handed");
  expect_input_error("latitude_deg: 37\nruns:\n  - {imu: a.txt, angle: b.csv, mounting: NED}\n", "runs[0].length_m");
  expect_input_error("latitude_deg: 37\nruns:\n  - {imu: missing.txt, angle: b.csv, length_m: 1, mounting: NED}\n",
                     "missing.txt");
  // An empty list of runs is data that cannot calibrate.
  try {
    CalibratePendulumRecord(dir.Write("record.yaml", "latitude_deg: 37\nruns: []\n"));
    ADD_FAILURE() << "no runtime_error for no runs";
  } catch (const InputError& e) {
    ADD_FAILURE() << e.what();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no run"), std::string::npos) << e.what();
  }
}

}  // namespace calibration_pendulum_test
}  // namespace navtwin::calibration
