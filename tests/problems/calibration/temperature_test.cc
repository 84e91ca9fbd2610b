// Temperature calibration (problems/calibration/temperature.h). The polynomial fit alone on
// synthetic points (exactness, honest covariance over 2000 noisy trials, chi-square, the
// coverage checks); then the whole calibration on chamber runs simulated in memory: a
// multi-position table (+1 g and -1 g on every axis) at -20, 15 and 50 degC (the seed's
// chamber) with the SAME fixed error constants in every run and independent noise, the
// recovered polynomial coefficients against the simulator's truth, a Monte Carlo of the
// 3-sigma fraction, orders 1 and 3, the errors for bad data, and one calibration through
// a record file. Then warm-up data (CalibrateWarmUp): one 16-position run warming from 0 to
// 40 degC, its Monte Carlo, the span check, the temperature file's errors, and a warm-up
// simulated into files (imu.txt, temperature.csv) and calibrated through a record.
#include "problems/calibration/temperature.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <stdlib.h>

#include <gtest/gtest.h>

#include "core/io/input_error.h"
#include "core/io/kfgins.h"
#include "core/sim/analytic_trajectory.h"
#include "core/sim/calibration_rig.h"
#include "core/sim/inertial_errors.h"
#include "core/sim/random.h"
#include "core/sim/scenario.h"
#include "core/sim/simulator.h"
#include "core/units.h"

namespace navtwin::calibration {
namespace calibration_temperature_test {


// ---------------------------------------------------------------------------------------
// The polynomial fit alone.

/// Expects `fn` to throw std::runtime_error whose message contains `text`.
template <typename F>
void ExpectRuntimeError(F fn, const std::string& text) {
  try {
    fn();
    ADD_FAILURE() << "no exception; expected one containing \"" << text << "\"";
  } catch (const InputError& e) {
    ADD_FAILURE() << "InputError instead of std::runtime_error: " << e.what();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

std::vector<TemperaturePoint> PointsOn(const std::vector<double>& temperatures_degC, const std::vector<double>& c,
                                       double reference_degC, double sigma, sim::Rng* noise) {
  std::vector<TemperaturePoint> points;
  for (double t : temperatures_degC) {
    const double dT = t - reference_degC;
    double v = 0.0;
    for (int k = static_cast<int>(c.size()) - 1; k >= 0; --k) v = v * dT + c[k];
    if (noise != nullptr) v += noise->Normal(sigma);
    points.push_back({t, v, sigma});
  }
  return points;
}

TEST(TemperaturePolynomial, ExactQuadraticIsRecovered) {
  const std::vector<double> c = {0.05, 1e-4, 2e-6};
  const auto points = PointsOn({-20.0, 15.0, 50.0}, c, 25.0, 1e-4, nullptr);
  const TemperaturePolynomial fit = FitTemperaturePolynomial(points, 2, 25.0);
  ASSERT_EQ(fit.order(), 2);
  // Noise-free points: only rounding (relative ~1e-15, amplified by the 3x3 solve).
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(fit.coefficients(k), c[k], 1e-11 * std::abs(c[k])) << k;
  EXPECT_EQ(fit.dof, 0);
  EXPECT_LT(fit.chi_square, 1e-12);  // three points, three coefficients: exact
  EXPECT_NEAR(fit.Evaluate(50.0), points[2].value, 1e-15);
}

TEST(TemperaturePolynomial, OrderZeroIsTheWeightedMean) {
  const std::vector<TemperaturePoint> points = {{10.0, 1.0, 1.0}, {20.0, 2.0, 0.5}, {30.0, 4.0, 2.0}};
  const TemperaturePolynomial fit = FitTemperaturePolynomial(points, 0, 20.0);
  const double w1 = 1.0, w2 = 4.0, w3 = 0.25;
  EXPECT_NEAR(fit.coefficients(0), (w1 * 1.0 + w2 * 2.0 + w3 * 4.0) / (w1 + w2 + w3), 1e-14);  // rounding
  EXPECT_NEAR(fit.covariance(0, 0), 1.0 / (w1 + w2 + w3), 1e-14);                             // rounding
  EXPECT_EQ(fit.dof, 2);
}

TEST(TemperaturePolynomial, ReferenceOnlyReparameterises) {
  sim::Rng rng(11);
  const auto points = PointsOn({-30.0, -5.0, 20.0, 45.0, 70.0}, {1.0, 0.01, 1e-4}, 0.0, 0.01, &rng);
  const TemperaturePolynomial a = FitTemperaturePolynomial(points, 2, 20.0);
  const TemperaturePolynomial b = FitTemperaturePolynomial(points, 2, -7.0);
  // The same polynomial in another variable: equal values and equal chi-square (rounding).
  for (double t : {-40.0, 0.0, 33.0, 80.0}) EXPECT_NEAR(a.Evaluate(t), b.Evaluate(t), 1e-12) << t;
  EXPECT_NEAR(a.chi_square, b.chi_square, 1e-9);
  // The leading coefficient does not depend on the reference.
  EXPECT_NEAR(a.coefficients(2), b.coefficients(2), 1e-15);
}

// 2000 noisy trials of a cubic at 6 temperatures: the coefficients' errors follow the
// reported covariance (variance ratio near 1, >= 99 % within 3 sigma per coefficient) and
// the chi-square averages its dof.
TEST(TemperaturePolynomial, CovarianceAndChiSquareAreHonest) {
  const std::vector<double> c = {0.3, -2e-3, 5e-5, 1e-6};
  const std::vector<double> temperatures = {-40.0, -20.0, 0.0, 25.0, 50.0, 85.0};
  const double reference = 25.0;
  const int trials = 2000;
  sim::Rng rng(2024);
  std::vector<int> within(4, 0);
  std::vector<double> sum_z2(4, 0.0);
  double sum_chi2 = 0.0;
  for (int t = 0; t < trials; ++t) {
    // Unequal sigmas so that the weights matter.
    std::vector<TemperaturePoint> points = PointsOn(temperatures, c, reference, 1.0, nullptr);
    for (std::size_t i = 0; i < points.size(); ++i) {
      points[i].sigma = 1e-3 * (1.0 + static_cast<double>(i % 3));
      points[i].value += rng.Normal(points[i].sigma);
    }
    const TemperaturePolynomial fit = FitTemperaturePolynomial(points, 3, reference);
    for (int k = 0; k < 4; ++k) {
      const double z = (fit.coefficients(k) - c[k]) / std::sqrt(fit.covariance(k, k));
      within[k] += std::abs(z) <= 3.0;
      sum_z2[k] += z * z;
    }
    sum_chi2 += fit.chi_square;
  }
  for (int k = 0; k < 4; ++k) {
    std::cout << "c" << k << ": within 3 sigma " << 100.0 * within[k] / trials << " %, mean z^2 "
              << sum_z2[k] / trials << "\n";
  }
  std::cout << "mean chi-square " << sum_chi2 / trials << " (dof 2)\n";
  for (int k = 0; k < 4; ++k) {
    // 3 sigma holds for 99.73 %; 99 % leaves > 6 binomial sigmas (sd 0.12 %) of margin.
    EXPECT_GE(within[k], 0.99 * trials) << "coefficient " << k;
    // Mean z^2 of 2000 trials: sd sqrt(2/2000) = 0.032; 0.15 is ~5 sd.
    EXPECT_NEAR(sum_z2[k] / trials, 1.0, 0.15) << "coefficient " << k;
  }
  // dof 2: mean chi-square 2, sd of the mean sqrt(4/2000) = 0.045; 0.25 is ~5 sd.
  EXPECT_NEAR(sum_chi2 / trials, 2.0, 0.25);
}

TEST(TemperaturePolynomial, TooFewTemperaturesForTheOrder) {
  const auto two = PointsOn({-20.0, 50.0, 50.4}, {1.0, 0.0, 0.0}, 15.0, 0.1, nullptr);
  // 50 and 50.4 degC are one set point (closer than 1 degC).
  ExpectRuntimeError([&] { FitTemperaturePolynomial(two, 2, 15.0); },
                     "order 2 needs at least 3 temperatures, got 2");
  ExpectRuntimeError([&] { FitTemperaturePolynomial(two, 3, 15.0); },
                     "order 3 needs at least 4 temperatures, got 2");
}

TEST(TemperaturePolynomial, SpanTooSmallForTheOrder) {
  const auto narrow = PointsOn({20.0, 25.0, 30.0}, {1.0, 0.0, 0.0}, 25.0, 0.1, nullptr);
  ExpectRuntimeError([&] { FitTemperaturePolynomial(narrow, 2, 25.0); },
                     "order 2 needs a temperature span of at least 20 degC");
  // Order 1 needs 10 degC: the same points are enough.
  EXPECT_NO_THROW(FitTemperaturePolynomial(narrow, 1, 25.0));
  // A smaller minimum (an option) lets the quadratic through.
  EXPECT_NO_THROW(FitTemperaturePolynomial(narrow, 2, 25.0, 5.0));
}

TEST(TemperaturePolynomial, BadSigmaOrValue) {
  auto points = PointsOn({-20.0, 15.0, 50.0}, {1.0}, 15.0, 0.1, nullptr);
  points[1].sigma = 0.0;
  ExpectRuntimeError([&] { FitTemperaturePolynomial(points, 2, 15.0, kMinSpanPerOrderDegC, "accel.bias.x"); },
                     "accel.bias.x: the sigma at 15 degC must be finite and > 0");
  points[1].sigma = 0.1;
  points[2].value = std::numeric_limits<double>::quiet_NaN();
  ExpectRuntimeError([&] { FitTemperaturePolynomial(points, 2, 15.0); }, "not finite");
}

// ---------------------------------------------------------------------------------------
// Chamber runs simulated in memory.

constexpr double kLatitudeDeg = 30.5;
constexpr double kHeightM = 20.0;
constexpr double kRateHz = 50.0;
constexpr double kSimReferenceDegC = 25.0;

const std::vector<Eigen::Vector3d> kSixPositionsDeg = {{0, 0, 0},  {180, 0, 0}, {90, 0, 0},
                                                     {-90, 0, 0}, {0, 90, 0},  {0, -90, 0}};
/// The z axis always horizontal (rolled or pitched by 90 deg): no gravity on z at all.
const std::vector<Eigen::Vector3d> kZHorizontalDeg = {{90, 0, 0},  {-90, 0, 0}, {0, 90, 0},
                                                    {0, -90, 0}, {90, 0, 90}, {-90, 0, 90}};

/// A table schedule holding each attitude (roll, pitch, yaw in deg) for dwell_s.
sim::MultiPositionConfig Schedule(const std::vector<Eigen::Vector3d>& euler_deg, double dwell_s) {
  sim::MultiPositionConfig c;
  c.rotation_s = 2.0;
  for (const Eigen::Vector3d& e : euler_deg) {
    sim::TableStep s;
    s.euler_rad = e * kDegToRad;
    s.dwell_s = dwell_s;
    c.steps.push_back(s);
  }
  return c;
}

/// The truth: fixed constants (the same in every run), quadratic in T - 25 degC, with
/// temperature effects large against a 3-run calibration's sigma.
sim::InertialErrorConfig TruthErrors() {
  sim::InertialErrorConfig e;
  e.gyro.bias.fixed = Eigen::Vector3d(1.0e-4, -0.6e-4, 0.8e-4);          // ~20 deg/h
  e.gyro.bias_per_degC.fixed = Eigen::Vector3d(2e-6, -1.5e-6, 1e-6);     // ~0.4 deg/h/degC
  e.gyro.bias_per_degC2.fixed = Eigen::Vector3d(4e-8, 3e-8, -5e-8);      // ~0.01 deg/h/degC^2
  e.gyro.scale_factor.fixed = Eigen::Vector3d(500e-6, -300e-6, 200e-6);
  e.gyro.misalignment.fixed = (Eigen::Matrix3d() << 0, 1e-3, -0.5e-3, 0.7e-3, 0, 0.4e-3, -0.8e-3, 0.3e-3, 0).finished();
  e.gyro.white_noise = 5e-5;  // rad/sqrt(s): 0.17 deg/sqrt(h)
  e.accel.bias.fixed = Eigen::Vector3d(0.03, -0.05, 0.04);                   // 3-5 mg
  e.accel.bias_per_degC.fixed = Eigen::Vector3d(2e-4, -1e-4, 1.5e-4);        // ~20 ug/degC
  e.accel.bias_per_degC2.fixed = Eigen::Vector3d(3e-6, -2e-6, 4e-6);
  e.accel.scale_factor.fixed = Eigen::Vector3d(1000e-6, -800e-6, 600e-6);
  e.accel.scale_factor_per_degC.fixed = Eigen::Vector3d(20e-6, -15e-6, 25e-6);  // ppm/degC
  e.accel.scale_factor_per_degC2.fixed = Eigen::Vector3d(0.3e-6, 0.2e-6, -0.4e-6);
  e.accel.misalignment.fixed = (Eigen::Matrix3d() << 0, 0.5e-3, 0.2e-3, -0.3e-3, 0, 0.6e-3, 0.4e-3, -0.1e-3, 0).finished();
  e.accel.white_noise = 2e-3;  // m/s/sqrt(s)
  e.g_sensitivity.fixed = 1e-5 * (Eigen::Matrix3d() << 1, -2, 0.5, 0.3, 1.5, -1, 2, 0.4, -0.8).finished();
  e.temperature.reference_degC = kSimReferenceDegC;
  return e;
}

/// One run soaked at temperature_degC: the exact increments of the table schedule through
/// the error model (its noise from `seed`).
TemperatureRun SimulateRun(const sim::InertialErrorConfig& errors, const sim::MultiPositionConfig& schedule,
                           double temperature_degC, std::uint64_t seed) {
  sim::InertialErrorConfig e = errors;
  e.temperature.initial_degC = e.temperature.final_degC = temperature_degC;
  sim::InertialErrorModel model(e, sim::Rng(seed).Stream("imu"), false);
  const sim::MultiPositionRig rig(schedule);
  TemperatureRun run;
  run.temperature_degC = temperature_degC;
  run.data.schedule = schedule;
  run.data.latitude_rad = kLatitudeDeg * kDegToRad;
  run.data.height_m = kHeightM;
  run.data.imu_path = "run at " + std::to_string(temperature_degC) + " degC";
  const wgs84::Geodetic start{kLatitudeDeg * kDegToRad, 114.0 * kDegToRad, kHeightM};
  sim::SynthesizeImu(rig, start, kRateHz, rig.duration_s(), [&](const ImuSample& s, const NavState&) {
    if (s.dt_s <= 0.0) return;  // the initial state, no increment
    ImuSample m = s;
    model.Apply(s.t_s, s.dt_s, temperature_degC, s.dtheta_b_rad, s.dv_b_mps, &m.dtheta_b_rad, &m.dv_b_mps);
    run.data.imu.push_back(m);
  });
  return run;
}

std::vector<TemperatureRun> SimulateChamber(const sim::InertialErrorConfig& errors,
                                            const std::vector<double>& temperatures_degC, double dwell_s,
                                            std::uint64_t seed) {
  std::vector<TemperatureRun> runs;
  const sim::MultiPositionConfig schedule = Schedule(kSixPositionsDeg, dwell_s);
  for (std::size_t i = 0; i < temperatures_degC.size(); ++i) {
    runs.push_back(SimulateRun(errors, schedule, temperatures_degC[i], seed * 1000 + i));
  }
  return runs;
}

/// Truth of the polynomial coefficients c_0..c_order of one parameter, re-expanded about
/// `reference_degC` (the simulator's is 25 degC): p = c + b u + a u^2 with u = dT + delta.
std::vector<double> TruthCoefficients(double c, double b, double a, double reference_degC, int order) {
  const double delta = reference_degC - kSimReferenceDegC;
  std::vector<double> out(order + 1, 0.0);
  out[0] = c + b * delta + a * delta * delta;
  if (order >= 1) out[1] = b + 2.0 * a * delta;
  if (order >= 2) out[2] = a;
  return out;
}

struct Truth {
  std::string name;
  std::vector<double> coefficients;  ///< c_0..c_order (pooled: c_0 only)
};

/// Every estimated parameter of the result with its truth.
std::vector<Truth> TruthOf(const sim::InertialErrorConfig& e, double reference_degC, int order) {
  std::vector<Truth> truth;
  for (const char* triad : {"gyro", "accel"}) {
    const sim::TriadErrorConfig& t = std::string(triad) == "gyro" ? e.gyro : e.accel;
    for (int axis = 0; axis < 3; ++axis) {
      truth.push_back({TriadParameterName(triad, axis),
                       TruthCoefficients((*t.scale_factor.fixed)(axis),
                                         t.scale_factor_per_degC.fixed ? (*t.scale_factor_per_degC.fixed)(axis) : 0.0,
                                         t.scale_factor_per_degC2.fixed ? (*t.scale_factor_per_degC2.fixed)(axis) : 0.0,
                                         reference_degC, order)});
      truth.push_back({TriadParameterName(triad, 9 + axis),
                       TruthCoefficients((*t.bias.fixed)(axis), (*t.bias_per_degC.fixed)(axis),
                                         (*t.bias_per_degC2.fixed)(axis), reference_degC, order)});
    }
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col) {
        if (r != col) {
          truth.push_back({TriadParameterName(triad, MisalignmentIndex(r, col)), {(*t.misalignment.fixed)(r, col)}});
        }
      }
    }
  }
  for (int i = 0; i < 9; ++i) truth.push_back({GSensitivityParameterName(i), {(*e.g_sensitivity.fixed)(i / 3, i % 3)}});
  return truth;
}

/// z = (estimate - truth) / sigma of every estimated coefficient ("<name>" for c_0,
/// "<name>.dT<k>" for c_k).
std::vector<std::pair<std::string, double>> ZScores(const TemperatureCalibration& cal,
                                                    const std::vector<Truth>& truth) {
  std::vector<std::pair<std::string, double>> z;
  const ImuCalibrationResult& r = cal.result;
  for (std::size_t i = 0; i < r.estimated.size(); ++i) {
    const std::string& name = r.estimated[i];
    const std::size_t dot = name.rfind(".dT");
    const std::string base = dot == std::string::npos ? name : name.substr(0, dot);
    const int k = dot == std::string::npos ? 0 : std::atoi(name.c_str() + dot + 3);
    double estimate = 0.0;
    bool found = false;
    for (const auto* fits : {&cal.fits, &cal.pooled}) {
      for (const TemperatureParameterFit& f : *fits) {
        if (f.name == base) {
          estimate = f.fit.coefficients(k);
          found = true;
        }
      }
    }
    EXPECT_TRUE(found) << name;
    for (const Truth& t : truth) {
      if (t.name == base && k < static_cast<int>(t.coefficients.size())) {
        z.push_back({name, (estimate - t.coefficients[k]) / std::sqrt(r.covariance(i, i))});
      }
    }
  }
  return z;
}

TEST(TemperatureCalibration, SeedChamberRecoversTheQuadratics) {
  const sim::InertialErrorConfig errors = TruthErrors();
  const std::vector<TemperatureRun> runs = SimulateChamber(errors, {-20.0, 15.0, 50.0}, 10.0, 1);
  TemperatureCalibrationOptions options;
  options.reference_degC = kSimReferenceDegC;
  const TemperatureCalibration cal = CalibrateTemperature(runs, options);
  const ImuCalibrationResult& r = cal.result;
  ASSERT_TRUE(r.calibration.temperature.has_value());
  EXPECT_EQ(r.calibration.temperature->reference_degC, kSimReferenceDegC);
  ASSERT_EQ(r.calibration.temperature->accel_bias_mps2.size(), 2u);
  ASSERT_EQ(r.covariance.rows(), static_cast<int>(r.estimated.size()));
  EXPECT_TRUE(r.covariance.allFinite());

  const std::vector<Truth> truth = TruthOf(errors, kSimReferenceDegC, 2);
  for (const TemperatureParameterFit& f : cal.fits) {
    if (f.name != "accel.scale_factor.x" && f.name != "accel.bias.x" && f.name != "gyro.bias.x") continue;
    for (const Truth& t : truth) {
      if (t.name != f.name) continue;
      for (int k = 0; k <= 2; ++k) {
        std::cout << f.name << " c" << k << ": " << f.fit.coefficients(k) << " +- "
                  << std::sqrt(f.fit.covariance(k, k)) << " (truth " << t.coefficients[k] << ")\n";
      }
    }
  }
  const auto z = ZScores(cal, truth);
  EXPECT_EQ(z.size(), 57u);  // 12 scale factors and biases x 3 coefficients, 12 misalignments, 9 G  // 12 accel + gyro bias coefficients x 3 (at least), misalignments, G
  for (const auto& [name, score] : z) {
    // One fixed draw of ~60 coefficients: 4.5 sigma leaves them all inside with
    // probability > 0.9995 when the sigma is honest.
    EXPECT_LT(std::abs(score), 4.5) << name;
  }
  // The temperature effects are resolved, not just consistent: each linear coefficient
  // below is > 5 sigma away from 0 (so the test would see a fit that ignored temperature).
  for (const char* name : {"accel.scale_factor.x.dT1", "accel.bias.z.dT1", "gyro.bias.x.dT1"}) {
    const auto it = std::find(r.estimated.begin(), r.estimated.end(), name);
    ASSERT_NE(it, r.estimated.end()) << name;
    const int i = static_cast<int>(it - r.estimated.begin());
    double value = 0.0;
    for (const TemperatureParameterFit& f : cal.fits) {
      if (name == f.name + ".dT1") value = f.fit.coefficients(1);
    }
    std::cout << name << " = " << value << " +- " << std::sqrt(r.covariance(i, i)) << "\n";
    EXPECT_GT(std::abs(value) / std::sqrt(r.covariance(i, i)), 5.0) << name;
  }
  // The constant blocks are the values at the reference: the temperature terms evaluate
  // back to the per-run estimates (exact fit: 3 runs, order 2).
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const ImuCalibration at = r.calibration.At(runs[k].temperature_degC);
    for (int i : {0, 1, 2, 9, 10, 11}) {
      // Exact interpolation through three points: rounding only (values ~1e-2 .. 1e-4).
      EXPECT_NEAR(at.accel(i), cal.runs[k].calibration.accel(i), 1e-12) << i;
      EXPECT_NEAR(at.gyro(i), cal.runs[k].calibration.gyro(i), 1e-12) << i;
    }
  }
  EXPECT_EQ(r.positions, 18);
  EXPECT_GT(r.accel_residual_rms_mps2, 0.0);
  // The residual rows: every position of every run at its run's temperature, after
  // calibration with the polynomial model (exact through three runs: the per-run fits').
  ASSERT_EQ(r.residuals.size(), 18u);
  double ss_after = 0.0, ss_before = 0.0;
  for (const CalibrationResidual& res : r.residuals) {
    ASSERT_GE(res.run, 0);
    ASSERT_LT(res.run, static_cast<int>(runs.size()));
    EXPECT_EQ(res.temperature_degC, runs[res.run].temperature_degC);
    ss_after += res.accel_after_mps2.squaredNorm();
    ss_before += res.accel_before_mps2.squaredNorm();
  }
  // The accelerometer's 6 misalignments are one set for all runs here, each run's own fit
  // had its own (dof 18 of 54 residuals; shared: 30). With the simulated misalignments
  // constant, ratio^2 = 1 + chi2(12)/chi2(18): above 1, and below 2.02 with probability
  // 0.999 (F(12, 18) quantile 4.6). Measured 1.63.
  const double ratio = std::sqrt(ss_after / 54.0) / r.accel_residual_rms_mps2;
  std::cout << "residual RMS after, polynomial model / per-run fits: " << ratio << "\n";
  EXPECT_GT(ratio, 0.99);
  EXPECT_LT(ratio, 2.02);
  EXPECT_GT(ss_before, 100.0 * ss_after);
}


/// Checks every z-score of one calibration against `limit` (with the reason at the caller).
void ExpectAllWithin(const std::vector<std::pair<std::string, double>>& z, double limit) {
  for (const auto& [name, score] : z) EXPECT_LT(std::abs(score), limit) << name;
}

// Order 1 on a truth that is linear in temperature (quadratic terms 0).
TEST(TemperatureCalibration, OrderOne) {
  sim::InertialErrorConfig errors = TruthErrors();
  errors.gyro.bias_per_degC2.fixed = Eigen::Vector3d::Zero();
  errors.accel.bias_per_degC2.fixed = Eigen::Vector3d::Zero();
  errors.accel.scale_factor_per_degC2.fixed = Eigen::Vector3d::Zero();
  const std::vector<TemperatureRun> runs = SimulateChamber(errors, {-20.0, 15.0, 50.0}, 6.0, 2);
  TemperatureCalibrationOptions options;
  options.order = 1;
  const TemperatureCalibration cal = CalibrateTemperature(runs, options);
  // Default reference: the mean of the run temperatures.
  EXPECT_NEAR(cal.result.calibration.temperature->reference_degC, 15.0, 1e-12);  // rounding
  EXPECT_EQ(cal.result.calibration.temperature->accel_scale_factor.size(), 1u);
  ASSERT_FALSE(cal.fits.empty());
  EXPECT_EQ(cal.fits.front().fit.dof, 1);  // 3 runs, 2 coefficients
  // One fixed draw of ~50 coefficients: 4.5 sigma (see SeedChamberRecoversTheQuadratics).
  ExpectAllWithin(ZScores(cal, TruthOf(errors, 15.0, 1)), 4.5);
}

// Order 3 from four set points; the truth's cubic term is 0.
TEST(TemperatureCalibration, OrderThree) {
  const sim::InertialErrorConfig errors = TruthErrors();
  const std::vector<TemperatureRun> runs = SimulateChamber(errors, {-20.0, 5.0, 30.0, 55.0}, 6.0, 3);
  TemperatureCalibrationOptions options;
  options.order = 3;
  options.reference_degC = kSimReferenceDegC;
  const TemperatureCalibration cal = CalibrateTemperature(runs, options);
  EXPECT_EQ(cal.result.calibration.temperature->gyro_bias_rad_per_s.size(), 3u);
  const auto z = ZScores(cal, TruthOf(errors, kSimReferenceDegC, 3));
  int cubic = 0;
  for (const auto& [name, score] : z) cubic += name.size() > 4 && name.compare(name.size() - 4, 4, ".dT3") == 0;
  // Scale factor and bias of both triads (the moves between positions turn the IMU about
  // every axis, so the gyro scale factor is observable too).
  EXPECT_EQ(cubic, 12);
  ExpectAllWithin(z, 4.5);  // one fixed draw of ~70 coefficients: see SeedChamberRecoversTheQuadratics
}

// Monte Carlo: the seed's chamber (3 set points, order 2) with independent noise in every
// calibration; the fraction of coefficients within 3 sigma of the truth.
/// Tally of z-scores over Monte Carlo calibrations: pooled, temperature terms, per name.
struct SigmaTally {
  std::map<std::string, int> within;
  int total = 0, total_within = 0, temperature_terms = 0, temperature_within = 0;

  void Add(const std::string& name, double score) {
    const bool in = std::abs(score) <= 3.0;
    within[name] += in;
    ++total;
    total_within += in;
    if (name.find(".dT") != std::string::npos) {
      ++temperature_terms;
      temperature_within += in;
    }
  }
  double fraction() const { return static_cast<double>(total_within) / total; }
  double temperature_fraction() const { return static_cast<double>(temperature_within) / temperature_terms; }
  /// The coefficient within 3 sigma least often, and how often.
  std::pair<std::string, int> Worst() const {
    std::pair<std::string, int> worst{"", std::numeric_limits<int>::max()};
    for (const auto& [name, n] : within) {
      if (n < worst.second) worst = {name, n};
    }
    return worst;
  }
  /// The criterion: >= 95 % within 3 sigma, pooled, for the temperature terms, and
  /// per coefficient (fewer than 95 of 100 by chance has p ~ 1e-6 for an honest sigma).
  void Check(int calibrations, const std::string& what) const {
    const auto [worst_name, worst] = Worst();
    std::cout << calibrations << " " << what << ", " << within.size() << " coefficients each: " << 100.0 * fraction()
              << " % within 3 sigma (temperature coefficients " << 100.0 * temperature_fraction() << " %); worst "
              << worst_name << " " << worst << "/" << calibrations << "\n";
    EXPECT_GE(fraction(), 0.95);
    EXPECT_GE(temperature_fraction(), 0.95);
    EXPECT_GE(worst, 95 * calibrations / 100) << worst_name;
  }
};

TEST(TemperatureCalibration, MonteCarloSigmaIsHonest) {
  const sim::InertialErrorConfig errors = TruthErrors();
  const int calibrations = 100;
  SigmaTally tally;
  for (int m = 0; m < calibrations; ++m) {
    const std::vector<TemperatureRun> runs = SimulateChamber(errors, {-20.0, 15.0, 50.0}, 3.0, 100 + m);
    TemperatureCalibrationOptions options;
    options.reference_degC = kSimReferenceDegC;
    const TemperatureCalibration cal = CalibrateTemperature(runs, options);
    for (const auto& [name, score] : ZScores(cal, TruthOf(errors, kSimReferenceDegC, 2))) {
      tally.Add(name, score);
    }
  }
  tally.Check(calibrations, "calibrations");
}

TEST(TemperatureCalibration, TooFewTemperatures) {
  const std::vector<TemperatureRun> runs = SimulateChamber(TruthErrors(), {-20.0, 50.0}, 3.0, 4);
  ExpectRuntimeError([&] { CalibrateTemperature(runs); }, "order 2 needs at least 3 temperatures, got 2");
}

TEST(TemperatureCalibration, SpanTooSmall) {
  const std::vector<TemperatureRun> runs = SimulateChamber(TruthErrors(), {20.0, 25.0, 30.0}, 3.0, 5);
  ExpectRuntimeError([&] { CalibrateTemperature(runs); },
                     "order 2 needs a temperature span of at least 20 degC (10 degC per order), got 10 degC");
}

// The middle run never puts gravity on z: its accelerometer z scale factor is unobservable
// there, so no polynomial can be fitted.
TEST(TemperatureCalibration, RunWithoutGravityOnAnAxis) {
  const sim::InertialErrorConfig errors = TruthErrors();
  std::vector<TemperatureRun> runs = SimulateChamber(errors, {-20.0, 15.0, 50.0}, 3.0, 6);
  runs[1] = SimulateRun(errors, Schedule(kZHorizontalDeg, 3.0), 15.0, 6001);
  ExpectRuntimeError([&] { CalibrateTemperature(runs); }, "accel.scale_factor.z cannot be estimated in run 1 (15 degC)");
}

// ---------------------------------------------------------------------------------------
// Through a record file.

class TemperatureRecord : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = ::testing::TempDir() + "navtwin_temperature_XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  std::string Write(const std::string& name, const std::string& text) {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path) << text;
    return path;
  }
  std::string dir_;
};

/// A record's table schedule in the simulator's YAML schema.
std::string ScheduleYaml(const std::vector<Eigen::Vector3d>& euler_deg, double dwell_s) {
  std::string y = "{kind: multiposition, rotation_s: 2, dwell_s: " + std::to_string(dwell_s) + ", steps: [";
  for (std::size_t i = 0; i < euler_deg.size(); ++i) {
    const Eigen::Vector3d& e = euler_deg[i];
    y += std::string(i ? ", " : "") + "{euler_deg: [" + std::to_string(e.x()) + ", " + std::to_string(e.y()) + ", " +
         std::to_string(e.z()) + "]}";
  }
  return y + "]}";
}

TEST_F(TemperatureRecord, FileGivesTheInMemoryResult) {
  const double dwell_s = 4.0;
  const std::vector<double> temperatures = {-20.0, 15.0, 50.0};
  const std::vector<TemperatureRun> runs = SimulateChamber(TruthErrors(), temperatures, dwell_s, 7);
  std::string record = "order: 2\nlatitude_deg: " + std::to_string(kLatitudeDeg) +
                       "\nheight_m: " + std::to_string(kHeightM) + "\nreference_degC: 25\nruns:\n";
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const std::string name = "imu_" + std::to_string(i) + ".txt";
    KfginsImuWriter writer(dir_ + "/" + name);
    for (const ImuSample& s : runs[i].data.imu) writer.Write(s);
    writer.Commit();
    record += "  - {temperature_degC: " + std::to_string(temperatures[i]) + ", imu: " + name +
              ", trajectory: " + ScheduleYaml(kSixPositionsDeg, dwell_s) + "}\n";
  }
  const std::string path = Write("chamber.yaml", record);
  const ImuCalibrationResult from_file = CalibrateTemperatureRecord(path);
  TemperatureCalibrationOptions options;
  options.reference_degC = 25.0;
  const ImuCalibrationResult in_memory = CalibrateTemperature(runs, options).result;
  ASSERT_EQ(from_file.estimated, in_memory.estimated);
  ASSERT_TRUE(from_file.calibration.temperature.has_value());
  // 17 significant digits round-trip the samples exactly; the solves may differ in the
  // last bits only: 1e-6 sigma.
  for (int i = 0; i < kTriadParameters; ++i) {
    EXPECT_NEAR(from_file.calibration.accel(i), in_memory.calibration.accel(i), 1e-6 * (*in_memory.calibration.accel_sigma)(i));
    EXPECT_NEAR(from_file.calibration.gyro(i), in_memory.calibration.gyro(i), 1e-6 * (*in_memory.calibration.gyro_sigma)(i));
  }
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector3d d = from_file.calibration.temperature->accel_bias_mps2[k] -
                              in_memory.calibration.temperature->accel_bias_mps2[k];
    EXPECT_LT(d.norm(), 1e-9);  // ~1e-6 sigma of coefficients whose sigma is ~1e-5 .. 1e-3
  }
}

TEST_F(TemperatureRecord, BadRecordsNameFileLineAndKey) {
  const auto expect_input_error = [&](const std::string& text, const std::string& key, long line) {
    const std::string path = Write("bad.yaml", text);
    try {
      CalibrateTemperatureRecord(path);
      ADD_FAILURE() << "no InputError for:\n" << text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.field(), key) << e.what();
      EXPECT_EQ(e.line(), line) << e.what();
    }
  };
  expect_input_error("latitude_deg: 30\nruns:\n  - {imu: a.txt, trajectory: {kind: multiposition}}\n",
                     "runs[0].temperature_degC", 3);
  expect_input_error("latitude_deg: 30\norder: 7\nruns: []\n", "order", 2);
  expect_input_error("latitude_deg: 30\nruns: []\n", "runs", 2);
  expect_input_error("runs:\n  - {temperature_degC: 20, imu: a.txt}\n", "latitude_deg", 1);  // absent: the line of the record's top mapping
  expect_input_error("latitude_deg: 30\nruns:\n  - {temperature_degC: 20, imu: a.txt, colour: red}\n",
                     "runs[0].colour", 3);
  expect_input_error("latitude_deg: 30\nruns:\n  - {temperature_degC: 900, imu: a.txt}\n",
                     "runs[0].temperature_degC", 3);
}

// ---------------------------------------------------------------------------------------
// Warm-up data: one multi-position run during which the IMU warms from 0 to 40 degC
// (time constant 300 s, the seed's self-heating), the temperature sensor read at every
// IMU sample (as the simulator's temperature.csv).

constexpr double kWarmUpInitialDegC = 0.0;
constexpr double kWarmUpFinalDegC = 40.0;
constexpr double kWarmUpTimeConstantS = 300.0;

/// 16 positions: the six +-1 g positions, the same in reverse order (each axis at +1 g and
/// -1 g early and late in the warm-up) and four tilted by 45 deg (misalignment).
const std::vector<Eigen::Vector3d> kWarmUpPositionsDeg = {
    {0, 0, 0},   {180, 0, 0}, {90, 0, 0},  {-90, 0, 0}, {0, 90, 0},  {0, -90, 0}, {0, -90, 0}, {0, 90, 0},
    {-90, 0, 0}, {90, 0, 0},  {180, 0, 0}, {0, 0, 0},   {45, 0, 0},  {0, 45, 0},  {-45, 0, 0}, {0, -45, 0}};

/// The exact increments of a table schedule (no sensor error) at rate_hz.
std::vector<ImuSample> ExactIncrements(const sim::MultiPositionConfig& schedule, double rate_hz) {
  const sim::MultiPositionRig rig(schedule);
  const wgs84::Geodetic start{kLatitudeDeg * kDegToRad, 114.0 * kDegToRad, kHeightM};
  std::vector<ImuSample> exact;
  sim::SynthesizeImu(rig, start, rate_hz, rig.duration_s(), [&](const ImuSample& s, const NavState&) {
    if (s.dt_s > 0.0) exact.push_back(s);  // the first call is the initial state, no increment
  });
  return exact;
}

/// A warm-up run: the exact increments through the error model at the profile's
/// temperature of each interval's middle (as core/sim/imu_simulator.cc), the temperature
/// sensor read at every sample's time tag.
WarmUpRun WarmUp(const sim::InertialErrorConfig& errors, const sim::MultiPositionConfig& schedule,
                 const std::vector<ImuSample>& exact, double initial_degC, double final_degC, std::uint64_t seed) {
  sim::InertialErrorConfig e = errors;
  e.temperature.initial_degC = initial_degC;
  e.temperature.final_degC = final_degC;
  e.temperature.time_constant_s = kWarmUpTimeConstantS;
  sim::InertialErrorModel model(e, sim::Rng(seed).Stream("imu"), false);
  WarmUpRun run;
  run.data.schedule = schedule;
  run.data.latitude_rad = kLatitudeDeg * kDegToRad;
  run.data.height_m = kHeightM;
  run.data.imu_path = "warm-up " + std::to_string(seed);
  run.temperature.path = "temperature " + std::to_string(seed);
  for (const ImuSample& s : exact) {
    ImuSample m = s;
    model.Apply(s.t_s, s.dt_s, e.temperature.At(s.t_s - 0.5 * s.dt_s), s.dtheta_b_rad, s.dv_b_mps, &m.dtheta_b_rad,
                &m.dv_b_mps);
    run.data.imu.push_back(m);
    run.temperature.t_s.push_back(s.t_s);
    run.temperature.temperature_degC.push_back(e.temperature.At(s.t_s));
  }
  return run;
}

/// The value of an estimated name ("<param>" or "<param>.dT<k>") in a result.
double EstimateOf(const ImuCalibrationResult& r, const std::string& name) {
  const std::size_t dot = name.rfind(".dT");
  const std::string base = dot == std::string::npos ? name : name.substr(0, dot);
  const int k = dot == std::string::npos ? 0 : std::atoi(name.c_str() + dot + 3);
  for (int i = 0; i < kGSensitivityParameters; ++i) {
    if (base == GSensitivityParameterName(i)) return r.calibration.g_sensitivity(i);
  }
  const TemperatureTerms& t = *r.calibration.temperature;
  for (const char* triad : {"gyro", "accel"}) {
    const bool gyro = std::string(triad) == "gyro";
    for (int i = 0; i < kTriadParameters; ++i) {
      if (base != TriadParameterName(triad, i)) continue;
      if (k == 0) return (gyro ? r.calibration.gyro : r.calibration.accel)(i);
      const auto& terms = gyro ? (i < 3 ? t.gyro_scale_factor : t.gyro_bias_rad_per_s)
                               : (i < 3 ? t.accel_scale_factor : t.accel_bias_mps2);
      return terms[k - 1](i < 3 ? i : i - 9);
    }
  }
  ADD_FAILURE() << "unknown name " << name;
  return 0.0;
}

/// z of every estimated coefficient of a warm-up result against the truth.
std::vector<std::pair<std::string, double>> WarmUpZScores(const ImuCalibrationResult& r,
                                                          const std::vector<Truth>& truth) {
  std::vector<std::pair<std::string, double>> z;
  for (std::size_t i = 0; i < r.estimated.size(); ++i) {
    const std::string& name = r.estimated[i];
    const std::size_t dot = name.rfind(".dT");
    const std::string base = dot == std::string::npos ? name : name.substr(0, dot);
    const int k = dot == std::string::npos ? 0 : std::atoi(name.c_str() + dot + 3);
    for (const Truth& t : truth) {
      if (t.name == base && k < static_cast<int>(t.coefficients.size())) {
        z.push_back({name, (EstimateOf(r, name) - t.coefficients[k]) / std::sqrt(r.covariance(i, i))});
      }
    }
  }
  return z;
}

double SigmaOf(const ImuCalibrationResult& r, const std::string& name) {
  const auto it = std::find(r.estimated.begin(), r.estimated.end(), name);
  EXPECT_NE(it, r.estimated.end()) << name;
  if (it == r.estimated.end()) return std::numeric_limits<double>::quiet_NaN();
  const int i = static_cast<int>(it - r.estimated.begin());
  return std::sqrt(r.covariance(i, i));
}

/// TruthErrors with a quarter of its white noise (a better IMU): one warm-up run then
/// resolves the temperature terms (at the chamber tests' noise its sigmas are 4x larger,
/// see MonteCarloSigmaIsHonest).
sim::InertialErrorConfig QuieterErrors() {
  sim::InertialErrorConfig e = TruthErrors();
  e.gyro.white_noise /= 4.0;
  e.accel.white_noise /= 4.0;
  return e;
}

TEST(TemperatureWarmUp, RecoversTheQuadratics) {
  const sim::InertialErrorConfig errors = QuieterErrors();
  const sim::MultiPositionConfig schedule = Schedule(kWarmUpPositionsDeg, 45.0);
  const std::vector<WarmUpRun> runs = {
      WarmUp(errors, schedule, ExactIncrements(schedule, kRateHz), kWarmUpInitialDegC, kWarmUpFinalDegC, 41)};
  TemperatureCalibrationOptions options;
  options.reference_degC = kSimReferenceDegC;
  const WarmUpCalibration cal = CalibrateWarmUp(runs, options);
  const ImuCalibrationResult& r = cal.result;
  ASSERT_TRUE(r.calibration.temperature.has_value());
  EXPECT_EQ(r.calibration.temperature->reference_degC, kSimReferenceDegC);
  ASSERT_EQ(r.calibration.temperature->accel_bias_mps2.size(), 2u);
  ASSERT_EQ(r.covariance.rows(), static_cast<int>(r.estimated.size()));
  EXPECT_TRUE(r.covariance.allFinite());
  EXPECT_EQ(r.positions, 16);
  // 16 holds of 45 s less 2 x 0.5 s settling: 4 segments of 11 s each.
  EXPECT_EQ(cal.segments.size(), 64u);
  // Gyro scale factors and misalignments need rotations: listed, not estimated.
  EXPECT_EQ(r.unobservable.size(), 9u);
  for (const std::string& u : r.unobservable) EXPECT_EQ(u.rfind("gyro.", 0), 0u) << u;
  EXPECT_FALSE(r.calibration.gyro_sigma->head<9>().allFinite());

  const auto z = WarmUpZScores(r, TruthOf(errors, kSimReferenceDegC, 2));
  // accel: 3 x (scale, 2 misalignments, bias, 2 + 2 temperature terms); gyro: 3 x (bias,
  // 2 temperature terms) and 9 g-sensitivities.
  EXPECT_EQ(z.size(), 42u);
  double worst = 0.0;
  for (const auto& [name, score] : z) {
    // One fixed draw of 42 coefficients: 4.5 sigma leaves them all inside with
    // probability > 0.9997 when the sigma is honest.
    EXPECT_LT(std::abs(score), 4.5) << name;
    worst = std::max(worst, std::abs(score));
  }
  std::cout << "warm-up 0 -> 40 degC, 16 positions: largest |z| " << worst << " of " << z.size() << "\n";
  // The temperature effects are resolved: each coefficient below is > 5 sigma from 0.
  for (const char* name : {"accel.scale_factor.x.dT1", "accel.bias.z.dT2", "accel.bias.z.dT1",
                           "accel.bias.x.dT2", "gyro.bias.x.dT1", "gyro.bias.z.dT2"}) {
    const double value = EstimateOf(r, name), sigma = SigmaOf(r, name);
    std::cout << name << " = " << value << " +- " << sigma << "\n";
    EXPECT_GT(std::abs(value) / sigma, 5.0) << name;
  }
}

// Monte Carlo: 100 warm-ups with independent noise (the same exact increments, 20 Hz to
// keep the test short), the fraction of coefficients within 3 sigma of the truth.
TEST(TemperatureWarmUp, MonteCarloSigmaIsHonest) {
  const sim::InertialErrorConfig errors = TruthErrors();
  const sim::MultiPositionConfig schedule = Schedule(kWarmUpPositionsDeg, 45.0);
  const std::vector<ImuSample> exact = ExactIncrements(schedule, 20.0);
  const std::vector<Truth> truth = TruthOf(errors, kSimReferenceDegC, 2);
  const int calibrations = 100;
  SigmaTally tally;
  for (int m = 0; m < calibrations; ++m) {
    TemperatureCalibrationOptions options;
    options.reference_degC = kSimReferenceDegC;
    const WarmUpCalibration cal = CalibrateWarmUp(
        {WarmUp(errors, schedule, exact, kWarmUpInitialDegC, kWarmUpFinalDegC, 500 + m)}, options);
    for (const auto& [name, score] : WarmUpZScores(cal.result, truth)) {
      tally.Add(name, score);
    }
  }
  tally.Check(calibrations, "warm-up calibrations");
}

TEST(TemperatureWarmUp, SpanTooSmall) {
  // 20 -> 30 degC with a 300 s time constant over a 190 s schedule: the means of the 12
  // segments (2 per 29 s hold) span 20.25 .. 24.55 degC, short of the 20 degC an order-2 fit needs.
  const sim::MultiPositionConfig schedule = Schedule(kSixPositionsDeg, 30.0);
  const WarmUpRun run = WarmUp(TruthErrors(), schedule, ExactIncrements(schedule, 20.0), 20.0, 30.0, 42);
  ExpectRuntimeError([&] { CalibrateWarmUp({run}); },
                     "warm-up temperature calibration (mean temperatures of the 12 segments): order 2 needs a "
                     "temperature span of at least 20 degC (10 degC per order), got 4.298 degC (20.25 .. 24.55 degC)");
  // 20 -> 25 degC over 70 s: every segment within 1 degC, a single temperature.
  const sim::MultiPositionConfig short_schedule = Schedule(kSixPositionsDeg, 10.0);
  const WarmUpRun flat = WarmUp(TruthErrors(), short_schedule, ExactIncrements(short_schedule, 20.0), 20.0, 25.0, 43);
  ExpectRuntimeError([&] { CalibrateWarmUp({flat}); },
                     "(mean temperatures of the 6 segments): order 2 needs at least 3 temperatures, got 1");
}

TEST(TemperatureWarmUp, TooFewPositions) {
  const std::vector<Eigen::Vector3d> five(kSixPositionsDeg.begin(), kSixPositionsDeg.begin() + 5);
  const sim::MultiPositionConfig schedule = Schedule(five, 10.0);
  const WarmUpRun run = WarmUp(TruthErrors(), schedule, ExactIncrements(schedule, 20.0), 0.0, 40.0, 43);
  ExpectRuntimeError([&] { CalibrateWarmUp({run}); }, "the schedule has 5 static positions; at least 6 are needed");
}

TEST_F(TemperatureRecord, TemperatureFileErrorsNameFileLineAndField) {
  const auto expect_input_error = [&](const std::string& text, const std::string& field, long line) {
    const std::string path = Write("temperature.csv", text);
    try {
      ReadTemperatureFile(path);
      ADD_FAILURE() << "no InputError for:\n" << text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.field(), field) << e.what();
      EXPECT_EQ(e.line(), line) << e.what();
    }
  };
  expect_input_error("t_s,temperature_degC\n0.0,20.0\n0.1,nan\n", "temperature_degC", 3);
  expect_input_error("t_s,temperature_degC\n0.0,20.0\n0.1,20.1\n0.05,20.2\n", "t_s", 4);
  expect_input_error("t_s,temp_C\n0.0,20.0\n", "temperature_degC", 1);
  expect_input_error("t_s,temperature_degC\n0.0,20.0\n0.1\n", "", 3);
  const TemperatureSeries ok = ReadTemperatureFile(Write("ok.csv", "t_ms,temperature_degC\n0,20\n100,20.5\n"));
  ASSERT_EQ(ok.t_s.size(), 2u);
  EXPECT_EQ(ok.t_s[1], 0.1);
  EXPECT_EQ(ok.temperature_degC[1], 20.5);
}

// The whole path through files: `navtwin simulate` of a warm-up on the table writes
// imu.txt and temperature.csv; a record names them; CalibrateTemperatureRecord recovers the
// simulator's truth. A record mixing chamber and warm-up runs is refused.
TEST_F(TemperatureRecord, WarmUpThroughTheSimulatorFiles) {
  const std::string trajectory = ScheduleYaml(kWarmUpPositionsDeg, 45.0);
  const double duration_s = sim::MultiPositionRig(Schedule(kWarmUpPositionsDeg, 45.0)).duration_s();
  const std::string scenario_yaml =
      "name: warmup\nduration_s: " + std::to_string(duration_s) + "\nstart: {lat_deg: " + std::to_string(kLatitudeDeg) +
      ", lon_deg: 114, h_m: " + std::to_string(kHeightM) + "}\ntrajectory: " + trajectory +
      "\nimu:\n  rate_hz: 20\n  errors:\n"
      "    gyro: {bias_fixed_deg_h: [20, -12, 16], arw_deg_sqrt_h: 0.1,\n"
      "           temperature: {bias_fixed_deg_h_per_degC: [0.4, -0.3, 0.2], bias_fixed_deg_h_per_degC2: [0.008, 0.006, -0.01]}}\n"
      "    accel: {bias_fixed_ug: [3000, -5000, 4000], scale_factor_fixed_ppm: [1000, -800, 600], vrw_m_s_sqrt_h: 0.06,\n"
      "            temperature: {bias_fixed_ug_per_degC: [20, -10, 15], bias_fixed_ug_per_degC2: [0.3, -0.2, 0.4],\n"
      "                          scale_factor_fixed_ppm_per_degC: [20, -15, 25], scale_factor_fixed_ppm_per_degC2: [0.3, 0.2, -0.4]}}\n"
      "    temperature_profile: {reference_degC: 25, initial_degC: 0, final_degC: 40, time_constant_s: 300}\n";
  const sim::Scenario scenario = sim::ParseScenario(ParseYaml(scenario_yaml, "warmup.yaml"));
  sim::SimulationOptions sim_options;
  sim_options.seed = 44;
  const sim::TemporarySimulation simulation(scenario, sim_options, "navtwin_warmup_");
  const std::string record = "order: 2\nlatitude_deg: " + std::to_string(kLatitudeDeg) +
                             "\nheight_m: " + std::to_string(kHeightM) +
                             "\nreference_degC: 25\nsegment_s: 10\nruns:\n  - {temperature: " +
                             simulation.path("temperature.csv") + ", imu: " + simulation.path("imu.txt") +
                             ", trajectory: " + trajectory + "}\n";
  const ImuCalibrationResult r = CalibrateTemperatureRecord(Write("warmup.yaml", record));
  EXPECT_EQ(r.positions, 16);
  ASSERT_TRUE(r.calibration.temperature.has_value());
  const sim::InertialErrorConfig& e = scenario.imu.errors;
  // Zero-valued truths where the YAML gives none (misalignment, G, gyro scale factor).
  sim::InertialErrorConfig truth = e;
  for (sim::TriadErrorConfig* t : {&truth.gyro, &truth.accel}) {
    for (sim::AxisConstant* a : {&t->bias, &t->scale_factor, &t->bias_per_degC, &t->bias_per_degC2,
                                 &t->scale_factor_per_degC, &t->scale_factor_per_degC2}) {
      if (!a->fixed) a->fixed = Eigen::Vector3d::Zero();
    }
    if (!t->misalignment.fixed) t->misalignment.fixed = Eigen::Matrix3d::Zero();
  }
  if (!truth.g_sensitivity.fixed) truth.g_sensitivity.fixed = Eigen::Matrix3d::Zero();
  const auto z = WarmUpZScores(r, TruthOf(truth, kSimReferenceDegC, 2));
  EXPECT_EQ(z.size(), 42u);
  for (const auto& [name, score] : z) EXPECT_LT(std::abs(score), 4.5) << name;  // one draw of 42: as above
  const double value = EstimateOf(r, "accel.bias.x.dT1");
  EXPECT_GT(std::abs(value) / SigmaOf(r, "accel.bias.x.dT1"), 5.0);  // resolved, not just consistent

  // Chamber and warm-up runs in one record: refused, naming the second kind's run.
  const std::string mixed = "latitude_deg: 30\nruns:\n  - {temperature_degC: 20, imu: " + simulation.path("imu.txt") +
                            ", trajectory: " + trajectory + "}\n  - {temperature: " +
                            simulation.path("temperature.csv") + ", imu: " + simulation.path("imu.txt") +
                            ", trajectory: " + trajectory + "}\n";
  const std::string mixed_path = Write("mixed.yaml", mixed);
  try {
    CalibrateTemperatureRecord(mixed_path);
    ADD_FAILURE() << "a mixed record was accepted";
  } catch (const InputError& err) {
    EXPECT_EQ(err.file(), mixed_path);
    EXPECT_EQ(err.field(), "runs[1].temperature") << err.what();
    EXPECT_EQ(err.line(), 4) << err.what();
    EXPECT_NE(std::string(err.what()).find("mixes chamber runs"), std::string::npos) << err.what();
  }
}

}  // namespace calibration_temperature_test
}  // namespace navtwin::calibration
