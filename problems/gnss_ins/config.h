// Configuration of the GNSS/INS/magnetometer estimators (filter, RTS, batch). SI units
// and radians inside; the YAML file says its units in its keys (docs/gnss-ins.md lists
// every key), and a KF-GINS configuration is accepted unchanged (ParseKfginsConfig).
#pragma once

#include <limits>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "core/mag_iron_model.h"
#include "core/types.h"
#include "problems/gnss_ins/ins_vocabulary.h"
#include "problems/ins/sources/odometer.h"
#include "core/units.h"

namespace navtwin::gnss_ins {


/// 1-sigma uncertainty of the initial state (error-state layout of ins_state.h).
struct InitialStd {
  Eigen::Vector3d pos_ned_m = Eigen::Vector3d::Constant(10.0);
  Eigen::Vector3d vel_ned_mps = Eigen::Vector3d::Constant(1.0);
  Eigen::Vector3d att_rad = Eigen::Vector3d::Constant(0.1);
  Eigen::Vector3d bg_radps = Eigen::Vector3d::Zero();  ///< zero: take ImuNoise::gyro_bias_std
  Eigen::Vector3d ba_mps2 = Eigen::Vector3d::Zero();   ///< zero: take ImuNoise::accel_bias_std
  Eigen::Vector3d sg = Eigen::Vector3d::Zero();        ///< zero: take ImuNoise::gyro_scale_std
  Eigen::Vector3d sa = Eigen::Vector3d::Zero();        ///< zero: take ImuNoise::accel_scale_std
};

/// How the IMU is installed.
struct Installation {
  /// Roll, pitch, yaw (ZYX) of the IMU axes relative to the body FRD axes:
  /// v_b = DcmFromEuler(r, p, y) * v_imu.
  Eigen::Vector3d imu_mounting_rpy_rad = Eigen::Vector3d::Zero();
  /// Added to the IMU time tags to put them on the GNSS time scale.
  double imu_time_offset_s = 0.0;
  /// GNSS antenna phase centre from the IMU, body FRD axes.
  Eigen::Vector3d antenna_lever_arm_b_m = Eigen::Vector3d::Zero();
};

/// Initial state: given (a KF-GINS initpos/initvel/initatt, or an init nav file), or from
/// an alignment.
struct InitConfig {
  enum class Source {
    kGiven,            ///< `state` below
    kStaticAlignment,  ///< coarse alignment (gravity + Earth rate, or + magnetometer heading)
                       ///< over the first static_duration_s; position from the first GNSS fix
    kGnssVelocity,     ///< level attitude, heading from the GNSS velocity once the speed
                       ///< exceeds min_speed_mps; position and velocity from GNSS
  };
  /// Heading of the static alignment (kStaticAlignment only).
  enum class Heading {
    kAuto,          ///< the magnetometer when mag.mode is not off, else gyrocompassing
    kGyrocompass,   ///< from the mean angular rate (the Earth rate: navigation-grade gyros only)
    kMagnetometer,  ///< from the mean magnetometer sample (needs mag.mode not off)
    kSearch,        ///< one filter per heading hypothesis over the first GNSS data, the most
                    ///< likely one wins (problems/gnss_ins/heading_search.h)
  };
  Source source = Source::kGiven;
  std::optional<InsState> state;  ///< required for kGiven (time = start)
  /// kGiven from a navigation file chosen on the command line (`--init_from`): `state` is
  /// its record at start_time_s or, without a start, at the start of the IMU record as the
  /// installation's time offset puts it, which only the inputs know (RunGnssIns fills
  /// `state` then). Empty: `state` as configured.
  std::string nav_file_at_start;
  /// kGiven: the position (and the start) from the first GNSS fix at or after the state's
  /// time, velocity and attitude from `state` (OB_GINS starts so).
  bool position_from_gnss = false;
  double static_duration_s = 60.0;
  Heading heading = Heading::kAuto;
  int heading_hypotheses = 8;      ///< kSearch: headings k 360 deg / heading_hypotheses
  double heading_search_s = 30.0;  ///< kSearch: GNSS data (s of epochs) after the alignment
  double min_speed_mps = 5.0;
  ImuErrors imu_errors;           ///< initial IMU error estimates (KF-GINS initgyrbias, ...)
  InitialStd std;
};

/// Injected GNSS outages for scoring: no GNSS in [start + k period, start + k period + len).
struct OutageConfig {
  double start_s = std::numeric_limits<double>::quiet_NaN();  ///< NaN: none (relative to the
                                                              ///< first IMU time)
  double len_s = 0.0;
  double period_s = 0.0;  ///< 0: a single outage
};

struct FilterConfig {
  bool scale_factors = false;          ///< 21 states instead of 15
  double gate_probability = 0.9999;    ///< chi-square gate on each innovation (1: no gating)
  double store_interval_s = 1.0;       ///< RTS knots: every update and at least this often
  double max_bridge_gap_s = 0.1;       ///< IMU gaps up to this are bridged, longer stop the run
  /// After this many GNSS positions in a row rejected by the gate, position (and velocity)
  /// are reset to the fix with its covariance (0: never).
  int gnss_reset_rejections = 10;
  /// The covariance is propagated over groups of IMU samples at most this long (the
  /// nominal state at every sample); 0: at every sample.
  double covariance_interval_s = 0.02;
};

struct BatchConfig {
  double state_interval_s = 0.0;   ///< 0: a state at every GNSS epoch (and every max_state_interval_s)
  double max_state_interval_s = 1.0;
  double huber_k = 3.0;            ///< Huber threshold on GNSS residuals, in sigmas (0: plain)
  int max_iterations = 50;
  int threads = 1;
  bool covariance = true;          ///< per-state standard deviations from ceres::Covariance
  double relinearize_bias_radps = 0.0;  ///< re-preintegrate when a gyro bias moves more (0: auto)
  /// Variance-component estimation: each residual group's noise scaled to fit its residuals
  /// (solvers/residual_groups.h), re-solving up to variance_rounds times.
  bool variance_components = true;
  int variance_rounds = 10;
};

struct GnssInsConfig {
  ImuNoise imu_noise;
  Installation installation;
  InitConfig init;
  MagConfig mag;
  BaroConfig baro;
  ZuptConfig zupt;
  NhcConfig nhc;
  ins::OdometerConfig odometer;
  VehicleConfig vehicle;
  GnssConfig gnss;
  OutageConfig outages;
  FilterConfig filter;
  BatchConfig batch;
  double start_time_s = -std::numeric_limits<double>::infinity();
  double end_time_s = std::numeric_limits<double>::infinity();
  double output_rate_hz = 0.0;  ///< 0: every IMU epoch
  /// Rate of std.csv and imu_errors.csv among the output epochs (0: every output epoch):
  /// a second's rows of σ and IMU errors change little, and at every 200 Hz epoch they were
  /// most of the bytes a run wrote.
  double std_rate_hz = 1.0;
  /// KF-GINS paths when the configuration came from a KF-GINS file (empty otherwise).
  std::string imu_path, gnss_path, output_path;
};

/// Parses navtwin's YAML configuration (keys in docs/gnss-ins.md). Unknown keys, missing
/// required keys, non-positive sigmas: InputError naming file, line and key.
/// `init_state_on_command_line`: the initial state comes from elsewhere (`--init_from`,
/// InitConfig::nav_file_at_start), so `init.source: given` (the default) may come without
/// nav_file or values; the rest of the init section (stds, IMU errors) still applies.
GnssInsConfig LoadGnssInsConfig(const std::string& path, bool init_state_on_command_line = false);

/// Reads a KF-GINS YAML configuration unchanged (imupath, gnsspath, outputpath,
/// imudatalen, imudatarate, starttime, endtime, initpos [deg deg m], initvel [m/s],
/// initatt [deg], initposstd [m], initvelstd [m/s], initattstd [deg], initgyrbias [deg/h],
/// initaccbias [mGal], initgyrscale [ppm], initaccscale [ppm], initbgstd [deg/h],
/// initbastd [mGal], initsgstd [ppm], initsastd [ppm], imunoise {arw [deg/sqrt(h)],
/// vrw [m/s/sqrt(h)], gbstd [deg/h], abstd [mGal], gsstd [ppm], asstd [ppm], corrtime [h]},
/// antlever [m]). Relative paths are taken relative to the current directory, as KF-GINS does.
GnssInsConfig LoadKfginsConfig(const std::string& path);

/// Reads an OB_GINS YAML configuration unchanged (imufile, gnssfile, outputpath, starttime,
/// endtime, initvel [m/s], initatt [deg], initgb [deg/h], initab [mGal], imudatalen,
/// imudatarate, antlever, odolever, bodyangle [deg] (C_b^v), odometer {isuseodo, std [m/s],
/// srw [ppm]}, imumodel {arw, vrw, gbstd, abstd, corrtime}, isuseoutage, outagetime,
/// outagelen, outageperiod; windows, isearth and gnssthreshold are listed as not used).
/// The position comes from the first GNSS fix at or after starttime, as in OB_GINS; with
/// isuseodo the odometer column of the 8-column IMU file and the NHC are used.
GnssInsConfig LoadObginsConfig(const std::string& path);

}  // namespace navtwin::gnss_ins
