// ANSFL quadrotor data set (Hurwitz & Klein, arXiv:2310.13452; CC BY 4.0): four Xsens
// DOT IMUs on a DJI Phantom 4 RTK and the DJI flight controller's solution as reference.
// docs/formats.md describes each file; in short:
//
// IMU_k.csv   time [s from the path start], Euler_X..Z [deg, unused], Acc_X..Z [m/s^2],
//             Gyr_X..Z [deg/s], 120 Hz -> ImuSample by the trapezoid rule
//             (rate_to_increment.h: the first row only starts the series, N rows give
//             N - 1 samples). AXES ARE THE DOT'S OWN, NOT ROTATED: its z axis points up
//             (Acc_Z ~ +9.8 m/s^2 at rest), so they are not FRD; the mounting on the
//             drone is unknown (an alignment problem, not a reader's).
// Xsens_DOT*.csv (StraightLine/RAW): SampleTimeFine [us, the DOT's uint32 clock since
//             power-on, unwrapped at 2^32], the same Acc/Gyr, optional Mag_X..Z [a.u.],
//             a trailing comma on every line. t_s = unwrapped device time in seconds.
//             Leading rows with all-zero Acc/Gyr are skipped (counted in the summary).
// Lost-sample repair (both kinds): the DOT marks a lost sample by giving the next row the
//             time of the one after it and repeating that time on the following row
//             (in RAW files that row's Acc/Gyr are NaN/Infinity; the processed files hold
//             hand-filled values there). The Euler angles show the first of the pair is
//             the sample one period earlier, so it is re-timed to the middle of the
//             double interval before it; a RAW row whose Acc/Gyr are not finite in that
//             pattern is dropped from the IMU stream. Both are counted; any other repeated
//             or decreasing time, or NaN, is an InputError.
// GT.csv      time [s], distance, speed, compass_heading, pitch, roll [deg],
//             height_above_takeoff, North, East, Down [m] at 10 Hz -> NavState.
// GTExtended.csv  time [ms], latitude, longitude [deg], altitude_above_seaLevel [m],
//             North, East, Down [m], xSpeed, ySpeed, zSpeed [m/s], roll, pitch,
//             compass_heading [deg] -> NavState. x/y/z speeds are North/East/Down: checked
//             against differenced positions (N, E) and, for the sign of z, against the
//             climb rate in the full DJI log (zSpeed = -d(height)/dt, correlation -0.97).
// Heights are the DJI log's (altitude above mean sea level, not the WGS84 ellipsoid).
// Attitude: q_n_b from (roll, pitch, compass_heading) as ZYX Euler angles of the drone.
// gps_week = -1 everywhere (the files carry no GPS time).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "core/earth.h"
#include "core/io/file_summary.h"
#include "core/io/sample_reader.h"

namespace navtwin {

/// One Xsens DOT magnetometer a.u. is "the field strength during calibration at Xsens'
/// calibration lab, approximately 40 uT" (Xsens DOT User Manual XD0502P, Table 9 note).
/// Approximate: the three DOTs here read 0.78-1.24 a.u. in the same field, so calibrate.
constexpr double kXsensDotMagUtPerUnit = 40.0;

/// IMU_k.csv (and IMU_avg.csv) of a path folder.
std::unique_ptr<ImuReader> OpenAnsflImu(const std::string& path);
/// Raw Xsens_DOT*.csv: IMU stream.
std::unique_ptr<ImuReader> OpenAnsflDotRawImu(const std::string& path);
/// Raw Xsens_DOT*.csv: magnetometer stream (a.u. * kXsensDotMagUtPerUnit, sensor axes).
/// InputError when the file has no Mag columns (DOT4's files do not).
std::unique_ptr<MagReader> OpenAnsflDotRawMag(const std::string& path);

/// The StraightLine flights' take-off point (GTExtended.csv of StraightLine/path_1, first
/// row: 32.8256829718786 deg N, 34.9559595644856 deg E, 10.1942341 m above mean sea level).
/// The Horizontal folders have no GTExtended.csv, hence no geodetic origin of their N/E/D
/// offsets; they were flown by the same group (University of Haifa), so this site stands
/// in. It sets only the normal gravity and the Earth rate's direction (1e-5 g and 1e-3
/// deg/h per km of error) and is the same for a GNSS file converted from GT.csv and for
/// GT.csv as --truth, so errors between the two do not depend on it.
wgs84::Geodetic AnsflSiteOrigin();

/// Default sigmas of the DJI reference used as GNSS fixes (`navtwin convert --what gnss`
/// from GT.csv / GTExtended.csv; docs/gnss-ins.md, "Smoothing an ANSFL DOT"):
///  - position 0.1 m: the N/E/D positions are not rounded; their 10 Hz second differences
///    are 1.4-3.8 cm RMS with the motion in them, so the noise is below 2 cm. What
///    dominates is the unknown lever arm from the DJI reference point to a DOT strapped on
///    the body (the airframe is 0.35 m across: up to about 0.1 m) and the DJI solution's own
///    error (RTK or not is not logged);
///  - velocity 0.15 m/s: GTExtended's speeds are rounded to 0.1 m/s (0.029 m/s uniform);
///    the Horizontal paths have only differenced positions, which on StraightLine/path_2
///    differ from the speeds by 0.06-0.15 m/s (std per axis); a 0.1 m lever arm adds
///    omega x l, up to 0.17 m/s in the Horizontal flights' 100 deg/s yaw spins.
constexpr double kAnsflReferencePosSigma_m = 0.1;
constexpr double kAnsflReferenceVelSigma_mps = 0.15;

struct AnsflGtOptions {
  /// Origin of the North/East/Down offsets of GT.csv. Unset: the first row of
  /// GTExtended.csv in the same folder when that file exists (it is the point where
  /// N = E = D = 0), else AnsflSiteOrigin().
  std::optional<wgs84::Geodetic> origin;
};

/// GT.csv. Position = origin + (North, East, Down) through WGS84 (exact). Velocity: from
/// GTExtended.csv's x/y/z speeds when that file is beside it (rows matched one to one and
/// checked in time), else central differences of the N/E/D positions (one-sided at the
/// ends). t_s = GT time [s from the path start].
std::unique_ptr<NavReader> OpenAnsflGt(const std::string& path, const AnsflGtOptions& options = {});
/// GTExtended.csv; t_s = time [ms] / 1000 (the DJI log's clock).
std::unique_ptr<NavReader> OpenAnsflGtExtended(const std::string& path);

/// Summaries with the repair counts in the notes.
FileSummary DescribeAnsflImu(const std::string& path);
FileSummary DescribeAnsflDotRaw(const std::string& path);

}  // namespace navtwin
