// The report pages of the alignment commands' run folders (docs/run-folder.md):
//   transfer-align: summary.json, <method>/estimates.csv, <method>/attitude_errors.csv (with a truth)
//   inflight-align: summary.json, <method>/track.csv
//   level-mc: summary.json, errors.csv
//   calibrate-imu: summary.json, parameters.csv, residuals.csv
//   calibrate-mag: summary.json, residuals.csv
// Each builds the page's tables and its figures (scripts, not yet rendered); report.cc
// renders them and writes the page (html.h HtmlPage).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "problems/report/figures.h"
#include "problems/report/html.h"

namespace navtwin::report {

/// A run folder with its summary.json read (run_folder.h ReadSummaryJson).
struct AlignmentFolder {
  std::string dir;
  std::string label;         ///< the folder's name (distinct among the folders)
  std::string summary_path;
  YAML::Node summary;
};

/// The tables and the figures of a page.
struct PageParts {
  PageText text;
  FigureSet figures;
};

/// The text frame of an alignment page: the title "navtwin report (<what>): <folders>", the
/// intro paragraph (HTML), one "Summary tables" section whose body starts with its heading
/// followed by `tables` (HTML).
PageText AlignmentPageText(const std::vector<AlignmentFolder>& folders, const std::string& what,
                           const std::string& intro, const std::string& tables);

/// transfer-align folders: per method the attitude errors and the final estimates (tables),
/// the misalignment and the delay against time with ±3σ bands and the true values, the
/// slave's attitude errors; with three or more folders of distinct true delays (a sweep) the
/// attitude RMS of each method against the true delay. Throws InputError (file, line, field)
/// for a method without estimates.csv or a malformed file. Series are labelled
/// folder/method with several folders.
PageParts TransferPage(const std::vector<AlignmentFolder>& folders, std::size_t max_points);

/// inflight-align folders: per method the heading error and σ at the distances and at the
/// end (tables), the heading error against the distance flown with ±3σ bands, σ against
/// distance. Throws InputError for a method without track.csv or a malformed file.
PageParts InflightPage(const std::vector<AlignmentFolder>& folders, std::size_t max_points);

/// level-mc folders: per method the errors' RMS and max, mean σ and err/σ (table), the
/// histograms of the pitch and roll errors over the runs. Throws InputError for a folder
/// without errors.csv, a method's column missing, or a malformed row.
PageParts LevelingPage(const std::vector<AlignmentFolder>& folders, std::size_t max_points);

/// calibrate-imu or calibrate-mag folders (all of one kind): the fit and the parameters with σ
/// (tables, one column per folder), the residuals before and after calibration (IMU: per
/// static position, log scale; magnetometer: the field magnitude against time). Throws
/// InputError for a missing or malformed file.
PageParts CalibrationPage(const std::vector<AlignmentFolder>& folders, std::size_t max_points);

}  // namespace navtwin::report
