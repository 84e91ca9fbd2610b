// navtwin: the command-line front end. `navtwin SUB [flags] [args]`; `navtwin --help`
// lists the subcommands, `navtwin SUB --help` the flags of one.
#include <gflags/gflags.h>
#include <glog/logging.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <exception>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/input_error.h"

namespace navtwin::app {

namespace {

std::vector<Command> AllCommands() {
  return {InfoCommand(),          ConvertCommand(),       InsCommand(),
          SimulateCommand(),      AllanCommand(),         NavigateCommand(),
          SmoothCommand(),        LevelCommand(),         LevelMcCommand(),
          InflightAlignCommand(), InflightMcCommand(),    TransferAlignCommand(),
          TransferAlignAnsflCommand(), CalibrateImuCommand(), CalibrateMagCommand(),
          ReportCommand(),        McCommand(),            BoundCommand()};
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

/// Parses the flags after the subcommand into gflags, or names what is wrong. Unlike
/// gflags::ParseCommandLineFlags (which exits 1), an unknown flag or a value its type does
/// not take is reported here, so that the caller exits 2. The syntax is gflags': one or
/// two leading dashes, --name=value, --name value (not for booleans), --name and --noname
/// (booleans); "--" ends the flags. Arguments that are not flags go to *positional, in order.
bool ParseFlags(const std::vector<std::string>& argv, std::vector<std::string>* positional,
                std::string* error) {
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& arg = argv[i];
    if (arg == "--") {
      positional->insert(positional->end(), argv.begin() + static_cast<std::ptrdiff_t>(i) + 1, argv.end());
      break;
    }
    if (arg.size() < 2 || arg[0] != '-') {
      positional->push_back(arg);
      continue;
    }
    const std::string body = arg.substr(arg[1] == '-' ? 2 : 1);
    const std::size_t eq = body.find('=');
    std::string name = body.substr(0, eq);
    std::optional<std::string> value;
    if (eq != std::string::npos) value = body.substr(eq + 1);
    gflags::CommandLineFlagInfo info;
    if (!gflags::GetCommandLineFlagInfo(name.c_str(), &info)) {
      const bool negated_bool = !value && name.rfind("no", 0) == 0 &&
                                gflags::GetCommandLineFlagInfo(name.substr(2).c_str(), &info) && info.type == "bool";
      if (!negated_bool) {
        *error = "unknown flag --" + name;
        return false;
      }
      name = name.substr(2);
      value = "false";
    }
    if (!value) {
      if (info.type == "bool") {
        value = "true";
      } else if (i + 1 < argv.size()) {
        value = argv[++i];
      } else {
        *error = "flag --" + name + " needs a value";
        return false;
      }
    }
    if (gflags::SetCommandLineOption(name.c_str(), value->c_str()).empty()) {
      *error = "bad value '" + *value + "' for --" + name + " (" + info.type + ")";
      return false;
    }
  }
  return true;
}

void PrintVersion() {
  std::cout << "navtwin " << NAVTWIN_VERSION << " (commit " << NAVTWIN_GIT_COMMIT << ")\n";
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
  if (std::strcmp(argv[1], "--version") == 0) {
    PrintVersion();
    return kExitOk;
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
    if (std::strcmp(argv[i], "--version") == 0) {
      PrintVersion();
      return kExitOk;
    }
  }
  std::vector<std::string> args;
  std::string error;
  if (!ParseFlags(std::vector<std::string>(argv + 2, argv + argc), &args, &error)) {
    std::cerr << "navtwin " << sub << ": " << error << "\nusage: " << it->usage << "\n";
    return kExitUsage;
  }
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
