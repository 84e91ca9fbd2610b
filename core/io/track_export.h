// Navigation solutions written for other people's tools (docs/formats.md "Exports"):
//   - RTKLIB .pos (week / seconds-of-week GPST time, lat/lon/height, Q, ns, sdn sde sdu,
//     velocity and its sigmas), so rtkplot overlays navtwin with RTKLIB and navtwin reads it
//     back (core/io/rtklib_pos.h);
//   - KML 2.2 for Google Earth: the track as a LineString and, optionally, the horizontal
//     K-sigma ellipse of the position every `ellipse_interval_s` as polygons;
//   - GPX 1.1: one track segment, the time of each point in UTC (GPS time minus the leap
//     seconds of core/gps_time.h).
// Heights are written as the solution's (WGS84 ellipsoid); KML and GPX readers take them as
// above mean sea level, which differs by the geoid undulation (tens of metres), so the KML
// is clamped to the ground and the GPX <ele> is documented as ellipsoidal.
// Each writer writes "<path>.tmp.<pid>" and renames it on Commit (AtomicFile): a failed
// conversion leaves nothing.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/io/atomic_file.h"
#include "core/types.h"

namespace navtwin {

/// The sigmas of a solution's epochs (a run's std.csv: t_s, pos_{n,e,d}_std_m,
/// vel_{n,e,d}_std_mps; other columns ignored).
struct NavStdSeries {
  std::string path;
  std::vector<double> t_s;
  std::vector<Eigen::Vector3d> pos_ned_m;
  std::vector<Eigen::Vector3d> vel_ned_mps;
  /// The row at time t (within 1e-6 s), or -1.
  long Find(double t_s) const;
};

/// Reads a std.csv; InputError naming file, line and field for a missing column, a bad,
/// non-finite or non-positive sigma, time not increasing, an empty file.
NavStdSeries ReadNavStdCsv(const std::string& path);

/// UTC calendar time of a GPS week and seconds of week, as ISO 8601 with milliseconds and
/// a 'Z' ("2023-08-27T17:30:41.250Z"). week >= 0.
std::string UtcIsoTimeFromGps(int gps_week, double sow_s);

class RtklibPosWriter {
 public:
  /// `source`: named in the header (the input file).
  RtklibPosWriter(const std::string& path, const std::string& source);
  /// Throws std::invalid_argument for a state without a GPS week or a non-positive sigma.
  void Write(const NavState& s, const Eigen::Vector3d& pos_std_ned_m, const Eigen::Vector3d& vel_std_ned_mps);
  void Commit();

 private:
  AtomicFile file_;
};

class KmlWriter {
 public:
  /// ellipse_sigma: K of the K-sigma ellipses (0: no ellipses); ellipse_interval_s: one
  /// ellipse at the first epoch and then at least this far apart.
  KmlWriter(const std::string& path, const std::string& name, double ellipse_sigma, double ellipse_interval_s);
  /// pos_std_ned_m: null when the epoch has no sigma (no ellipse there).
  void Write(const NavState& s, const Eigen::Vector3d* pos_std_ned_m);
  /// Writes the document (the track after the ellipses) and renames it into place.
  void Commit();
  std::size_t ellipses() const { return ellipses_; }

 private:
  void WriteEllipse(const NavState& s, const Eigen::Vector3d& pos_std_ned_m);

  AtomicFile file_;
  std::string name_;
  double ellipse_sigma_, ellipse_interval_s_;
  double last_ellipse_t_s_;
  std::size_t ellipses_ = 0;
  std::vector<Eigen::Vector2d> track_lon_lat_deg_;
};

class GpxWriter {
 public:
  GpxWriter(const std::string& path, const std::string& name);
  /// A state without a GPS week gets no <time>.
  void Write(const NavState& s);
  void Commit();

 private:
  AtomicFile file_;
};

}  // namespace navtwin
