// A run folder as the report reads it (docs/gnss-ins.md "Outputs", docs/report.md):
//   summary.json               required
//   gnss.csv                   t_s,lat_deg,lon_deg,h_m,pos_n_std_m,pos_e_std_m,pos_d_std_m,in_outage
//   <method>/nav.csv           t_s,lat_deg,lon_deg,h_m,vn_mps,ve_mps,vd_mps,roll_deg,pitch_deg,yaw_deg
//   <method>/std.csv           t_s,pos_n_std_m,...,att_d_std_deg,... (output.h)
//   <method>/errors.csv        t_s,<9 errors>,<9 sigmas>,in_outage[,<6 reference sigmas>] (output.h)
//   <method>/residuals.csv     t_s,sensor,dof,chi2,rejected
// The top-level nav.csv and std.csv belong to summary.json's output_method; they stand in
// for that method's own files when the folder has none. Every file but summary.json may be
// missing: the figure that needs it is left out, with the reason in `notes`.
// The loaders keep the full-rate numbers only while computing what the report shows (the
// scores over every row, the thinned series for the figures), one file at a time.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace navtwin::report {

struct Outage {
  double start_s = 0.0;
  double end_s = 0.0;
};

/// A thinned time series: times and one or more value columns of the same length.
struct Series {
  std::vector<double> t;
  std::vector<std::vector<double>> y;
};

/// The χ² consistency of one set of values with known dof: how many, how many outside the
/// two-sided 95 % bounds.
struct BoundsCount {
  std::size_t values = 0;
  std::size_t below = 0;
  std::size_t above = 0;
};

/// One sensor's updates in residuals.csv for one method.
struct NisSeries {
  std::string sensor;
  Series accepted;           ///< y[0] = chi2 (NIS or whitened-residual square sum), y[1] = dof
  Series rejected;           ///< y[0] = chi2 of the rejected updates
  BoundsCount counts;        ///< accepted updates against their dof's bounds
  std::size_t rejected_count = 0;
  std::vector<int> dofs;     ///< distinct dof values, increasing
};

/// The nine scored components (scoring.h order): position N/E/D (m), velocity N/E/D (m/s),
/// roll/pitch/yaw (deg).
constexpr int kComponents = 9;

struct MethodData {
  std::string method;        ///< e.g. "filter"
  std::string label;         ///< "method", or "folder/method" with several folders
  Series track;              ///< nav.csv thinned: y[0] lat_deg, y[1] lon_deg
  Series sigma;              ///< std.csv thinned: y = pos horizontal, pos down (m), vel horizontal,
                             ///< vel down (m/s), tilt, heading (deg)
  bool has_errors = false;
  std::array<Series, kComponents> errors;  ///< y[0] error, y[1] sigma (with the reference's)
  std::array<bool, kComponents> compared{};  ///< some finite error in the component
  Series nees;               ///< y[0] position NEES (diagonal sigmas)
  BoundsCount nees_counts;   ///< against the χ²(3) 95 % bounds
  std::vector<double> outage_max_horizontal_m;  ///< per outage of the folder, NaN without epochs
  std::vector<NisSeries> nis;
};

struct RunData {
  std::string dir;
  std::string label;         ///< the folder's name
  std::string summary_path;
  YAML::Node summary;
  std::string output_method;
  std::vector<Outage> outages;
  double t_start_s = 0.0;    ///< inputs.t_start_s (else the first time found)
  Series gnss;               ///< gnss.csv thinned: y[0] lat_deg, y[1] lon_deg, y[2] in_outage
  bool has_gnss = false;
  std::vector<MethodData> methods;
  std::vector<std::string> notes;  ///< files not found and what is left out for want of them
};

/// Reads a run folder. `label_methods`: label series "folder/method". Throws InputError
/// (file, line, field) for a folder without summary.json, malformed JSON or CSV.
/// `jobs` methods are read at once.
RunData LoadRunFolder(const std::string& dir, const std::string& label, bool label_methods,
                      std::size_t max_points, int jobs);

/// summary.json of the folder `dir` (at `path`): an object with a non-empty "methods"
/// object (but for the calibration commands' folders, which have none). Throws InputError (file, line, field) when it is missing or malformed.
YAML::Node ReadSummaryJson(const std::string& dir, const std::string& path);

/// A number of summary.json: NaN for null or absent; InputError naming the file, line and
/// key for anything else that is not a number.
double JsonNumber(const YAML::Node& node, const std::string& path, const std::string& key);

/// node[key] when node is an object holding key, else a null node (never yaml-cpp's invalid
/// node, which throws when indexed further): summary.json's optional keys nest.
YAML::Node JsonChild(const YAML::Node& node, const std::string& key);

/// The two-sided 95 % bounds of χ² with `dof` degrees of freedom: {2.5 %, 97.5 %} quantiles.
std::array<double, 2> ChiSquareBounds95(int dof);

}  // namespace navtwin::report
