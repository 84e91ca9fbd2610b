// Magnetometer calibration (seed 001 section 3, issue 8): hard and soft iron.
//
// Sensor model (core/mag_iron_model.h, as the simulator draws it): m = (I + S) m_b + h + n,
// with m_b the Earth field in body axes (|m_b| = B everywhere), S the soft iron, h the hard
// iron, n noise.
// Calibration: m_b ~ A (m - h), A = (I + S)^-1 up to a rotation; A is estimated SYMMETRIC
// (6 unknowns: the rotation part of (I + S)^-1 cannot be seen from magnitudes alone and is
// the IMU-to-magnetometer alignment, not iron), h has 3, and the field magnitude B is fixed
// (given) or fitted with |A| scaled so that the mean corrected magnitude is B.
//
// Methods:
//  - FitEllipsoid (3-axis, batch): Ceres least squares of r_i = |A (m_i - h)| - B over all
//    samples with a robust loss (Huber or Cauchy, scale in uT), started from the algebraic
//    ellipsoid fit (linear least squares on the quadric). Parameter sigmas from
//    ceres::Covariance; a coverage check: the directions (m_i - h)/|m_i - h| must span the
//    sphere enough (eigenvalues of their scatter), else std::runtime_error naming what is
//    missing (e.g. "all samples near one plane: the axis normal to it is not calibrated").
//  - RecursiveEllipsoidFit (3-axis, recursive): recursive least squares on the algebraic
//    quadric parameters as samples arrive, with the same calibration available at any time.
//  - FitPlanar (3-axis data near one plane: a level flight or a level turn, in whatever
//    sensor plane): the plane from the smallest-eigenvalue direction n of the scatter, then
//    in the plane's 2-D coordinates a centre and a symmetric 2x2 correction (ellipse ->
//    circle; Ceres, robust loss, sandwich sigmas as FitEllipsoid). Lifted to 3-D with the
//    component along n left uncalibrated (hard iron 0 and A identity along n). Refuses
//    when the in-plane directions cover < 270 deg or the ellipse is implausible.
//  - FitBidirectional (the seed's 2-axis method): from a level turn of a 2-axis sensor, hard
//    iron as the midpoint of opposite readings (pairs 180 deg apart in heading:
//    h = (m(psi) + m(psi + 180))/2, taken from the extremes of each axis), soft iron as the
//    x/y phase correction (the heading between the x and y maxima should be 90 deg; the
//    seed's example is -15.32 deg) and a y/x scale; valid only while |roll|, |pitch| are
//    within max_tilt (the seed: 2 deg keeps the heading error within 3 deg at 57 deg
//    inclination); TiltErrorBound gives that relation.
//  - Heading: TiltCompensatedHeading (3-axis, roll and pitch from the IMU) and
//    LevelHeading (2-axis), both plus the declination to true north.
#pragma once

#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/mag_iron_model.h"
#include "core/types.h"
#include "core/units.h"

namespace navtwin::calibration {

struct MagCalibration {
  Eigen::Vector3d hard_iron_uT = Eigen::Vector3d::Zero();  ///< h
  Eigen::Matrix3d correction = Eigen::Matrix3d::Identity();  ///< A (symmetric for the ellipsoid fit)
  double field_uT = 0.0;                                     ///< B
  /// 1-sigma of h and of A (A00 A01 A02 A11 A12 A22); NaN where not estimated (the
  /// bidirectional method and the recursive fit give none).
  Eigen::Vector3d hard_iron_sigma_uT = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 6, 1> correction_sigma = Eigen::Matrix<double, 6, 1>::Zero();
  /// Unit vector (sensor axes) along which nothing is calibrated (h has no component along
  /// it and A maps it to itself): the plane normal of FitPlanar, z for FitBidirectional;
  /// zero for the 3-axis fits, which calibrate every axis.
  Eigen::Vector3d uncalibrated_axis = Eigen::Vector3d::Zero();
  double residual_rms_uT = 0.0;        ///< RMS of |A (m - h)| - B over the samples used
  /// std of |m| before and of |A (m - h)| after calibration; for the planar and 2-axis
  /// methods the magnitudes of the in-plane part only (the component along
  /// uncalibrated_axis is left out, before and after).
  double field_spread_before_uT = 0.0;
  double field_spread_after_uT = 0.0;
  int samples = 0;
  int downweighted = 0;                ///< robust weight < 0.5
  std::string method;                  ///< "ellipsoid", "recursive", "planar", "bidirectional"
  /// Planar and 2-axis: the angle (deg) covered by the in-plane field directions after
  /// calibration (360 minus the largest gap); 0 for the 3-axis fits.
  double coverage_deg = 0.0;
  /// Planar: RMS distance of the samples from the fitted plane (uT); 0 otherwise.
  double out_of_plane_rms_uT = 0.0;
};

/// A (m - h).
Eigen::Vector3d ApplyMagCalibration(const MagCalibration& c, const Eigen::Vector3d& m_uT);

/// The field magnitude of a sample raw and calibrated, as MagCalibration's spreads measure
/// it: |m| and |A (m - h)|, or with an uncalibrated axis n their parts normal to n.
struct FieldMagnitude {
  double before_uT = 0.0;
  double after_uT = 0.0;
};
FieldMagnitude FieldMagnitudeOf(const MagCalibration& c, const Eigen::Vector3d& m_uT);

/// residuals.csv of `calibrate-mag --run_dir` (docs/run-folder.md): `t_s,field_before_uT,
/// field_after_uT`, FieldMagnitudeOf every sample.
void WriteMagResidualsCsv(std::ostream& out, const MagCalibration& c, const std::vector<MagSample>& samples);

enum class MagLoss { kNone, kHuber, kCauchy };

struct EllipsoidFitOptions {
  MagLoss loss = MagLoss::kCauchy;
  double loss_scale_uT = 2.0;
  /// Field magnitude to scale to (uT); <= 0: keep the algebraic fit's mean magnitude.
  double field_uT = 0.0;
  int max_iterations = 50;
  /// Smallest accepted ratio of the smallest to the largest eigenvalue of the direction
  /// scatter (a full sphere has 1; a single plane 0).
  double min_coverage = 0.02;
};

MagCalibration FitEllipsoid(const std::vector<MagSample>& samples, const EllipsoidFitOptions& options = {});

class RecursiveEllipsoidFit {
 public:
  explicit RecursiveEllipsoidFit(double field_uT = 0.0);
  void Add(const Eigen::Vector3d& m_uT);
  int count() const { return count_; }
  /// The calibration from the samples so far (needs >= 9 well-spread samples; throws
  /// std::runtime_error otherwise).
  MagCalibration Current() const;

 private:
  double field_uT_;
  int count_ = 0;
  Eigen::Matrix<double, 9, 9> P_;
  Eigen::Matrix<double, 9, 1> theta_;
};

/// One estimate of the recursive fit over a record (FitRecursive): after `samples` samples
/// (the last at t_s), the calibration, or why there is none yet.
struct RecursiveMagStep {
  std::size_t samples = 0;
  double t_s = 0.0;
  std::optional<MagCalibration> estimate;
  std::string why_not;  ///< when !estimate
};

/// RecursiveEllipsoidFit over `samples` in order, with an estimate after every `block`
/// samples and after the last (to `on_step`); returns the last estimate with its residual
/// RMS and |m| spreads over every sample (as FitEllipsoid reports them). Throws
/// std::runtime_error when the whole record cannot calibrate.
MagCalibration FitRecursive(const std::vector<MagSample>& samples, double field_uT, std::size_t block,
                            const std::function<void(const RecursiveMagStep&)>& on_step);

/// convergence.csv of `calibrate-mag --method recursive --run_dir`: `samples,t_s,
/// hard_iron_x_uT,hard_iron_y_uT,hard_iron_z_uT,field_uT`, nan while not determined.
void WriteMagConvergenceCsv(std::ostream& out, const std::vector<RecursiveMagStep>& steps);

struct PlanarFitOptions {
  MagLoss loss = MagLoss::kCauchy;
  double loss_scale_uT = 2.0;
  int max_iterations = 50;
  /// Smallest accepted angle covered by the in-plane directions (rad): with a gap below
  /// 90 deg, at most one of the four extremes of any pair of in-plane axes is unseen, so
  /// both extremes of one axis and at least one of the other bound the centre and the shape.
  double min_coverage_rad = 270.0 * kDegToRad;
  /// Largest accepted RMS distance from the plane as a fraction of the in-plane radius R:
  /// a tilt t about a horizontal axis at a random angle moves a sample out of the plane by
  /// R t / sqrt(2) RMS, so 0.15 is ~12 deg of tilt (a heading error of ~18 deg at 57 deg
  /// inclination, TiltErrorBound): beyond it the data are not one plane (use FitEllipsoid).
  double max_out_of_plane = 0.15;
};

/// Planar calibration of a 3-axis sensor from data near one plane (any sensor plane). The
/// plane normal n is the smallest-eigenvalue direction of the sample scatter; field_uT is the
/// circle radius (the field component in that plane, e.g. the horizontal field for a level
/// turn). Throws std::invalid_argument for bad input (too few samples, NaN, bad options),
/// std::runtime_error naming what is missing when the data cannot calibrate.
MagCalibration FitPlanar(const std::vector<MagSample>& samples, const PlanarFitOptions& options = {});

struct BidirectionalOptions {
  double max_tilt_rad = 2.0 * kDegToRad;  ///< samples with |roll| or |pitch| above this are left out
};

/// 2-axis (x, y) calibration from samples taken during a level turn through at least 360
/// deg; roll_pitch_rad[i] = (roll, pitch) of sample i (from the IMU; zeros if level).
/// correction = [[1, 0, 0], [-sin(phase) * k, cos(phase) * k, 0], [0, 0, 1]]-style 2x2 block
/// documented in the implementation. Throws std::runtime_error when the turn does not cover
/// both extremes of both axes, when the y/x scale or the phase is implausible (beyond what
/// a correction axis ratio of 2 gives: scale outside [1/2, 2], |phase| > 36.9 deg) or when
/// the data's plane is not the sensor's x/y plane (normal > 20 deg from z: use FitPlanar).
MagCalibration FitBidirectional(const std::vector<MagSample>& samples, const std::vector<Eigen::Vector2d>& roll_pitch_rad,
                                const BidirectionalOptions& options = {});

/// Population standard deviation of |m| over the samples, uT (0 for none): the spread a
/// calibration should shrink, and what a refused fit reports about its data.
double FieldMagnitudeSpread_uT(const std::vector<MagSample>& samples);

/// Heading (rad, true north) from a calibrated 3-axis body-axis field, roll and pitch.
double TiltCompensatedHeading(const Eigen::Vector3d& m_b_uT, double roll_rad, double pitch_rad, double declination_rad);
/// Heading from the horizontal (x, y) components only (2-axis sensor, level).
double LevelHeading(const Eigen::Vector3d& m_b_uT, double declination_rad);
/// Largest heading error (rad) a 2-axis sensor makes at tilt t and inclination I:
/// about t tan I (the seed: 2 deg at 57 deg -> 3.1 deg).
double TiltErrorBound(double tilt_rad, double inclination_rad);

}  // namespace navtwin::calibration
