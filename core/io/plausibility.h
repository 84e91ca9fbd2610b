// Plausibility limits: values that are finite but absurd. Every limit is generous: no real
// sensor or vehicle comes near it; it only has to catch values that are wrong by orders of
// magnitude.
#pragma once

#include "core/units.h"

namespace navtwin::plausible {

/// Velocity components: 1e5 m/s is more than ten times the orbital speed.
constexpr double kMaxSpeed_mps = 1e5;
/// Ellipsoidal height: the deepest ocean trench is 11 km below the geoid, whose undulation
/// is at least -107 m, so -12 km is below any surface or submarine position; 1e7 m is above
/// aircraft, balloons and low orbits (GNSS satellites at 2e7 m are not navigated here).
constexpr double kMinHeight_m = -12e3;
constexpr double kMaxHeight_m = 1e7;

}  // namespace navtwin::plausible
