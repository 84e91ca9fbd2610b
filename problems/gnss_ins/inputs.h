// The input records of a GNSS/INS run, loaded and checked once. The IMU record is held in
// memory (the batch needs it whole) or streamed from its file (the filter and the
// densification read it in passes: memory independent of the record's length); its
// samples are in the body FRD axes (mounting applied) on the GNSS time scale (time offset
// applied), with dt_s from the time tags and short gaps bridged.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "core/types.h"
#include "core/io/csv_odometer.h"
#include "problems/ins/imu_record.h"
#include "problems/gnss_ins/config.h"

namespace navtwin::gnss_ins {

struct InputPaths {
  std::string imu, gnss, mag, baro;  ///< mag and baro may be empty
  /// Calibration file (core/calibration_file.h) or empty: its imu section is applied to the
  /// IMU (in the IMU's own axes, before the mounting), its mag section to the magnetometer,
  /// its installation section (mounting, time offset) in place of the configuration's
  /// installation.imu_mounting_deg and imu_time_offset_s, which must then be zero; it must
  /// hold at least one section for the files read.
  std::string calibration;
  double imu_temperature_degC = NAN;  ///< NaN: the calibration's reference temperature
};

struct Inputs {
  InputPaths paths;
  /// The installation applied to the IMU: the configuration's, with the mounting and time
  /// offset of the calibration file's installation section when it has one.
  Installation installation;
  bool installation_from_calibration = false;  ///< the calibration file set the mounting and time offset
  ins::ImuRecord imu;             ///< body axes, strictly increasing t_s, dt_s > 0
  std::vector<GnssSample> gnss;   ///< strictly increasing; injected outages removed
  std::vector<MagSample> mag;     ///< raw (calibration is applied by the models' users)
  std::vector<BaroSample> baro;   ///< with altitude_m
  /// Wheel-odometer speeds (config.odometer: its file, or the IMU file's column).
  std::vector<OdometerSample> odometer;
  std::string odometer_file;  ///< the file `odometer` came from
  std::size_t gnss_removed_by_outages = 0;
  /// The GNSS epochs the injected outages removed (gnss_removed_by_outages of them), increasing.
  std::vector<GnssSample> gnss_removed;
  /// The injected outage intervals [start, end) in time (empty without outages).
  std::vector<std::pair<double, double>> outages;
};

enum class ImuStorage {
  kInMemory,  ///< every IMU sample read now and kept
  kStreamed,  ///< the IMU file read on each pass; until a pass has reached its end, the
              ///< other records run on past the IMU's last sample (CutToImuEnd)
};

/// Reads every file (any format core/io/open.h detects), applies the installation, cuts
/// to [start_time_s, end_time_s], injects the outages (up to the last GNSS epoch: an
/// interval after it would remove nothing) and checks: non-positive sigma, GNSS epochs
/// out of order or duplicated, NaN, IMU gaps (bridged up to
/// FilterConfig::max_bridge_gap_s by splitting the following sample's increments over the
/// gap, ins/imu_gaps.h; longer ones are an InputError naming the file and time), no GNSS
/// inside the IMU span. Throws InputError (file, line, field); a streamed IMU record
/// throws it from the pass that reads the bad sample.
Inputs LoadInputs(const InputPaths& paths, const GnssInsConfig& config,
                  ImuStorage storage = ImuStorage::kInMemory);

/// Drops what lies after the IMU record's last sample (GNSS epochs, the epochs the outages
/// removed, outages, magnetometer, barometer and odometer samples) and checks that GNSS
/// epochs and odometer samples remain (InputError). Needs in->imu.end_known(): LoadInputs
/// calls it for a record in memory; call it after the first pass over a streamed one.
void CutToImuEnd(Inputs* in);

}  // namespace navtwin::gnss_ins
