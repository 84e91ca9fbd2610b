// Magnetometer calibration (problems/calibration/mag_calibration.h) on samples simulated
// from the model m = (I + S) R_b_n m_n + h + n (S symmetric, entries ~0.05; h 10-30 uT per
// axis; white noise; the seed's field: 57 deg inclination, 50 uT): honest sigmas over 100
// Monte Carlo runs, robustness to 2 % outliers, the recursive fit against the batch, the
// seed's 2-axis bidirectional method on a level turn, heading error before and after both
// methods, the tilt bound, the errors for bad input, and the real magnetometers (skipped
// when the data are absent, failed in CI).
#include "problems/calibration/mag_calibration.h"

#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "core/io/ansfl.h"
#include "core/io/open.h"
#include "core/rotation.h"
#include "core/sim/random.h"
#include "core/units.h"
#include "tests/test_data.h"

namespace navtwin::calibration {
namespace calibration_mag_calibration_test {

constexpr double kField_uT = 50.0;
constexpr double kInclination_rad = 57.0 * kDegToRad;

/// The seed's field in NED (declination 0): B (cos I, 0, sin I).
Eigen::Vector3d FieldNed() { return kField_uT * Eigen::Vector3d(std::cos(kInclination_rad), 0.0, std::sin(kInclination_rad)); }

struct Iron {
  Eigen::Vector3d h_uT;
  Eigen::Matrix3d S;  ///< symmetric
};

/// h: 10-30 uT per axis with a random sign; S symmetric with N(0, 0.05) entries.
Iron DrawIron(sim::Rng& rng) {
  Iron iron;
  for (int i = 0; i < 3; ++i) iron.h_uT(i) = (rng.Uniform() < 0.5 ? -1.0 : 1.0) * rng.Uniform(10.0, 30.0);
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) iron.S(i, j) = iron.S(j, i) = rng.Normal(0.05);
  }
  return iron;
}

/// Uniformly distributed attitude (normalised 4-d normal).
Eigen::Quaterniond RandomAttitude(sim::Rng& rng) {
  Eigen::Quaterniond q(rng.Normal(), rng.Normal(), rng.Normal(), rng.Normal());
  q.normalize();
  return q;
}

Eigen::Vector3d Measure(const Iron& iron, const Eigen::Matrix3d& R_n_b, double noise_uT, sim::Rng& rng) {
  return (Eigen::Matrix3d::Identity() + iron.S) * (R_n_b.transpose() * FieldNed()) + iron.h_uT + rng.Normal3(noise_uT);
}

std::vector<MagSample> SphereSamples(const Iron& iron, int n, double noise_uT, sim::Rng& rng) {
  std::vector<MagSample> samples(n);
  for (int i = 0; i < n; ++i) {
    samples[i].t_s = 0.1 * i;
    samples[i].m_b_uT = Measure(iron, RandomAttitude(rng).toRotationMatrix(), noise_uT, rng);
  }
  return samples;
}

/// Truth of (h, A_sym) in the order of MagCalibration's sigmas; A = (I + S)^-1.
Eigen::Matrix<double, 9, 1> TruthVector(const Iron& iron) {
  const Eigen::Matrix3d A = (Eigen::Matrix3d::Identity() + iron.S).inverse();
  Eigen::Matrix<double, 9, 1> t;
  t << iron.h_uT, A(0, 0), A(0, 1), A(0, 2), A(1, 1), A(1, 2), A(2, 2);
  return t;
}
Eigen::Matrix<double, 9, 1> EstimateVector(const MagCalibration& c) {
  const Eigen::Matrix3d& A = c.correction;
  Eigen::Matrix<double, 9, 1> e;
  e << c.hard_iron_uT, A(0, 0), A(0, 1), A(0, 2), A(1, 1), A(1, 2), A(2, 2);
  return e;
}
Eigen::Matrix<double, 9, 1> SigmaVector(const MagCalibration& c) {
  Eigen::Matrix<double, 9, 1> s;
  s << c.hard_iron_sigma_uT, c.correction_sigma;
  return s;
}

TEST(FitEllipsoid, ExactWithoutNoise) {
  sim::Rng rng(1);
  const Iron iron = DrawIron(rng);
  EllipsoidFitOptions options;
  options.field_uT = kField_uT;
  const MagCalibration c = FitEllipsoid(SphereSamples(iron, 200, 0.0, rng), options);
  // Noise-free samples lie exactly on the ellipsoid: only solver tolerance remains.
  EXPECT_LT((EstimateVector(c) - TruthVector(iron)).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT(c.residual_rms_uT, 1e-6);
  EXPECT_EQ(c.method, "ellipsoid");
  EXPECT_EQ(c.samples, 200);
}

// 100 runs, 300 samples, noise 0.3 uT, each run its own iron: all 9 parameters within 3 sigma
// of the truth in >= 95 runs. With honest Gaussian sigmas P(all 9 within 3 sigma) = 0.9973^9
// = 0.976, i.e. ~97.6 of 100 runs (binomial sd ~1.5): 95 allows for chance, while sigmas
// 15 % too small (2.6 sigma, 0.9907^9 = 0.92) would fail.
TEST(FitEllipsoid, MonteCarloSigmasAreHonest) {
  EllipsoidFitOptions options;
  options.field_uT = kField_uT;
  int within = 0;
  double worst_normalised = 0.0;
  for (int run = 0; run < 100; ++run) {
    sim::Rng rng(1000 + run);
    const Iron iron = DrawIron(rng);
    const MagCalibration c = FitEllipsoid(SphereSamples(iron, 300, 0.3, rng), options);
    const Eigen::Matrix<double, 9, 1> z =
        (EstimateVector(c) - TruthVector(iron)).cwiseQuotient(SigmaVector(c)).cwiseAbs();
    if (z.maxCoeff() <= 3.0) ++within;
    worst_normalised = std::max(worst_normalised, z.maxCoeff());
    ASSERT_TRUE(SigmaVector(c).allFinite());
    ASSERT_GT(SigmaVector(c).minCoeff(), 0.0);
  }
  std::cout << "[ellipsoid MC] runs with all 9 parameters within 3 sigma: " << within
            << "/100, worst |error|/sigma " << worst_normalised << "\n";
  EXPECT_GE(within, 95);
}

// 2 % of the samples replaced by readings disturbed by 20-60 uT (a motor, a passing car):
// the Cauchy fit stays within 4 sigma of the truth (sigma of the inliers; the outliers'
// residual influence is bounded but not zero) and flags them, while the plain least
// squares is pulled many of its sigmas away.
TEST(FitEllipsoid, RobustLossKeepsTheFitWithTwoPercentOutliers) {
  sim::Rng rng(77);
  const Iron iron = DrawIron(rng);
  std::vector<MagSample> samples = SphereSamples(iron, 1000, 0.3, rng);
  int outliers = 0;
  for (std::size_t i = 0; i < samples.size(); i += 50) {  // 20 of 1000
    Eigen::Vector3d d = rng.Normal3(1.0).normalized() * rng.Uniform(20.0, 60.0);
    samples[i].m_b_uT += d;
    ++outliers;
  }
  EllipsoidFitOptions robust;
  robust.field_uT = kField_uT;
  const MagCalibration c = FitEllipsoid(samples, robust);
  const Eigen::Matrix<double, 9, 1> z = (EstimateVector(c) - TruthVector(iron)).cwiseQuotient(SigmaVector(c));
  EXPECT_LT(z.cwiseAbs().maxCoeff(), 4.0) << z.transpose();
  // A disturbance nearly tangent to the field sphere barely changes |m| and is no outlier of
  // the magnitude: allow 2 of the 20 to pass; inliers at 0.3 uT never reach the 2 uT scale.
  EXPECT_GE(c.downweighted, outliers - 2);
  EXPECT_LE(c.downweighted, outliers);
  EllipsoidFitOptions plain = robust;
  plain.loss = MagLoss::kNone;
  const MagCalibration p = FitEllipsoid(samples, plain);
  const double robust_error = (c.hard_iron_uT - iron.h_uT).norm();
  const double plain_error = (p.hard_iron_uT - iron.h_uT).norm();
  std::cout << "[ellipsoid outliers] |h error| robust " << robust_error << " uT, plain LS " << plain_error << " uT\n";
  EXPECT_LT(robust_error, 0.1);   // ~3 x the inlier sigma of h (~0.02 uT per axis)
  EXPECT_GT(plain_error, 3.0 * robust_error);
}

TEST(FitEllipsoid, HuberAndFittedFieldMagnitude) {
  sim::Rng rng(5);
  const Iron iron = DrawIron(rng);
  EllipsoidFitOptions options;
  options.loss = MagLoss::kHuber;  // field_uT = 0: B from the algebraic fit (det A = 1)
  const MagCalibration c = FitEllipsoid(SphereSamples(iron, 500, 0.2, rng), options);
  // A and B are known only up to a common scale: compare the shape A / B with the truth's.
  const Eigen::Matrix3d A_true = (Eigen::Matrix3d::Identity() + iron.S).inverse();
  EXPECT_LT(((c.correction / c.field_uT) - A_true / kField_uT).cwiseAbs().maxCoeff() * kField_uT, 0.01);
  // det A = 1 at the algebraic start (the convention fixing B); the least squares then moves
  // A with B held, by O(noise / B / sqrt(N)) ~ 1e-4.
  EXPECT_NEAR(c.correction.determinant(), 1.0, 1e-3);
  EXPECT_LT((c.hard_iron_uT - iron.h_uT).norm(), 0.1);  // sigma ~0.02 uT per axis at 500 samples
  EXPECT_LT(c.field_spread_after_uT, 0.3);              // ~ the 0.2 uT noise
  EXPECT_GT(c.field_spread_before_uT, 5.0);             // hard iron of 10-30 uT
}

// 3-axis: heading from the raw and the calibrated field, tilt-compensated with the true
// roll and pitch, on a vehicle rotated through +-60 deg of roll and pitch and all headings.
TEST(FitEllipsoid, HeadingErrorBeforeAndAfter) {
  sim::Rng rng(11);
  const Iron iron = DrawIron(rng);
  EllipsoidFitOptions options;
  options.field_uT = kField_uT;
  const MagCalibration c = FitEllipsoid(SphereSamples(iron, 1000, 0.3, rng), options);
  const double declination = 8.0 * kDegToRad;
  double ss_before = 0.0, ss_after = 0.0;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const double roll = rng.Uniform(-60.0, 60.0) * kDegToRad, pitch = rng.Uniform(-60.0, 60.0) * kDegToRad;
    const double yaw = rng.Uniform(-180.0, 180.0) * kDegToRad;
    const Eigen::Vector3d m = Measure(iron, DcmFromEuler(roll, pitch, yaw), 0.3, rng);
    const double truth = WrapPi(yaw + declination);
    const double before = WrapPi(TiltCompensatedHeading(m, roll, pitch, declination) - truth);
    const double after = WrapPi(TiltCompensatedHeading(ApplyMagCalibration(c, m), roll, pitch, declination) - truth);
    ss_before += before * before;
    ss_after += after * after;
  }
  const double rms_before_deg = std::sqrt(ss_before / n) / kDegToRad, rms_after_deg = std::sqrt(ss_after / n) / kDegToRad;
  std::cout << "[ellipsoid heading] RMS heading error before " << rms_before_deg << " deg, after " << rms_after_deg
            << " deg\n";
  EXPECT_GT(rms_before_deg, 10.0);  // 10-30 uT of hard iron against a 27 uT horizontal field
  // Noise 0.3 uT across H cos(tilt) >= 13.6 uT is <= 1.3 deg per sample, RMS ~0.8 deg: 1.5 is safe.
  EXPECT_LT(rms_after_deg, 1.5);
}

TEST(FitEllipsoid, OnePlaneIsACoverageError) {
  sim::Rng rng(3);
  const Iron iron = DrawIron(rng);
  std::vector<MagSample> samples(500);  // a level turn: rotation about the vertical only
  for (int i = 0; i < 500; ++i) {
    samples[i].m_b_uT = Measure(iron, DcmFromEuler(0.0, 0.0, 0.01 * i), 0.3, rng);
  }
  try {
    FitEllipsoid(samples);
    FAIL() << "a level turn cannot calibrate the z axis";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("one plane"), std::string::npos) << e.what();
  }
  // One side only: attitudes within 5 deg of level at one heading: the readings are a small
  // patch of the sphere.
  std::vector<MagSample> cap(500);
  for (int i = 0; i < 500; ++i) {
    cap[i].m_b_uT = Measure(iron, DcmFromEuler(rng.Uniform(-5.0, 5.0) * kDegToRad, rng.Uniform(-5.0, 5.0) * kDegToRad, 0.0),
                            0.3, rng);
  }
  EXPECT_THROW(FitEllipsoid(cap), std::runtime_error);
}

TEST(FitEllipsoid, RejectsBadInput) {
  sim::Rng rng(4);
  const Iron iron = DrawIron(rng);
  EXPECT_THROW(FitEllipsoid(SphereSamples(iron, 11, 0.3, rng)), std::invalid_argument);
  std::vector<MagSample> samples = SphereSamples(iron, 100, 0.3, rng);
  samples[17].m_b_uT.y() = std::numeric_limits<double>::quiet_NaN();
  try {
    FitEllipsoid(samples);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sample 17"), std::string::npos) << e.what();
  }
  samples[17].m_b_uT.y() = 1.0;
  EllipsoidFitOptions bad;
  bad.loss_scale_uT = 0.0;
  EXPECT_THROW(FitEllipsoid(samples, bad), std::invalid_argument);
  bad = {};
  bad.min_coverage = 1.5;
  EXPECT_THROW(FitEllipsoid(samples, bad), std::invalid_argument);
}

// The recursive least squares on the quadric equals the batch algebraic fit; with 3000
// samples at 0.3 uT it lands within 0.1 uT (h) and 0.002 (A) of the geometric batch fit
// (the algebraic and geometric fits differ by O(noise^2 / B) ~ 0.002 uT plus a share of
// the noise: both sigmas of h are ~0.01 uT here).
TEST(RecursiveEllipsoidFit, ConvergesToTheBatch) {
  sim::Rng rng(21);
  const Iron iron = DrawIron(rng);
  const std::vector<MagSample> samples = SphereSamples(iron, 3000, 0.3, rng);
  RecursiveEllipsoidFit recursive(kField_uT);
  EXPECT_THROW(recursive.Current(), std::runtime_error);  // no samples yet
  double error_at_100 = 0.0;
  for (const MagSample& s : samples) {
    recursive.Add(s.m_b_uT);
    if (recursive.count() == 100) error_at_100 = (recursive.Current().hard_iron_uT - iron.h_uT).norm();
  }
  EllipsoidFitOptions options;
  options.field_uT = kField_uT;
  const MagCalibration batch = FitEllipsoid(samples, options);
  const MagCalibration c = recursive.Current();
  EXPECT_EQ(c.samples, 3000);
  EXPECT_EQ(c.method, "recursive");
  const double h_gap = (c.hard_iron_uT - batch.hard_iron_uT).norm();
  const double a_gap = (c.correction - batch.correction).cwiseAbs().maxCoeff();
  const double error_at_end = (c.hard_iron_uT - iron.h_uT).norm();
  std::cout << "[recursive] |h - h_batch| " << h_gap << " uT, |A - A_batch|max " << a_gap << "; |h error| after 100 "
            << error_at_100 << " uT, after 3000 " << error_at_end << " uT\n";
  EXPECT_LT(h_gap, 0.1);
  EXPECT_LT(a_gap, 0.002);
  EXPECT_LT(error_at_end, error_at_100);  // converges
}

TEST(RecursiveEllipsoidFit, OnePlaneIsACoverageError) {
  sim::Rng rng(22);
  const Iron iron = DrawIron(rng);
  RecursiveEllipsoidFit recursive;
  for (int i = 0; i < 400; ++i) recursive.Add(Measure(iron, DcmFromEuler(0.0, 0.0, 0.02 * i), 0.3, rng));
  try {
    recursive.Current();
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("one plane"), std::string::npos) << e.what();
  }
  EXPECT_THROW(recursive.Add(Eigen::Vector3d(std::nan(""), 0, 0)), std::invalid_argument);
}

// ------------------------------------------------------------------------ 2-axis

/// The seed's 2-axis soft iron with x/y phase phi: x = X cos psi, y = -Y sin(psi + phi) for
/// a horizontal field H (cos psi, -sin psi): (I + S)_2x2 = [[X, 0], [-Y sin phi, Y cos phi]] / H.
Eigen::Matrix3d TwoAxisIron(double X_over_H, double Y_over_H, double phase_rad) {
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();  // z row 0: the 2-axis sensor reads m_z = 0
  M(0, 0) = X_over_H;
  M(1, 0) = -Y_over_H * std::sin(phase_rad);
  M(1, 1) = Y_over_H * std::cos(phase_rad);
  return M;
}

struct LevelTurn {
  std::vector<MagSample> samples;
  std::vector<Eigen::Vector2d> roll_pitch_rad;
  std::vector<double> yaw_rad;
};

/// Two level turns at 0.5 deg per sample, then 100 samples tilted by 10 deg (to be left out).
LevelTurn SimulateTurn(const Eigen::Matrix3d& M, const Eigen::Vector3d& h_uT, double noise_uT, sim::Rng& rng) {
  LevelTurn turn;
  for (int i = 0; i < 1540; ++i) {
    const bool tilted = i >= 1440;
    const double roll = tilted ? 10.0 * kDegToRad : 0.0, pitch = 0.0, yaw = WrapPi(0.5 * kDegToRad * i + 0.3);
    MagSample s;
    s.t_s = 0.02 * i;
    s.m_b_uT = M * (DcmFromEuler(roll, pitch, yaw).transpose() * FieldNed()) + h_uT;
    s.m_b_uT.head<2>() += Eigen::Vector2d(rng.Normal(noise_uT), rng.Normal(noise_uT));
    turn.samples.push_back(s);
    turn.roll_pitch_rad.emplace_back(roll, pitch);
    turn.yaw_rad.push_back(yaw);
  }
  return turn;
}

TEST(FitBidirectional, RecoversHardIronAndTheSeedsPhaseOnALevelTurn) {
  sim::Rng rng(31);
  const double H = kField_uT * std::cos(kInclination_rad);  // 27.2 uT
  const double phase = -15.32 * kDegToRad;                        // the seed's example
  const Eigen::Vector3d h(18.0, -12.0, 0.0);
  const LevelTurn turn = SimulateTurn(TwoAxisIron(1.06, 0.93, phase), h, 0.2, rng);
  const MagCalibration c = FitBidirectional(turn.samples, turn.roll_pitch_rad);
  EXPECT_EQ(c.samples, 1440);  // the tilted samples are left out
  EXPECT_EQ(c.method, "bidirectional");
  const double phase_est = std::atan(c.correction(1, 0));
  std::cout << "[bidirectional] h = (" << c.hard_iron_uT.x() << ", " << c.hard_iron_uT.y() << ") uT, phase "
            << phase_est / kDegToRad << " deg (truth -15.32), field " << c.field_uT << " uT (truth " << 1.06 * H << ")\n";
  // Extremes of 0.2 uT noise: ~50 samples compete near each flat peak, so the max and min
  // are both biased outwards by ~2.3 sigma with an sd of ~0.4 sigma each; the bias cancels
  // in the midpoint, the sd does not: 0.06 uT, and 0.25 uT is 4 of those.
  EXPECT_NEAR(c.hard_iron_uT.x(), h.x(), 0.25);
  EXPECT_NEAR(c.hard_iron_uT.y(), h.y(), 0.25);
  // The phase is averaged over ~120 samples near the x extremes: noise 0.2 / 25 / sqrt(60)
  // ~ 0.06 deg, plus the amplitude bias ~0.2/25 rad ~ 0.5 deg * sin(phase): 0.3 deg.
  EXPECT_NEAR(phase_est / kDegToRad, -15.32, 0.3);
  EXPECT_NEAR(c.field_uT, 1.06 * H, 0.6);  // amplitude biased outwards by ~2.3 noise sigma = 0.46 uT
  EXPECT_LT(c.field_spread_after_uT, 0.3);
  EXPECT_GT(c.field_spread_before_uT, 5.0);

  // Heading error of the level turn before and after.
  double ss_before = 0.0, ss_after = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < 1440; ++i) {
    const double truth = turn.yaw_rad[i];
    const double before = WrapPi(LevelHeading(turn.samples[i].m_b_uT, 0.0) - truth);
    const double after = WrapPi(LevelHeading(ApplyMagCalibration(c, turn.samples[i].m_b_uT), 0.0) - truth);
    ss_before += before * before;
    ss_after += after * after;
    ++n;
  }
  const double rms_before_deg = std::sqrt(ss_before / n) / kDegToRad, rms_after_deg = std::sqrt(ss_after / n) / kDegToRad;
  std::cout << "[bidirectional heading] RMS heading error before " << rms_before_deg << " deg, after "
            << rms_after_deg << " deg\n";
  EXPECT_GT(rms_before_deg, 20.0);
  EXPECT_LT(rms_after_deg, 1.0);  // 0.2 uT noise over 28.8 uT: 0.4 deg per sample, plus phase/scale errors
}

TEST(FitBidirectional, RejectsAPartialTurnAndTooMuchTilt) {
  sim::Rng rng(32);
  LevelTurn turn = SimulateTurn(TwoAxisIron(1.0, 1.0, 0.0), Eigen::Vector3d(5.0, 5.0, 0.0), 0.2, rng);
  std::vector<MagSample> half(turn.samples.begin(), turn.samples.begin() + 360);  // 180 deg
  std::vector<Eigen::Vector2d> half_rp(turn.roll_pitch_rad.begin(), turn.roll_pitch_rad.begin() + 360);
  EXPECT_THROW(FitBidirectional(half, half_rp), std::runtime_error);
  std::vector<Eigen::Vector2d> all_tilted(turn.samples.size(), Eigen::Vector2d(0.0, 3.0 * kDegToRad));
  try {
    FitBidirectional(turn.samples, all_tilted);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("tilt"), std::string::npos) << e.what();
  }
  EXPECT_THROW(FitBidirectional(turn.samples, half_rp), std::invalid_argument);  // sizes differ
}

// ------------------------------------------------------------------------ planar (3-axis, one plane)

/// Sensor axes from body axes for a sensor mounted on its side: body z (down) is sensor -y,
/// so a level turn lies in the sensor's x/z plane (normal along y).
Eigen::Matrix3d SensorOnItsSide() { return Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitX()).toRotationMatrix(); }

struct MountedTurn {
  std::vector<MagSample> samples;
  std::vector<double> yaw_rad;
};

/// A level turn of a 3-axis sensor mounted with R_s_b: m_s = (I + S) R_s_b R_b_n m_n + h + n,
/// `degrees` of heading at 0.5 deg per sample.
MountedTurn SimulateMountedTurn(const Iron& iron, const Eigen::Matrix3d& R_s_b, double degrees, double noise_uT,
                                sim::Rng& rng) {
  MountedTurn turn;
  const int n = static_cast<int>(degrees / 0.5);
  for (int i = 0; i < n; ++i) {
    const double yaw = WrapPi(0.5 * kDegToRad * i + 0.3);
    MagSample s;
    s.t_s = 0.02 * i;
    s.m_b_uT = Measure(iron, DcmFromEuler(0.0, 0.0, yaw) * R_s_b.transpose(), noise_uT, rng);
    turn.samples.push_back(s);
    turn.yaw_rad.push_back(yaw);
  }
  return turn;
}

TEST(FitPlanar, LevelTurnOfASensorOnItsSideRecoversTheInPlaneHardIronAndTheHeading) {
  sim::Rng rng(51);
  const Iron iron = DrawIron(rng);
  const Eigen::Matrix3d R_s_b = SensorOnItsSide();
  const MountedTurn turn = SimulateMountedTurn(iron, R_s_b, 720.0, 0.3, rng);
  const MagCalibration c = FitPlanar(turn.samples);
  EXPECT_EQ(c.method, "planar");
  EXPECT_EQ(c.samples, 1440);
  // The readings lie on the image of the horizontal circle, M = (I + S) R_s_b: the plane
  // spanned by M e_x, M e_y through o = h + M (0, 0, V) (the vertical field through the soft
  // iron adds to the offset: only o's in-plane part is measurable, and it is what h calibrates).
  const Eigen::Matrix3d M = (Eigen::Matrix3d::Identity() + iron.S) * R_s_b;
  const Eigen::Vector3d n_true = M.col(0).cross(M.col(1)).normalized();
  const Eigen::Vector3d o = iron.h_uT + M * Eigen::Vector3d(0.0, 0.0, FieldNed().z());
  const Eigen::Vector3d n = c.uncalibrated_axis;
  // Plane normal from 1440 samples of 0.3 uT noise over a 27 uT circle: ~1e-3 rad.
  EXPECT_GT(std::abs(n.dot(n_true)), std::cos(0.5 * kDegToRad)) << n.transpose() << " vs " << n_true.transpose();
  EXPECT_GT(std::abs(n.y()), std::cos(15.0 * kDegToRad));  // about the sensor's y axis (S tilts it a little)
  EXPECT_NEAR(n.dot(c.hard_iron_uT), 0.0, 1e-9);      // no hard iron along the normal
  EXPECT_NEAR((c.correction * n - n).norm(), 0.0, 1e-9);  // A identity along it
  const Eigen::Vector3d h_error = (Eigen::Matrix3d::Identity() - n * n.transpose()) * (c.hard_iron_uT - o);
  std::cout << "[planar] in-plane |h error| " << h_error.norm() << " uT, sigma (" << c.hard_iron_sigma_uT.transpose()
            << ") uT, coverage " << c.coverage_deg << " deg, in-plane |m| spread " << c.field_spread_before_uT << " -> "
            << c.field_spread_after_uT << " uT, off-plane RMS " << c.out_of_plane_rms_uT << " uT\n";
  // sigma of the centre ~0.3 uT / sqrt(720) = 0.011 uT per axis: 0.06 uT is ~5 sigma.
  EXPECT_LT(h_error.norm(), 0.06);
  EXPECT_LT(c.hard_iron_sigma_uT.maxCoeff(), 0.02);
  // Two full turns at 0.5 deg per sample; noise jitters each direction by ~0.6 deg (0.3 uT
  // over 27 uT), widening the largest gap to ~1.5 deg.
  EXPECT_GT(c.coverage_deg, 355.0);
  EXPECT_GT(c.field_spread_before_uT, 5.0);  // 10-30 uT of hard iron
  EXPECT_LT(c.field_spread_after_uT, 0.35);  // the 0.3 uT noise (its radial part)
  EXPECT_TRUE(c.correction_sigma.allFinite());

  // Heading in the plane: the calibrated field without its (raw) normal component, back to
  // body axes, against the true yaw.
  double ss_before = 0.0, ss_after = 0.0;
  for (std::size_t i = 0; i < turn.samples.size(); ++i) {
    const Eigen::Vector3d& m = turn.samples[i].m_b_uT;
    Eigen::Vector3d m_c = ApplyMagCalibration(c, m);
    m_c -= n * n.dot(m_c);
    const double before = WrapPi(LevelHeading(R_s_b.transpose() * m, 0.0) - turn.yaw_rad[i]);
    const double after = WrapPi(LevelHeading(R_s_b.transpose() * m_c, 0.0) - turn.yaw_rad[i]);
    ss_before += before * before;
    ss_after += after * after;
  }
  const double n_samples = static_cast<double>(turn.samples.size());
  const double rms_before_deg = std::sqrt(ss_before / n_samples) / kDegToRad, rms_after_deg = std::sqrt(ss_after / n_samples) / kDegToRad;
  std::cout << "[planar heading] RMS heading error before " << rms_before_deg << " deg, after " << rms_after_deg
            << " deg\n";
  EXPECT_GT(rms_before_deg, 10.0);  // 10-30 uT of hard iron against the 27 uT horizontal field
  // Noise: 0.3 uT across 27 uT is 0.63 deg RMS; the symmetric in-plane correction leaves a
  // rotation of O(S^2) ~ 0.15 deg: 1 deg.
  EXPECT_LT(rms_after_deg, 1.0);
}

TEST(FitPlanar, HalfATurnAndASphereAreRefused) {
  sim::Rng rng(52);
  const Iron iron = DrawIron(rng);
  const MountedTurn half = SimulateMountedTurn(iron, SensorOnItsSide(), 180.0, 0.3, rng);
  try {
    FitPlanar(half.samples);
    FAIL() << "half a turn cannot calibrate the plane";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("360"), std::string::npos) << e.what();
  }
  try {
    FitPlanar(SphereSamples(iron, 500, 0.3, rng));
    FAIL() << "a sphere is not one plane";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not near one plane"), std::string::npos) << e.what();
  }
  EXPECT_THROW(FitPlanar(std::vector<MagSample>(half.samples.begin(), half.samples.begin() + 11)),
               std::invalid_argument);
  PlanarFitOptions bad;
  bad.min_coverage_rad = 400.0 * kDegToRad;
  EXPECT_THROW(FitPlanar(half.samples, bad), std::invalid_argument);
}

TEST(FitBidirectional, RefusesATurnOutsideTheXYPlaneAndImplausibleSoftIron) {
  sim::Rng rng(33);
  const Iron iron = DrawIron(rng);
  // A 3-axis sensor on its side: its level plane is x/z; x/y alone read a line, not a circle.
  const MountedTurn side = SimulateMountedTurn(iron, SensorOnItsSide(), 720.0, 0.3, rng);
  try {
    FitBidirectional(side.samples, std::vector<Eigen::Vector2d>(side.samples.size(), Eigen::Vector2d::Zero()));
    FAIL() << "the x/y plane is not the plane of the turn";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("planar"), std::string::npos) << e.what();
  }
  // y/x scale 0.4 (beyond the axis ratio 2) and a phase of 45 deg (beyond 36.9 deg).
  for (const auto& [M, expect] : {std::make_pair(TwoAxisIron(1.0, 0.4, 0.0), std::string("y/x scale")),
                                  std::make_pair(TwoAxisIron(1.0, 1.0, 45.0 * kDegToRad), std::string("phase"))}) {
    const LevelTurn turn = SimulateTurn(M, Eigen::Vector3d(5.0, 5.0, 0.0), 0.2, rng);
    try {
      FitBidirectional(turn.samples, turn.roll_pitch_rad);
      FAIL() << expect;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
    }
  }
  // Sigmas are not estimated by the 2-axis method: NaN (printed n/a, JSON null).
  const LevelTurn good = SimulateTurn(TwoAxisIron(1.0, 1.0, 0.0), Eigen::Vector3d(5.0, 5.0, 0.0), 0.2, rng);
  const MagCalibration c = FitBidirectional(good.samples, good.roll_pitch_rad);
  EXPECT_TRUE(c.hard_iron_sigma_uT.array().isNaN().all());
  EXPECT_TRUE(c.correction_sigma.array().isNaN().all());
  EXPECT_EQ(c.uncalibrated_axis, Eigen::Vector3d::UnitZ());
}

// ------------------------------------------------------------------------ heading

TEST(Heading, TiltCompensatedIsExactForTheTrueField) {
  sim::Rng rng(41);
  const double declination = -4.0 * kDegToRad;
  for (int i = 0; i < 100; ++i) {
    const double roll = rng.Uniform(-80.0, 80.0) * kDegToRad, pitch = rng.Uniform(-80.0, 80.0) * kDegToRad;
    const double yaw = rng.Uniform(-180.0, 180.0) * kDegToRad;
    const Eigen::Vector3d m_b = DcmFromEuler(roll, pitch, yaw).transpose() * FieldNed();
    // Rounding only (atan2 of ~27 uT components).
    EXPECT_NEAR(WrapPi(TiltCompensatedHeading(m_b, roll, pitch, declination) - (yaw + declination)), 0.0, 1e-12);
  }
  EXPECT_NEAR(LevelHeading(DcmFromEuler(0.0, 0.0, 1.0).transpose() * FieldNed(), 0.1), 1.1, 1e-12);
}

TEST(Heading, TiltErrorBoundIsTheSeeds) {
  // The seed: 2 deg of tilt at 57 deg inclination keeps a 2-axis heading within ~3 deg.
  // atan(tan 57 sin 2) = 3.077 deg; the exact maximum is a little above (cos t factor).
  EXPECT_NEAR(TiltErrorBound(2.0 * kDegToRad, kInclination_rad) / kDegToRad, 3.08, 0.01);
  // Attained: heading east, pitched by 2 deg; never exceeded at other headings and tilts.
  double worst = 0.0;
  for (int k = 0; k < 360; ++k) {
    for (const Eigen::Vector2d& rp : {Eigen::Vector2d(2.0, 0.0), Eigen::Vector2d(0.0, 2.0), Eigen::Vector2d(-1.4, 1.4)}) {
      const double yaw = k * kDegToRad;
      const Eigen::Vector3d m_b = DcmFromEuler(rp.x() * kDegToRad, rp.y() * kDegToRad, yaw).transpose() * FieldNed();
      worst = std::max(worst, std::abs(WrapPi(LevelHeading(m_b, 0.0) - yaw)));
    }
  }
  EXPECT_LE(worst, TiltErrorBound(2.0 * kDegToRad, kInclination_rad) + 1e-9);
  EXPECT_GT(worst, TiltErrorBound(2.0 * kDegToRad, kInclination_rad) - 0.01 * kDegToRad);  // 1 deg heading grid
  EXPECT_THROW(TiltErrorBound(std::nan(""), 1.0), std::invalid_argument);
}

// ------------------------------------------------------------------------ real data

std::vector<MagSample> ReadAll(MagReader& reader) {
  std::vector<MagSample> out;
  MagSample s;
  while (reader.Next(&s)) out.push_back(s);
  return out;
}

/// Fits and prints the field-magnitude spread before and after; returns the calibration or
/// rethrows a coverage error (printed) as nullptr.
std::unique_ptr<MagCalibration> FitReal(const std::string& name, const std::vector<MagSample>& samples) {
  try {
    auto c = std::make_unique<MagCalibration>(FitEllipsoid(samples));
    std::cout << "[real] " << name << ": " << samples.size() << " samples, |m| spread " << c->field_spread_before_uT
              << " -> " << c->field_spread_after_uT << " uT, B " << c->field_uT << " uT, h ("
              << c->hard_iron_uT.transpose() << ") uT, downweighted " << c->downweighted << "\n";
    return c;
  } catch (const std::runtime_error& e) {
    std::cout << "[real] " << name << ": " << samples.size() << " samples, not calibratable: " << e.what() << "\n";
    return nullptr;
  }
}

/// The what() of the runtime_error fit() throws ("" when it does not throw).
template <typename Fit>
std::string Refusal(Fit fit) {
  try {
    fit();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

// The DOT's straight flight holds one heading (yaw within ~5 deg): the readings are near one
// plane (normal about sensor -y) and an arc of its circle. Each method refuses with the
// reason instead of inventing a calibration (docs/calibration-magnetometer.md, real data).
TEST(RealData, XsensDotRawMagnetometer) {
  const std::string path =
      testing::DataPath("ansfl-quadrotor/StraightLine/RAW/Xsens_DOT1_D422CD003EBC_20220707_111438.csv");
  NAVTWIN_REQUIRE_DATA(path);
  const auto reader = OpenAnsflDotRawMag(path);
  const std::vector<MagSample> samples = ReadAll(*reader);
  ASSERT_GT(samples.size(), 1000u);
  const auto c = FitReal("DOT1 111438", samples);
  EXPECT_FALSE(c);
  const std::string ellipsoid = Refusal([&] { FitEllipsoid(samples); });
  EXPECT_NE(ellipsoid.find("all samples near one plane"), std::string::npos) << ellipsoid;
  const std::string planar = Refusal([&] { FitPlanar(samples); });
  std::cout << "[real] DOT1 111438 planar: " << planar << "\n";
  EXPECT_NE(planar.find("cover only"), std::string::npos) << planar;
  const std::string bidirectional = Refusal([&] {
    FitBidirectional(samples, std::vector<Eigen::Vector2d>(samples.size(), Eigen::Vector2d::Zero()));
  });
  std::cout << "[real] DOT1 111438 bidirectional: " << bidirectional << "\n";
  EXPECT_NE(bidirectional.find("not the sensor's x/y plane"), std::string::npos) << bidirectional;
}

TEST(RealData, Px4UlogMagnetometer) {
  const std::string path = testing::DataPath("px4-ulog/sample.ulg");
  NAVTWIN_REQUIRE_DATA(path);
  const auto reader = OpenMag(path);
  const std::vector<MagSample> samples = ReadAll(*reader);
  ASSERT_GT(samples.size(), 100u);
  const auto c = FitReal("px4 sample.ulg", samples);
  if (c) {
    EXPECT_LT(c->field_spread_after_uT, c->field_spread_before_uT);
  }
}

}  // namespace calibration_mag_calibration_test
}  // namespace navtwin::calibration

namespace navtwin::calibration {
namespace calibration_mag_calibration_test {

TEST(FieldMagnitudeSpread, IsThePopulationStdOfTheFieldMagnitude) {
  EXPECT_EQ(FieldMagnitudeSpread_uT({}), 0.0);
  std::vector<MagSample> mag(4);
  // |m| = 3, 5, 13, 5 uT: mean 6.5, population variance (12.25 + 2.25 + 42.25 + 2.25) / 4.
  const Eigen::Vector3d m_uT[4] = {{3.0, 0.0, 0.0}, {0.0, 3.0, 4.0}, {5.0, 0.0, -12.0}, {0.0, -5.0, 0.0}};
  for (int i = 0; i < 4; ++i) {
    mag[i].t_s = 0.1 * i;
    mag[i].m_b_uT = m_uT[i];
  }
  EXPECT_NEAR(FieldMagnitudeSpread_uT(mag), std::sqrt(59.0 / 4.0), 1e-12);
  // A constant magnitude in any direction has no spread.
  for (int i = 0; i < 4; ++i) mag[i].m_b_uT = 50.0 * m_uT[i].normalized();
  EXPECT_NEAR(FieldMagnitudeSpread_uT(mag), 0.0, 1e-12);
}

}  // namespace calibration_mag_calibration_test
}  // namespace navtwin::calibration
