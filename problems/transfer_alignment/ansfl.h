// Transfer alignment on the real ANSFL quadrotor flights (issue 6 evidence): the DJI flight
// controller's RTK-GNSS/INS solution (GT.csv with GTExtended.csv beside it: 10 Hz attitude,
// velocity, position) is the master; each Xsens DOT IMU (IMU_k.csv, 120 Hz, its own axes
// with z up) is a slave whose mounting R_b_s and clock offset are unknown. The mounting is
// far from identity (the DOTs' axes are about forward-left-up: 180 deg about x from the
// drone's FRD, plus a few degrees), so a coarse solution comes first:
//  - clock offset: the lag maximising the correlation of |omega| of the DOT gyro with the
//    body rate magnitude differenced from the GT attitude, searched over +-max_offset_s;
//  - mounting: the rotation that best maps the DOT's angular rates onto the GT body rates
//    at that lag (Wahba's problem solved by SVD, Kabsch, with the DOT gyro bias as the
//    centroid offset: the DOTs' biases are 0.5-2 deg/s), which needs rotation about two
//    axes at least (checked: a report instead of a number when the rates span a line);
// then the transfer-alignment method refines mounting and delay (the delay here is the
// residual clock offset plus the DJI solution's own latency).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/calibration_file.h"
#include "problems/transfer_alignment/config.h"
#include "problems/transfer_alignment/inputs.h"
#include "problems/transfer_alignment/run.h"

namespace navtwin::transfer {

struct CoarseAlignment {
  double clock_offset_s = 0.0;   ///< add to the DOT times to put them on the GT time scale
  Eigen::Quaterniond mounting = Eigen::Quaterniond::Identity();  ///< R_b_s
  /// DOT gyro bias (DOT axes): omega_b = R_b_s (omega_s - bias) over the fit.
  Eigen::Vector3d gyro_bias_s_radps = Eigen::Vector3d::Zero();
  double rate_residual_rms_radps = 0.0;  ///< of R_b_s (omega_s - bias) - omega_b after the fit
  double correlation = 0.0;              ///< of the |omega| series at the chosen lag
};

/// Coarse clock offset and mounting from the DOT gyro and the GT attitude. Throws
/// std::runtime_error with the reason when the rotation does not excite two axes.
CoarseAlignment CoarseAlignAnsfl(const std::vector<ImuSample>& dot_imu, const std::vector<NavState>& gt,
                                 double max_offset_s = 2.0);

/// Inputs for one path folder and one DOT (1-4): GT.csv (master, tags = GT times), IMU_k.csv
/// shifted by the coarse clock offset and with the coarse gyro bias removed, the coarse
/// mounting as misalignment guess, the slave initial state from the first GT record inside
/// the DOT record. No truth (the result is scored by repeatability).
TransferInputs LoadAnsflPath(const std::string& path_dir, int dot, CoarseAlignment* coarse = nullptr);

struct AnsflAlignment {
  std::string path;      ///< e.g. "StraightLine/path_1"
  int dot = 0;
  CoarseAlignment coarse;
  TransferResult result;  ///< misalignment, delay with sigma
  /// RMS of the attitude matching residual after alignment (slave vs master x mounting), mrad.
  double residual_attitude_mrad = 0.0;
  std::string note;       ///< why a run was skipped or is unreliable
};

/// Configuration for the DOT slaves against the DJI master (values and their sources in
/// ansfl.cc and docs/transfer-alignment-real.md).
TransferConfig AnsflDotConfig();

/// Which paths and DOTs to align (defaults: all).
struct AnsflSelection {
  std::string path;  ///< a path folder relative to the data directory, e.g. "Horizontal/path_4"; empty: all
  int dot = 0;       ///< 1-4; 0: every IMU_k.csv of the path
};

/// Every StraightLine/path_* and Horizontal/path_* under data_dir and every IMU_k.csv in
/// it (or the selected ones: InputError when the selected folder or DOT file is missing),
/// with the given method. Progress on stderr.
std::vector<AnsflAlignment> AlignAllAnsfl(const std::string& data_dir, const TransferConfig& config, Method method,
                                          const AnsflSelection& selection = {});

/// The coarse step succeeded (CoarseAlignAnsfl set a correlation > 0 at its peak).
bool AnsflCoarseOk(const AnsflAlignment& a);
/// The refinement gave a mounting and delay (no note, or only "no epoch after settle_s").
bool AnsflRefined(const AnsflAlignment& a);

/// The calibration file of one refined alignment (docs/calibration-file.md), for
/// `smooth --calibration`: installation = the refined mounting R_b_s (ZYX Euler) and the time
/// offset clock_offset_s + delay_s (the DOT sample tagged t_dot belongs to GT.csv's time
/// t_dot + offset + delay: the GT record tagged t carries the drone's state at t - delay),
/// with the refinement's sigmas (the delay's covers the coarse offset's error: it is
/// estimated around it); imu.gyro.bias_rad_per_s = the coarse gyro bias (DOT axes), which
/// the calibration removes before the mounting turns the DOT into body axes.
/// std::invalid_argument when the alignment was not refined (AnsflRefined).
CalibrationFile AnsflCalibrationFile(const AnsflAlignment& a, const std::string& created_by);

/// Mean, sample standard deviation (n - 1; NaN for one value) and max - min of values; NaN
/// for none. Angles (rad) that may wrap at +-pi (the DOT roll is near pi) are first brought
/// next to the first one, and their mean is wrapped to (-pi, pi].
struct SampleSpread {
  int n = 0;
  double mean = std::numeric_limits<double>::quiet_NaN();
  double std = std::numeric_limits<double>::quiet_NaN();
  double range = std::numeric_limits<double>::quiet_NaN();
};
SampleSpread SpreadOf(const std::vector<double>& values, bool angle_rad);

/// One DOT's mounting and delay across the paths of a group: the score of an alignment
/// without truth.
struct DotRepeatability {
  int dot = 0;
  std::string group;              ///< "all", "StraightLine" or "Horizontal"
  SampleSpread coarse_rad[3];     ///< coarse mounting roll, pitch, yaw (paths with AnsflCoarseOk)
  SampleSpread mounting_rad[3];   ///< refined mounting roll, pitch, yaw (paths with AnsflRefined)
  SampleSpread delay_s;           ///< refined delay
  SampleSpread residual_rad;      ///< residual attitude (finite ones)
};

/// Per DOT (in increasing order), over all its paths and over each flight type (the path's
/// first folder: their excitation differs, the StraightLine flights barely rotate, the
/// Horizontal ones spin in yaw), groups in name order.
std::vector<DotRepeatability> AnsflRepeatability(const std::vector<AnsflAlignment>& runs);

}  // namespace navtwin::transfer
