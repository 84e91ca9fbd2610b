// Plausibility limits of the quantities the readers deliver: values that are finite but
// absurd (1e16 from a deleted byte, 1e308) are refused where they are read, naming file,
// line and field, instead of failing an estimator later with a message that names no
// place. Every limit is generous: no real sensor or vehicle comes near it; it only has to
// catch values that are wrong by orders of magnitude. Checks apply to SI values (after
// the reader's unit scaling) and throw InputError with the value and the limit.
#pragma once

#include <cmath>
#include <string>
#include <string_view>

#include "core/units.h"

namespace navtwin::plausible {

/// Time tags: seconds of week (< 6.1e5), since power-on, since the GPS epoch (1.4e9 s in
/// 2026) or the Unix epoch (1.8e9 s), or relative to a chosen origin (may be negative).
/// 1e10 s (317 years) exceeds every one of them.
constexpr double kMaxAbsTime_s = 1e10;
/// Angular rate: tactical and MEMS gyros have full scales of 300 ... 4000 deg/s; 1e4 deg/s
/// (28 rev/s) is beyond any of them.
constexpr double kMaxAngularRate_radps = 1e4 * kDegPerSecond_radps;
/// Increments are checked against the interval from the previous time tag; a file's first
/// sample has none (its interval is taken from the next one), so its increments are checked
/// against 1 s: IMU records sample at 1 Hz or faster.
constexpr double kFirstIncrementInterval_s = 1.0;
/// Specific force: MEMS accelerometers reach 16 ... 400 g (shock sensors); 1e4 m/s^2
/// (about 1000 g) is beyond them.
constexpr double kMaxSpecificForce_mps2 = 1e4;
/// Velocity components: 1e5 m/s is more than ten times the orbital speed.
constexpr double kMaxSpeed_mps = 1e5;
/// Ellipsoidal height: the deepest ocean trench is 11 km below the geoid, whose undulation
/// is at least -107 m, so -12 km is below any surface or submarine position; 1e7 m is above
/// aircraft, balloons and low orbits (GNSS satellites at 2e7 m are not navigated here).
constexpr double kMinHeight_m = -12e3;
constexpr double kMaxHeight_m = 1e7;
/// Longitude: +-180 deg, or 0 ... 360 deg in some formats.
constexpr double kMaxAbsLongitude_rad = 2.0 * kPi;
/// Standard deviations (m, m/s, rad ...): below 1e-12 a sigma would give weights of 1e24
/// and more; above 1e7 it says the value is unknown (the Earth's radius is 6.4e6 m).
constexpr double kMinSigma = 1e-12;
constexpr double kMaxSigma = 1e7;
/// Magnetic field: the Earth's is at most 67 uT; magnetometer full scales reach 1600 uT
/// (16 G); 1e4 uT (1 T / 100) is beyond them.
constexpr double kMaxMagneticField_uT = 1e4;
/// Static pressure: barometers measure 300 ... 1260 hPa; 1e7 Pa (100 bar) is beyond any
/// altitude sensor.
constexpr double kMaxPressure_pa = 1e7;

/// Throws InputError(path, line, field) naming the value, its quantity and the limits.
[[noreturn]] void Refuse(double value, double lo, double hi, const char* quantity, const char* unit,
                         const std::string& path, long line, std::string_view field);

/// Throws (Refuse) unless lo <= value <= hi (NaN included). Inline: the readers call it for
/// every number of every row, and only a refusal builds a message.
inline void Within(double value, double lo, double hi, const char* quantity, const char* unit,
                   const std::string& path, long line, std::string_view field) {
  if (value >= lo && value <= hi) return;
  Refuse(value, lo, hi, quantity, unit, path, line, field);
}

/// Each throws InputError(path, line, field, ...) naming the value and the limit when the
/// value is outside its plausible range (or not finite).
inline void Time(double t_s, const std::string& path, long line, std::string_view field) {
  Within(t_s, -kMaxAbsTime_s, kMaxAbsTime_s, "time", "s", path, line, field);
}
inline void AngularRate(double w_radps, const std::string& path, long line, std::string_view field) {
  Within(w_radps, -kMaxAngularRate_radps, kMaxAngularRate_radps, "angular rate", "rad/s", path, line, field);
}
inline void SpecificForce(double f_mps2, const std::string& path, long line, std::string_view field) {
  Within(f_mps2, -kMaxSpecificForce_mps2, kMaxSpecificForce_mps2, "specific force", "m/s^2", path, line, field);
}
/// Increments over dt_s: |dtheta| <= kMaxAngularRate_radps dt, |dv| <= kMaxSpecificForce_mps2 dt.
inline void AngleIncrement(double dtheta_rad, double dt_s, const std::string& path, long line, std::string_view field) {
  const double limit = kMaxAngularRate_radps * std::abs(dt_s);
  Within(dtheta_rad, -limit, limit, "angle increment", "rad", path, line, field);
}
inline void VelocityIncrement(double dv_mps, double dt_s, const std::string& path, long line, std::string_view field) {
  const double limit = kMaxSpecificForce_mps2 * std::abs(dt_s);
  Within(dv_mps, -limit, limit, "velocity increment", "m/s", path, line, field);
}
inline void Latitude(double lat_rad, const std::string& path, long line, std::string_view field) {
  Within(lat_rad * kRadToDeg, -90.0, 90.0, "latitude", "deg", path, line, field);
}
inline void Longitude(double lon_rad, const std::string& path, long line, std::string_view field) {
  Within(lon_rad * kRadToDeg, -360.0, 360.0, "longitude", "deg", path, line, field);
}
inline void Height(double h_m, const std::string& path, long line, std::string_view field) {
  Within(h_m, kMinHeight_m, kMaxHeight_m, "height", "m", path, line, field);
}
inline void Velocity(double v_mps, const std::string& path, long line, std::string_view field) {
  Within(v_mps, -kMaxSpeed_mps, kMaxSpeed_mps, "velocity", "m/s", path, line, field);
}
inline void Sigma(double sigma, const std::string& path, long line, std::string_view field) {
  Within(sigma, kMinSigma, kMaxSigma, "standard deviation", "(SI units)", path, line, field);
}
inline void MagneticField(double m_uT, const std::string& path, long line, std::string_view field) {
  Within(m_uT, -kMaxMagneticField_uT, kMaxMagneticField_uT, "magnetic field", "uT", path, line, field);
}
inline void Pressure(double p_pa, const std::string& path, long line, std::string_view field) {
  Within(p_pa, 0.0, kMaxPressure_pa, "pressure", "Pa", path, line, field);
}

}  // namespace navtwin::plausible
