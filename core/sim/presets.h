// The named scenarios of the seeds (parameters and their sources in docs/scenarios.md).
// Each preset is YAML text in the scenario schema, so a preset and a file go through the
// same parser, and `navtwin simulate --print_scenario PRESET` shows a starting point for
// a user's own file.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace navtwin::sim {

/// The preset names, in the order docs/scenarios.md lists them.
std::vector<std::string> PresetNames();

/// The YAML text of a preset, or nothing when `name` is not a preset.
std::optional<std::string> PresetYaml(const std::string& name);

}  // namespace navtwin::sim
