// navtwin: the command-line front end. `navtwin SUB [flags] [args]`; `navtwin --help`
// lists the subcommands, `navtwin SUB --help` the flags of one.
#include <gflags/gflags.h>
#include <glog/logging.h>

#include <algorithm>
#include <cstring>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "core/io/input_error.h"

DEFINE_string(format, "text", "Output format of printed results: text or json");

namespace navtwin::app {

// cmd_inflight.cc (declared here rather than in command.h, which another change owns).
Command InflightAlignCommand();
Command InflightMcCommand();
// cmd_transfer.cc
Command TransferAlignCommand();
Command TransferAlignAnsflCommand();  // cmd_transfer_ansfl.cc
Command CalibrateMagCommand();        // cmd_calibrate_mag.cc
Command CalibrateImuCommand();        // cmd_calibrate_imu.cc

namespace {

std::vector<Command> AllCommands() {
  return {InfoCommand(),          ConvertCommand(),       InsCommand(),
          SimulateCommand(),      AllanCommand(),         NavigateCommand(),
          SmoothCommand(),        LevelCommand(),         LevelMcCommand(),
          InflightAlignCommand(), InflightMcCommand(),    TransferAlignCommand(),
          TransferAlignAnsflCommand(), CalibrateImuCommand(), CalibrateMagCommand()};
}

void PrintMainHelp(const std::vector<Command>& commands) {
  std::cout << "navtwin — inertial-navigation estimation: filters and their batch twins\n\n"
               "usage: navtwin SUBCOMMAND [flags] [args]\n\nsubcommands:\n";
  for (const Command& c : commands) {
    std::cout << "  " << c.name << std::string(c.name.size() < 12 ? 12 - c.name.size() : 1, ' ')
              << c.summary << "\n";
  }
  std::cout << "\n`navtwin SUBCOMMAND --help` lists the flags of one subcommand.\n";
}

void PrintCommandHelp(const Command& c) {
  std::cout << c.summary << "\n\nusage: " << c.usage << "\n\nflags:\n";
  std::vector<std::string> flags = c.flags;
  flags.push_back("format");
  for (const std::string& name : flags) {
    gflags::CommandLineFlagInfo info;
    if (!gflags::GetCommandLineFlagInfo(name.c_str(), &info)) continue;
    std::cout << "  --" << info.name << " (" << info.type << ", default \"" << info.default_value
              << "\")\n      " << info.description << "\n";
  }
}

/// Flags set on the command line that the chosen subcommand does not read.
std::vector<std::string> ForeignFlags(const Command& c) {
  std::vector<gflags::CommandLineFlagInfo> all;
  gflags::GetAllFlags(&all);
  std::vector<std::string> foreign;
  for (const auto& f : all) {
    // Compared as text: is_default is false for a NaN default (NaN != NaN).
    if (f.current_value == f.default_value || f.name == "format") continue;
    const bool ours = std::find(c.flags.begin(), c.flags.end(), f.name) != c.flags.end();
    // Only the flags defined by this program are policed (not glog's own).
    if (!ours && f.filename.find("apps/navtwin/") != std::string::npos) foreign.push_back(f.name);
  }
  return foreign;
}

int Main(int argc, char** argv) {
  const std::vector<Command> commands = AllCommands();
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0 ||
      std::strcmp(argv[1], "help") == 0) {
    PrintMainHelp(commands);
    return argc < 2 ? kExitUsage : kExitOk;
  }
  const std::string sub = argv[1];
  const auto it = std::find_if(commands.begin(), commands.end(),
                               [&](const Command& c) { return c.name == sub; });
  if (it == commands.end()) {
    std::cerr << "navtwin: unknown subcommand '" << sub << "' (see navtwin --help)\n";
    return kExitUsage;
  }
  for (int i = 2; i < argc; ++i) {
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
      PrintCommandHelp(*it);
      return kExitOk;
    }
  }
  // Parse the flags after the subcommand; what remains are its positional arguments.
  int sub_argc = argc - 1;
  char** sub_argv = argv + 1;
  gflags::SetUsageMessage(it->usage);
  gflags::ParseCommandLineFlags(&sub_argc, &sub_argv, /*remove_flags=*/true);
  const std::vector<std::string> foreign = ForeignFlags(*it);
  if (!foreign.empty()) {
    std::cerr << "navtwin " << sub << ": flag --" << foreign.front()
              << " does not apply to this subcommand\nusage: " << it->usage << "\n";
    return kExitUsage;
  }
  if (FLAGS_format != "text" && FLAGS_format != "json") {
    std::cerr << "navtwin " << sub << ": --format must be text or json\n";
    return kExitUsage;
  }
  std::vector<std::string> args(sub_argv + 1, sub_argv + sub_argc);
  try {
    return it->run(args);
  } catch (const InputError& e) {
    std::cerr << "navtwin " << sub << ": " << e.what() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "navtwin " << sub << ": error: " << e.what() << "\n";
  }
  return kExitFailure;
}

}  // namespace
}  // namespace navtwin::app

int main(int argc, char** argv) {
  google::InitGoogleLogging(argv[0]);
  FLAGS_logtostderr = true;
  return navtwin::app::Main(argc, argv);
}
