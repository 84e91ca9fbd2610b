// Leveling on recorded files: one window of specific force (and angular rate) read from
// any IMU file OpenImu knows, ULog included. CheckWindow (declared in leveling.h) is
// implemented beside it in window.cc. docs/leveling.md describes the checks.
#pragma once

#include <cmath>
#include <string>

#include "problems/leveling/leveling.h"

namespace navtwin::leveling {

/// Reads the IMU samples whose time lies in [t0 + start_s, t0 + start_s + window_s),
/// t0 = the time of the file's first IMU sample: f = dv/dt, omega = dtheta/dt,
/// t = the sample time (end of its increment interval); rate_hz = 1 / the median sample
/// interval of the window; source = path.
/// Throws std::invalid_argument for a negative or non-finite start_s or a non-positive
/// window_s, and InputError (file, field "t_s") when the window goes beyond the end of
/// the record (the message gives the record length) or holds fewer than 8 samples;
/// the readers' own InputErrors pass through. A non-empty calibration_path applies that
/// calibration file's imu section at temperature_degC (core/calibration_file.h; NaN: the
/// file's reference temperature).
AccelWindow ReadAccelWindow(const std::string& path, double start_s, double window_s,
                            const std::string& calibration_path = "", double temperature_degC = NAN);

/// The fewest samples a window may hold (the autocorrelation needs some lags).
constexpr int kMinWindowSamples = 8;

}  // namespace navtwin::leveling
