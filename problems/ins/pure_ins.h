// Pure (free) inertial navigation over an IMU record: the strapdown mechanization from
// an initial state, the solution written at every IMU epoch (or a chosen interval), and,
// when a reference trajectory is given, its errors.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "core/io/sample_reader.h"
#include "core/strapdown.h"
#include "problems/ins/nav_error.h"

namespace navtwin {

/// The NED mechanization is singular at the poles: the longitude rate v_E / ((R_N + h) cos
/// lat) and the transport rate's tan(lat) term grow without bound (at lat = 90 deg cos lat
/// is 6e-17 and one step swings the velocity by 1e9 m/s). Within 0.01 deg of a pole (1.1
/// km) the first-order position and transport-rate integration is no longer valid at
/// vehicle speeds and IMU rates (300 m/s at 100 Hz turns the longitude by 0.15 deg per
/// step there); closer starts and solutions are refused.
constexpr double kPolarMargin_deg = 0.01;

/// Throws InputError(source, 0, field, ...) naming the time and what is impossible when the
/// state cannot be mechanized: not finite, |lat| >= 90 deg - kPolarMargin_deg, a height or
/// velocity outside the limits of core/io/plausibility.h. `what`: "initial state",
/// "solution" ... (for the message).
void RequireMechanizable(const NavState& s, const std::string& source, const std::string& what);

struct PureInsOptions {
  StrapdownOptions strapdown;
  /// Write the solution every this many seconds (0: at every IMU epoch).
  double output_interval_s = 0.0;
  /// Stop after this time (inf: the end of the IMU record).
  double end_time_s = std::numeric_limits<double>::infinity();
  /// Progress on stderr every this many IMU samples (0: none).
  std::size_t progress_every = 0;
};

struct PureInsResult {
  std::size_t imu_samples = 0;   ///< samples mechanized
  std::size_t skipped_before_start = 0;
  NavState final_state;
  std::optional<NavErrorStats> errors;  ///< when a truth reader was given and overlapped
  double run_time_s = 0.0;
};

/// The initial state from a navigation file: the first record at or after start_s
/// (within 1 us), or the first record when start_s is not given. Throws InputError when
/// the file holds no such record.
NavState InitialStateFromNav(NavReader& nav, std::optional<double> start_s);

/// Runs the mechanization from `initial` over the IMU samples with t_s > initial.t_s.
/// `output` (may be empty) receives the solution at the output epochs. `truth` (may be
/// null) is compared at each of its epochs inside the run, interpolating the solution
/// between IMU epochs. Throws InputError on bad input, and when the solution is not
/// mechanizable (RequireMechanizable, naming the IMU file; the caller checks `initial`
/// naming where it came from).
PureInsResult RunPureIns(ImuReader& imu, const NavState& initial, const PureInsOptions& options,
                         const std::function<void(const NavState&)>& output,
                         NavReader* truth = nullptr);

}  // namespace navtwin
