#include "core/io/plausibility.h"

#include <cmath>
#include <sstream>

#include "core/io/input_error.h"

namespace navtwin::plausible {
namespace {

/// Throws unless lo <= value <= hi.
void Within(double value, double lo, double hi, const char* quantity, const char* unit, const std::string& path,
            long line, const std::string& field) {
  if (value >= lo && value <= hi) return;
  std::ostringstream os;
  os << "implausible " << quantity << " " << value << " " << unit << ": outside the plausibility limits [" << lo
     << ", " << hi << "] " << unit << " (core/io/plausibility.h)";
  throw InputError(path, line, field, os.str());
}

}  // namespace

void Time(double t_s, const std::string& path, long line, const std::string& field) {
  Within(t_s, -kMaxAbsTime_s, kMaxAbsTime_s, "time", "s", path, line, field);
}
void AngularRate(double w_radps, const std::string& path, long line, const std::string& field) {
  Within(w_radps, -kMaxAngularRate_radps, kMaxAngularRate_radps, "angular rate", "rad/s", path, line, field);
}
void SpecificForce(double f_mps2, const std::string& path, long line, const std::string& field) {
  Within(f_mps2, -kMaxSpecificForce_mps2, kMaxSpecificForce_mps2, "specific force", "m/s^2", path, line, field);
}
void AngleIncrement(double dtheta_rad, double dt_s, const std::string& path, long line, const std::string& field) {
  const double limit = kMaxAngularRate_radps * std::abs(dt_s);
  Within(dtheta_rad, -limit, limit, "angle increment", "rad", path, line, field);
}
void VelocityIncrement(double dv_mps, double dt_s, const std::string& path, long line, const std::string& field) {
  const double limit = kMaxSpecificForce_mps2 * std::abs(dt_s);
  Within(dv_mps, -limit, limit, "velocity increment", "m/s", path, line, field);
}
void Latitude(double lat_rad, const std::string& path, long line, const std::string& field) {
  Within(lat_rad * kRadToDeg, -90.0, 90.0, "latitude", "deg", path, line, field);
}
void Longitude(double lon_rad, const std::string& path, long line, const std::string& field) {
  Within(lon_rad * kRadToDeg, -360.0, 360.0, "longitude", "deg", path, line, field);
}
void Height(double h_m, const std::string& path, long line, const std::string& field) {
  Within(h_m, kMinHeight_m, kMaxHeight_m, "height", "m", path, line, field);
}
void Velocity(double v_mps, const std::string& path, long line, const std::string& field) {
  Within(v_mps, -kMaxSpeed_mps, kMaxSpeed_mps, "velocity", "m/s", path, line, field);
}
void Sigma(double sigma, const std::string& path, long line, const std::string& field) {
  Within(sigma, kMinSigma, kMaxSigma, "standard deviation", "(SI units)", path, line, field);
}
void MagneticField(double m_uT, const std::string& path, long line, const std::string& field) {
  Within(m_uT, -kMaxMagneticField_uT, kMaxMagneticField_uT, "magnetic field", "uT", path, line, field);
}
void Pressure(double p_pa, const std::string& path, long line, const std::string& field) {
  Within(p_pa, 0.0, kMaxPressure_pa, "pressure", "Pa", path, line, field);
}

}  // namespace navtwin::plausible
