// Output folders of the commands' run folders (docs/run-folder.md).
#pragma once

#include <string>

namespace navtwin {

/// Creates `dir` (one level) unless it exists as a folder; std::runtime_error when it
/// exists as something else or cannot be created.
void EnsureFolder(const std::string& dir);

}  // namespace navtwin
