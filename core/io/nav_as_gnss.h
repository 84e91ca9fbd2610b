// A navigation solution used as GNSS fixes: one fix per record of a reference trajectory
// (e.g. the DJI flight controller's RTK/INS solution of the ANSFL data, or any navigation
// file `navtwin info` knows), with a standard deviation the caller states, since a
// navigation file carries none. `navtwin convert --what gnss` writes it as a KF-GINS GNSS
// file (13 columns: position and velocity with their sigmas).
#pragma once

#include <memory>

#include "core/io/sample_reader.h"

namespace navtwin {

struct NavAsGnssOptions {
  double pos_sigma_m = 0.0;    ///< per axis (N, E, D); must be > 0 and finite
  double vel_sigma_mps = 0.0;  ///< per axis; must be > 0 and finite
};

/// Wraps `nav`: each NavState becomes a GnssSample with the same time, week, position
/// (the navigation file's height, whatever its datum) and velocity, sigma from `options`,
/// quality 0 and satellites 0 (unknown). Throws std::invalid_argument for a sigma that is
/// not > 0 and finite (the GNSS readers and writers refuse it; the caller names the flag).
std::unique_ptr<GnssReader> NavAsGnssReader(std::unique_ptr<NavReader> nav, const NavAsGnssOptions& options);

}  // namespace navtwin
