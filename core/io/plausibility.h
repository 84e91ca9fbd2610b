// Plausibility limits of the quantities the readers deliver: values that are finite but
// absurd (1e16 from a deleted byte, 1e308) are refused where they are read, naming file,
// line and field, instead of failing an estimator later with a message that names no
// place. Every limit is generous: no real sensor or vehicle comes near it; it only has to
// catch values that are wrong by orders of magnitude. Checks apply to SI values (after
// the reader's unit scaling) and throw InputError with the value and the limit.
#pragma once

#include <string>

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

/// Each throws InputError(path, line, field, ...) naming the value and the limit when the
/// value is outside its plausible range (or not finite).
void Time(double t_s, const std::string& path, long line, const std::string& field);
void AngularRate(double w_radps, const std::string& path, long line, const std::string& field);
void SpecificForce(double f_mps2, const std::string& path, long line, const std::string& field);
/// Increments over dt_s: |dtheta| <= kMaxAngularRate_radps dt, |dv| <= kMaxSpecificForce_mps2 dt.
void AngleIncrement(double dtheta_rad, double dt_s, const std::string& path, long line, const std::string& field);
void VelocityIncrement(double dv_mps, double dt_s, const std::string& path, long line, const std::string& field);
void Latitude(double lat_rad, const std::string& path, long line, const std::string& field);
void Longitude(double lon_rad, const std::string& path, long line, const std::string& field);
void Height(double h_m, const std::string& path, long line, const std::string& field);
void Velocity(double v_mps, const std::string& path, long line, const std::string& field);
void Sigma(double sigma, const std::string& path, long line, const std::string& field);
void MagneticField(double m_uT, const std::string& path, long line, const std::string& field);
void Pressure(double p_pa, const std::string& path, long line, const std::string& field);

}  // namespace navtwin::plausible
