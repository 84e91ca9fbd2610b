// The calibration file (YAML) that every calibration command writes and every IMU and
// magnetometer reader applies through --calibration FILE. Schema and units in
// docs/calibration-file.md; in short:
//
//   navtwin_calibration: 1
//   created_by: "navtwin calibrate-imu --rig multiposition ..."   (free text)
//   imu:                                  (optional)
//     gyro:  {scale_factor: [3], misalignment_rad: [[3]x3, diagonal 0], bias_rad_per_s: [3],
//             g_sensitivity_rad_per_s_per_mps2: [[3]x3]}
//     accel: {scale_factor: [3], misalignment_rad: [[..]], bias_mps2: [3]}
//     sigma: the same layout, one standard deviation per value (optional, for reports)
//     temperature:                        (optional; applied at --imu_temperature_degC)
//       reference_degC: 25
//       gyro_bias_rad_per_s: [[c1x,c1y,c1z], [c2x,c2y,c2z], ...]    bias += sum_k c_k dT^k
//       gyro_scale_factor:   [[...], ...]                             s += sum_k c_k dT^k
//       accel_bias_mps2:     [[...], ...]
//       accel_scale_factor:  [[...], ...]
//   mag:                                  (optional)
//     hard_iron_uT: [3]     h
//     correction: [[3]x3]   A: m_corrected = A (m - h), A = (I + S)^-1 for the soft iron S
//                           (core/mag_iron_model.h); older files name A `soft_iron`
//     field_uT: B
//   installation:                         (optional; applied by navigate and smooth only)
//     imu_mounting_rpy_rad: [r, p, y]     R_b_imu as ZYX Euler angles: v_b = DcmFromEuler(r, p, y) v_imu
//     imu_time_offset_s: o                added to the IMU time tags (the reference's time scale)
//     sigma: {imu_mounting_rpy_rad: [3], imu_time_offset_s: x}   (optional, reports only)
//
// Any key missing inside a present imu or mag section means "no error" (zero) for that
// term; the installation section needs both of its values (a hand-edited file that lost
// one would otherwise be applied with a zero there).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/io/sample_reader.h"
#include "core/imu_error_model.h"
#include "core/mag_iron_model.h"

namespace navtwin {

/// Polynomial temperature terms: coefficient k (k = 1..order) of dT^k per axis.
struct TemperatureTerms {
  double reference_degC = 25.0;
  std::vector<Eigen::Vector3d> gyro_bias_rad_per_s;
  std::vector<Eigen::Vector3d> gyro_scale_factor;
  std::vector<Eigen::Vector3d> accel_bias_mps2;
  std::vector<Eigen::Vector3d> accel_scale_factor;
};

struct ImuCalibration {
  /// Triad blocks in the layout of core/imu_error_model.h (SI units).
  Eigen::Matrix<double, kTriadParameters, 1> gyro = Eigen::Matrix<double, kTriadParameters, 1>::Zero();
  Eigen::Matrix<double, kTriadParameters, 1> accel = Eigen::Matrix<double, kTriadParameters, 1>::Zero();
  Eigen::Matrix<double, kGSensitivityParameters, 1> g_sensitivity =
      Eigen::Matrix<double, kGSensitivityParameters, 1>::Zero();
  /// One sigma per value (NaN where not estimated); written under `sigma`.
  std::optional<Eigen::Matrix<double, kTriadParameters, 1>> gyro_sigma, accel_sigma;
  std::optional<Eigen::Matrix<double, kGSensitivityParameters, 1>> g_sensitivity_sigma;
  std::optional<TemperatureTerms> temperature;

  /// The gyro and accel blocks with the temperature terms evaluated at temperature_degC
  /// (the constant blocks when there are no temperature terms).
  ImuCalibration At(double temperature_degC) const;
};

/// The iron of core/mag_iron_model.h in the correction form a calibration estimates.
struct MagCorrection {
  Eigen::Vector3d hard_iron_uT = Eigen::Vector3d::Zero();   ///< h
  Eigen::Matrix3d correction = Eigen::Matrix3d::Identity();  ///< A = (I + S)^-1
  double field_uT = 0.0;                                    ///< 0: unknown
};

/// Where the IMU sits on the vehicle and how its clock relates to the reference's: what an
/// alignment against a reference trajectory estimates (navtwin transfer-align-ansfl). The
/// same quantities as a GNSS/INS configuration's installation.imu_mounting_deg and
/// installation.imu_time_offset_s (problems/gnss_ins/config.h), in SI.
struct ImuInstallation {
  /// ZYX Euler angles (roll, pitch, yaw) of R_b_imu, v_b = DcmFromEuler(r, p, y) v_imu;
  /// roll and yaw in [-pi, pi], pitch in [-pi/2, pi/2].
  Eigen::Vector3d mounting_rpy_rad = Eigen::Vector3d::Zero();
  /// Added to the IMU time tags to put them on the reference's (GNSS) time scale.
  double time_offset_s = 0.0;
  /// One sigma each (NaN: not estimated); written under `sigma` when set.
  std::optional<Eigen::Vector3d> mounting_sigma_rad;
  std::optional<double> time_offset_sigma_s;
};

struct CalibrationFile {
  std::string created_by;
  std::optional<ImuCalibration> imu;
  std::optional<MagCorrection> mag;
  std::optional<ImuInstallation> installation;
};

/// Throws InputError naming the file, line and key (unknown keys, wrong sizes, non-finite
/// values, a non-invertible I + diag(s) + M or correction A, a missing version).
CalibrationFile ReadCalibrationFile(const std::string& path);
/// Writes atomically (the file appears whole or not at all).
void WriteCalibrationFile(const std::string& path, const CalibrationFile& file);

/// Compensates one IMU sample (increments): dv' = K_a^-1 (dv - b_a dt),
/// dtheta' = K_g^-1 (dtheta - G dv' - b_g dt).
ImuSample ApplyImuCalibration(const ImuCalibration& c, const ImuSample& s);
MagSample ApplyMagCorrection(const MagCorrection& c, const MagSample& s);

/// Readers that compensate every sample of `inner`. The IMU reader evaluates the temperature
/// terms at temperature_degC (NaN: at the file's reference temperature).
std::unique_ptr<ImuReader> CalibratedImuReader(std::unique_ptr<ImuReader> inner, const ImuCalibration& c,
                                               double temperature_degC);
std::unique_ptr<MagReader> CalibratedMagReader(std::unique_ptr<MagReader> inner, const MagCorrection& c);

/// OpenImu / OpenMag (core/io/open.h) followed by the calibration in calibration_path, when
/// not empty. Throws InputError when the file has no `imu` (resp. `mag`) section, and
/// OpenImu when it has an `installation` section: the commands that use these (ins, level,
/// allan, inflight-align, transfer-align) have no mounting or clock to apply it to, and
/// dropping it silently would hide that (navigate and smooth read the file themselves).
std::unique_ptr<ImuReader> OpenImu(const std::string& path, const std::string& calibration_path,
                                   double temperature_degC);
std::unique_ptr<MagReader> OpenMag(const std::string& path, const std::string& calibration_path);

}  // namespace navtwin
