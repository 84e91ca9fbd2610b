#include "core/io/track_export.h"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <stdexcept>

#include "core/earth.h"
#include "core/gps_time.h"
#include "core/io/csv_series.h"
#include "core/io/input_error.h"
#include "core/text.h"
#include "core/units.h"

namespace navtwin {
namespace {

constexpr double kExportWeek_s = 604800.0;
/// Epochs of a solution and of its std.csv are the same instants written alike.
constexpr double kStdMatch_s = 1e-6;
/// Points of a sigma ellipse's polygon (10 degrees apart).
constexpr int kEllipsePoints = 36;

/// Week and seconds of week with 0 <= sow < 604800 (a reader's t_s may run past the week).
void NormalizeGpsWeek(int* week, double* sow_s) {
  const double extra = std::floor(*sow_s / kExportWeek_s);
  *week += static_cast<int>(extra);
  *sow_s -= extra * kExportWeek_s;
}

void RequirePositiveSigma(const Eigen::Vector3d& std, const char* what, double t_s) {
  if (!(std.array() > 0.0).all() || !std.allFinite()) {
    throw std::invalid_argument(StringPrintf("the %s sigma at t = %.6f s is not positive and finite", what, t_s));
  }
}

}  // namespace

long NavStdSeries::Find(double t) const {
  std::size_t lo = 0, hi = t_s.size();
  while (lo < hi) {  // first row with t_s >= t - kStdMatch_s
    const std::size_t mid = (lo + hi) / 2;
    if (t_s[mid] < t - kStdMatch_s) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return lo < t_s.size() && std::abs(t_s[lo] - t) <= kStdMatch_s ? static_cast<long>(lo) : -1;
}

NavStdSeries ReadNavStdCsv(const std::string& path) {
  NavStdSeries out;
  out.path = path;
  const char* const kColumns[6] = {"pos_n_std", "pos_e_std", "pos_d_std", "vel_n_std", "vel_e_std", "vel_d_std"};
  for (int c = 0; c < 6; ++c) {
    const bool position = c < 3;
    const ScalarSeries s = position ? ReadScalarSeriesCsv(path, kColumns[c], {{"_m", 1.0}}, 0.0)
                                    : ReadScalarSeriesCsv(path, kColumns[c], {{"_mps", 1.0}}, 0.0);
    if (c == 0) {
      out.t_s = s.t_s;
      out.pos_ned_m.assign(s.t_s.size(), Eigen::Vector3d::Zero());
      out.vel_ned_mps.assign(s.t_s.size(), Eigen::Vector3d::Zero());
    }
    for (std::size_t i = 0; i < s.value.size(); ++i) {
      if (!(s.value[i] > 0.0)) {
        // Rows: a header line, then one per sample (ReadScalarSeriesCsv refuses anything else
        // but '#' and blank lines before the header, which this file does not have).
        throw InputError(path, static_cast<long>(i) + 2, std::string(kColumns[c]) + (position ? "_m" : "_mps"),
                         "a standard deviation must be > 0");
      }
      (position ? out.pos_ned_m : out.vel_ned_mps)[i][c % 3] = s.value[i];
    }
  }
  return out;
}

std::string UtcIsoTimeFromGps(int gps_week, double sow_s) {
  if (gps_week < 0 || !std::isfinite(sow_s)) throw std::invalid_argument("UtcIsoTimeFromGps: no GPS week");
  NormalizeGpsWeek(&gps_week, &sow_s);
  double whole_s = std::floor(sow_s);
  long ms = std::lround((sow_s - whole_s) * 1000.0);
  if (ms == 1000) {
    ms = 0;
    whole_s += 1.0;
  }
  const std::int64_t gps_unix_s =
      kGpsEpochUnix_s + static_cast<std::int64_t>(gps_week) * 604800 + static_cast<std::int64_t>(whole_s);
  // GPS - UTC is a function of UTC: once from the GPS instant, once more from the result
  // (they differ only within a leap second's reach of its insertion).
  std::int64_t utc_s = gps_unix_s - GpsMinusUtc_s(gps_unix_s);
  utc_s = gps_unix_s - GpsMinusUtc_s(utc_s);
  const std::time_t t = static_cast<std::time_t>(utc_s);
  std::tm tm{};
  if (gmtime_r(&t, &tm) == nullptr) throw std::invalid_argument("UtcIsoTimeFromGps: time out of range");
  return StringPrintf("%04d-%02d-%02dT%02d:%02d:%02d.%03ldZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday, tm.tm_hour,
                tm.tm_min, tm.tm_sec, ms);
}

// ---------------------------------------------------------------------------------------

RtklibPosWriter::RtklibPosWriter(const std::string& path, const std::string& source) : file_(path) {
  std::ostream& o = file_.stream();
  o << "% program   : navtwin convert\n"
    << "% inp file  : " << source << "\n"
    << "% solution  : inertial navigation (navtwin); Q = 5 for every epoch (RTKLIB has no code for an INS "
       "solution), ns = 0, sdne sdeu sdun sdvne sdveu sdvun = 0 (uncorrelated)\n"
    << "% (lat/lon/height=WGS84/ellipsoidal,Q=1:fix,2:float,3:sbas,4:dgps,5:single,6:ppp,ns=# of satellites)\n"
    << "%  GPST                latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)  sdne(m)"
       "  sdeu(m)  sdun(m) age(s)  ratio  vn(m/s)  ve(m/s)  vu(m/s)     sdvn     sdve     sdvu    sdvne    sdveu"
       "    sdvun\n";
}

void RtklibPosWriter::Write(const NavState& s, const Eigen::Vector3d& pos_std_ned_m,
                            const Eigen::Vector3d& vel_std_ned_mps) {
  if (s.gps_week < 0) {
    throw std::invalid_argument(StringPrintf("the epoch at t = %.6f s has no GPS week: RTKLIB .pos needs GPS time", s.t_s));
  }
  RequirePositiveSigma(pos_std_ned_m, "position", s.t_s);
  RequirePositiveSigma(vel_std_ned_mps, "velocity", s.t_s);
  int week = s.gps_week;
  double sow = s.t_s;
  NormalizeGpsWeek(&week, &sow);
  file_.stream() << StringPrintf(
      "%4d %11.4f %14.9f %14.9f %10.4f %3d %3d %8.4f %8.4f %8.4f %8.4f %8.4f %8.4f %6.2f %6.1f %8.5f %8.5f %8.5f "
      "%8.5f %8.5f %8.5f %8.5f %8.5f %8.5f\n",
      week, sow, s.lat_rad * kRadToDeg, s.lon_rad * kRadToDeg, s.h_m, 5, 0, pos_std_ned_m.x(), pos_std_ned_m.y(),
      pos_std_ned_m.z(), 0.0, 0.0, 0.0, 0.0, 0.0, s.v_n_mps.x(), s.v_n_mps.y(), -s.v_n_mps.z(), vel_std_ned_mps.x(),
      vel_std_ned_mps.y(), vel_std_ned_mps.z(), 0.0, 0.0, 0.0);
}

void RtklibPosWriter::Commit() { file_.Commit(); }

// ---------------------------------------------------------------------------------------

KmlWriter::KmlWriter(const std::string& path, const std::string& name, double ellipse_sigma,
                     double ellipse_interval_s)
    : file_(path),
      name_(name),
      ellipse_sigma_(ellipse_sigma),
      ellipse_interval_s_(ellipse_interval_s),
      last_ellipse_t_s_(-INFINITY) {
  if (!(ellipse_sigma >= 0.0) || !std::isfinite(ellipse_sigma) || !(ellipse_interval_s >= 0.0)) {
    throw std::invalid_argument("KmlWriter: the ellipse sigma and interval must be finite and >= 0");
  }
  std::ostream& o = file_.stream();
  o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    << "<kml xmlns=\"http://www.opengis.net/kml/2.2\">\n<Document>\n<name>" << MarkupEscaped(name) << "</name>\n"
    << "<Style id=\"track\"><LineStyle><color>ff0000ff</color><width>2</width></LineStyle></Style>\n"
    << "<Style id=\"ellipse\"><LineStyle><color>ff00ffff</color><width>1</width></LineStyle>"
       "<PolyStyle><fill>0</fill></PolyStyle></Style>\n";
  if (ellipse_sigma_ > 0.0) {
    o << "<Folder><name>" << StringPrintf("%g", ellipse_sigma_) << "-sigma horizontal position ellipses</name>\n";
  }
}

void KmlWriter::WriteEllipse(const NavState& s, const Eigen::Vector3d& pos_std_ned_m) {
  const double r_n = wgs84::MeridianRadius(s.lat_rad) + s.h_m;
  const double r_e = (wgs84::PrimeVerticalRadius(s.lat_rad) + s.h_m) * std::cos(s.lat_rad);
  std::ostream& o = file_.stream();
  o << "<Placemark><styleUrl>#ellipse</styleUrl><Polygon><altitudeMode>clampToGround</altitudeMode>"
       "<outerBoundaryIs><LinearRing><coordinates>";
  for (int k = 0; k <= kEllipsePoints; ++k) {
    const double a = 2.0 * kPi * static_cast<double>(k % kEllipsePoints) / kEllipsePoints;
    const double dn_m = ellipse_sigma_ * pos_std_ned_m.x() * std::cos(a);
    const double de_m = ellipse_sigma_ * pos_std_ned_m.y() * std::sin(a);
    o << StringPrintf("%.9f,%.9f,0 ", (s.lon_rad + de_m / r_e) * kRadToDeg, (s.lat_rad + dn_m / r_n) * kRadToDeg);
  }
  o << "</coordinates></LinearRing></outerBoundaryIs></Polygon></Placemark>\n";
  ++ellipses_;
}

void KmlWriter::Write(const NavState& s, const Eigen::Vector3d* pos_std_ned_m) {
  track_lon_lat_deg_.emplace_back(s.lon_rad * kRadToDeg, s.lat_rad * kRadToDeg);
  if (ellipse_sigma_ > 0.0 && pos_std_ned_m != nullptr && s.t_s >= last_ellipse_t_s_ + ellipse_interval_s_) {
    WriteEllipse(s, *pos_std_ned_m);
    last_ellipse_t_s_ = s.t_s;
  }
}

void KmlWriter::Commit() {
  std::ostream& o = file_.stream();
  if (ellipse_sigma_ > 0.0) o << "</Folder>\n";
  o << "<Placemark><name>" << MarkupEscaped(name_) << "</name><styleUrl>#track</styleUrl><LineString>"
    << "<tessellate>1</tessellate><altitudeMode>clampToGround</altitudeMode><coordinates>\n";
  for (const Eigen::Vector2d& p : track_lon_lat_deg_) o << StringPrintf("%.9f,%.9f,0\n", p.x(), p.y());
  o << "</coordinates></LineString></Placemark>\n</Document>\n</kml>\n";
  file_.Commit();
}

// ---------------------------------------------------------------------------------------

GpxWriter::GpxWriter(const std::string& path, const std::string& name) : file_(path) {
  file_.stream() << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                 << "<gpx version=\"1.1\" creator=\"navtwin\" xmlns=\"http://www.topografix.com/GPX/1/1\">\n"
                 << "<trk><name>" << MarkupEscaped(name) << "</name><trkseg>\n";
}

void GpxWriter::Write(const NavState& s) {
  std::ostream& o = file_.stream();
  o << StringPrintf("<trkpt lat=\"%.9f\" lon=\"%.9f\"><ele>%.4f</ele>", s.lat_rad * kRadToDeg, s.lon_rad * kRadToDeg,
              s.h_m);
  if (s.gps_week >= 0) o << "<time>" << UtcIsoTimeFromGps(s.gps_week, s.t_s) << "</time>";
  o << "</trkpt>\n";
}

void GpxWriter::Commit() {
  file_.stream() << "</trkseg></trk>\n</gpx>\n";
  file_.Commit();
}

}  // namespace navtwin
