// A subcommand of the navtwin program: its name, one-line summary, usage, the flags
// it reads (for `navtwin SUB --help` and for rejecting flags that belong elsewhere),
// and the function that runs it. Apps only parse flags, call problems and write output.
#pragma once

#include <string>
#include <vector>

namespace navtwin::app {

struct Command {
  std::string name;
  std::string summary;
  std::string usage;               ///< e.g. "navtwin info FILE [--format=json]"
  std::vector<std::string> flags;  ///< gflags names this command reads
  /// Runs with the positional arguments after the subcommand; returns the exit code.
  int (*run)(const std::vector<std::string>& args) = nullptr;
};

Command InfoCommand();
Command ConvertCommand();
Command InsCommand();
Command SimulateCommand();
Command AllanCommand();
Command NavigateCommand();
Command SmoothCommand();
Command LevelCommand();
Command LevelMcCommand();
Command InflightAlignCommand();
Command InflightMcCommand();
Command TransferAlignCommand();
Command TransferAlignAnsflCommand();
Command CalibrateImuCommand();
Command CalibrateMagCommand();
Command ReportCommand();
Command McCommand();
Command BoundCommand();

/// Exit codes shared by all subcommands.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;  ///< bad input data or a failed computation
constexpr int kExitUsage = 2;    ///< bad command line
constexpr int kExitWarnings = 3; ///< --strict: the outputs were written, but the run reported warnings

}  // namespace navtwin::app
