// Flags that several subcommands read, defined once (common_flags.cc) with one help text
// that fits every subcommand using them. A flag that only one subcommand reads is defined
// in that subcommand's file. Each subcommand lists the flags it reads in Command::flags.
#pragma once

#include <gflags/gflags.h>

#include <string>

// Output and run control.
DECLARE_string(format);
DECLARE_string(out);
DECLARE_string(run_dir);
DECLARE_uint64(seed);
DECLARE_int32(runs);
DECLARE_int32(threads);
DECLARE_string(errors_csv);
DECLARE_string(method);
DECLARE_bool(demo);
DECLARE_bool(report);

// Inputs.
DECLARE_string(imu);
DECLARE_string(gnss);
DECLARE_string(mag);
DECLARE_string(baro);
DECLARE_string(truth);
DECLARE_string(init_from);
DECLARE_string(data);
DECLARE_string(config);
DECLARE_string(scenario);
DECLARE_string(calibration);
DECLARE_double(imu_temperature_degC);

// Time span and output rate.
DECLARE_double(start_s);
DECLARE_double(end_s);
DECLARE_double(output_rate_hz);
DECLARE_double(std_rate_hz);

// Leveling (level, level-mc).
DECLARE_double(window_s);
DECLARE_double(noise_mg);
DECLARE_string(vib_axes);
DECLARE_int32(vib_tones);

namespace navtwin::app {

/// Whether a flag was given on the command line (also when given its default value, so
/// that it overrides a configuration file), or otherwise differs from its default.
/// Unset flags with a NaN default count as not given (compared as text: NaN != NaN).
bool FlagGiven(const char* name);

/// --report: DIR/report.html from the run folder `dir` just written (navtwin report DIR),
/// with the progress and the outcome on stderr prefixed by `command`.
void WriteRunReport(const std::string& command, const std::string& dir);

}  // namespace navtwin::app
