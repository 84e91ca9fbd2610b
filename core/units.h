// Unit constants: the only place where a people unit (deg, deg/h, mg, ug, ppm, arcmin,
// mrad, ...) is related to SI. Code keeps SI inside (rad, rad/s, m/s, m/s^2, s, uT) and
// uses these constants only where a file or a configuration is read or a result printed.
//
// Naming: k<Unit>_<si suffix> is one <Unit> expressed in SI (kMicroG_mps2 = 1 ug in
// m/s^2), so reading is `value * kMicroG_mps2` and printing `value_mps2 / kMicroG_mps2`.
//
// References:
//  [1] BIPM, "The International System of Units (SI)", 9th ed., 2019, table 8
//      (non-SI units accepted for use with the SI: degree, minute and second of arc, hour).
//  [2] 3rd CGPM (1901), declaration on the unit of mass and the definition of weight:
//      standard acceleration of gravity g_n = 9.80665 m/s^2 (exact by definition).
//  [3] IEEE Std 952-1997, "IEEE Standard Specification Format Guide and Test Procedure for
//      Single-Axis Interferometric Fiber Optic Gyros", annex C: angle random walk in
//      deg/sqrt(h) and bias instability in deg/h.
#pragma once

namespace navtwin {

// ---- angles [1]
constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;
constexpr double kDegToRad = kPi / 180.0;
constexpr double kRadToDeg = 180.0 / kPi;
constexpr double kArcmin_rad = kDegToRad / 60.0;
constexpr double kArcsec_rad = kDegToRad / 3600.0;
constexpr double kMrad_rad = 1e-3;
constexpr double kMicrorad_rad = 1e-6;

// ---- time [1]
constexpr double kMicrosecond_s = 1e-6;
constexpr double kMillisecond_s = 1e-3;
constexpr double kMinute_s = 60.0;
constexpr double kHour_s = 3600.0;
constexpr double kSqrtHour_sqrts = 60.0;  ///< sqrt(1 h) = 60 sqrt(s)
constexpr double kSecondsPerDay = 86400.0;
constexpr double kSecondsPerWeek = 604800.0;  ///< GNSS week

// ---- gyro and accelerometer specification units [3]
constexpr double kDegPerSecond_radps = kDegToRad;
constexpr double kDegPerHour_radps = kDegToRad / kHour_s;
constexpr double kDegPerSqrtHour_radpsqrts = kDegToRad / kSqrtHour_sqrts;  ///< ARW, rad/sqrt(s)
constexpr double kMpsPerSqrtHour_mpspsqrts = 1.0 / kSqrtHour_sqrts;        ///< VRW, m/s/sqrt(s)
constexpr double kPpm = 1e-6;  ///< parts per million (scale factors), dimensionless

// ---- acceleration
constexpr double kStandardGravity_mps2 = 9.80665;  ///< g_n, exact [2]; the "g" of g, mg, ug
constexpr double kMilliG_mps2 = 1e-3 * kStandardGravity_mps2;
constexpr double kMicroG_mps2 = 1e-6 * kStandardGravity_mps2;
constexpr double kGal_mps2 = 1e-2;       ///< 1 Gal = 1 cm/s^2
constexpr double kMilliGal_mps2 = 1e-5;  ///< gravity anomalies

// ---- magnetic flux density (inside: uT)
constexpr double kGauss_uT = 100.0;
constexpr double kNanotesla_uT = 1e-3;

// ---- temperature
constexpr double kAbsoluteZero_degC = -273.15;

}  // namespace navtwin
