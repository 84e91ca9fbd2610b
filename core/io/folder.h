// Output folders of the commands' run folders (docs/run-folder.md).
#pragma once

#include <string>
#include <utility>

namespace navtwin {

/// Creates `dir` (one level) unless it exists as a folder; std::runtime_error when it
/// exists as something else or cannot be created.
void EnsureFolder(const std::string& dir);

/// A command's output folder: created when missing, and removed again (if it is empty by
/// then) when the run fails, i.e. when the object is destroyed before Keep(), so that a
/// failed run leaves nothing behind. A folder that existed before is never removed.
class OutputFolder {
 public:
  explicit OutputFolder(std::string dir) : dir_(std::move(dir)) {}
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  /// True when the folder exists (as a folder) afterwards.
  bool Make();
  void Keep() { keep_ = true; }

 private:
  std::string dir_;
  bool created_ = false;
  bool keep_ = false;
};

}  // namespace navtwin
