// Temperature calibration (problems/calibration/temperature.h). The polynomial fit alone on
// synthetic points (exactness, honest covariance over 2000 noisy trials, chi-square, the
// coverage checks); then the whole calibration on chamber runs simulated in memory: a
// multi-position table (+1 g and -1 g on every axis) at -20, 15 and 50 degC (the seed's
// chamber) with the SAME fixed error constants in every run and independent noise, the
// recovered polynomial coefficients against the simulator's truth, a Monte Carlo of the
// 3-sigma fraction, orders 1 and 3, the errors for bad data, and one calibration through
// a record file.
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

namespace navtwin::calibration {
namespace {

constexpr double kDeg = M_PI / 180.0;

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
    s.euler_rad = e * kDeg;
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
  run.data.latitude_rad = kLatitudeDeg * kDeg;
  run.data.height_m = kHeightM;
  run.data.imu_path = "run at " + std::to_string(temperature_degC) + " degC";
  const wgs84::Geodetic start{kLatitudeDeg * kDeg, 114.0 * kDeg, kHeightM};
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
TEST(TemperatureCalibration, MonteCarloSigmaIsHonest) {
  const sim::InertialErrorConfig errors = TruthErrors();
  const int calibrations = 100;
  std::map<std::string, int> within;
  int total = 0, total_within = 0, temperature_terms = 0, temperature_within = 0;
  for (int m = 0; m < calibrations; ++m) {
    const std::vector<TemperatureRun> runs = SimulateChamber(errors, {-20.0, 15.0, 50.0}, 3.0, 100 + m);
    TemperatureCalibrationOptions options;
    options.reference_degC = kSimReferenceDegC;
    const TemperatureCalibration cal = CalibrateTemperature(runs, options);
    for (const auto& [name, score] : ZScores(cal, TruthOf(errors, kSimReferenceDegC, 2))) {
      const bool in = std::abs(score) <= 3.0;
      within[name] += in;
      ++total;
      total_within += in;
      if (name.find(".dT") != std::string::npos) {
        ++temperature_terms;
        temperature_within += in;
      }
    }
  }
  int worst = calibrations;
  std::string worst_name;
  for (const auto& [name, n] : within) {
    if (n < worst) {
      worst = n;
      worst_name = name;
    }
  }
  const double fraction = static_cast<double>(total_within) / total;
  const double fraction_t = static_cast<double>(temperature_within) / temperature_terms;
  std::cout << calibrations << " calibrations, " << within.size() << " coefficients each: " << 100.0 * fraction
            << " % within 3 sigma (temperature coefficients " << 100.0 * fraction_t << " %); worst "
            << worst_name << " " << worst << "/" << calibrations << "\n";
  // The criterion: >= 95 % within 3 sigma. Pooled over ~4000 z-scores an honest
  // sigma gives 99.7 %; per coefficient, fewer than 95 of 100 fails by chance with p ~ 1e-6.
  EXPECT_GE(fraction, 0.95);
  EXPECT_GE(fraction_t, 0.95);
  EXPECT_GE(worst, 95) << worst_name;
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

/// The schedule of kSixPositionsDeg in the simulator's YAML schema.
std::string TrajectoryYaml(double dwell_s) {
  std::string y = "{kind: multiposition, rotation_s: 2, dwell_s: " + std::to_string(dwell_s) + ", steps: [";
  for (std::size_t i = 0; i < kSixPositionsDeg.size(); ++i) {
    const Eigen::Vector3d& e = kSixPositionsDeg[i];
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
              ", trajectory: " + TrajectoryYaml(dwell_s) + "}\n";
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

}  // namespace
}  // namespace navtwin::calibration
