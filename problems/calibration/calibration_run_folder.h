// The run folders of the calibration commands (docs/run-folder.md), which `navtwin report`
// draws (problems/report/calibration_page.cc):
//   calibrate-imu --run_dir DIR: summary.json, calibration.yaml, parameters.csv, residuals.csv
//   calibrate-mag --run_dir DIR: summary.json, calibration.yaml, residuals.csv
// The CSV writers are imu_calibration.h WriteImuParametersCsv / WriteImuResidualsCsv and
// mag_calibration.h WriteMagResidualsCsv.
#pragma once

#include <functional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "core/calibration_file.h"

namespace navtwin::calibration {

/// A file of the folder: its name and what writes its content.
using RunFolderFile = std::pair<std::string, std::function<void(std::ostream&)>>;

/// Writes DIR (created if missing): summary_json as summary.json, `file` as calibration.yaml
/// and each of `files`. All or nothing: each file goes to a temporary first and is renamed
/// when every one has been written; on failure the renamed ones are removed again and
/// std::runtime_error is thrown.
void WriteCalibrationRunFolder(const std::string& dir, const std::string& summary_json, const CalibrationFile& file,
                               const std::vector<RunFolderFile>& files);

}  // namespace navtwin::calibration
