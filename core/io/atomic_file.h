// Output files appear whole or not at all: data goes to a temporary file in the same
// folder, renamed over the target by Commit(). A writer destroyed without Commit()
// (an exception, bad input) removes the temporary, so no partial output is left.
// Doubles written to stream() come out in the shortest form that reads back exactly.
#pragma once

#include <fstream>
#include <string>

namespace navtwin {

class AtomicFile {
 public:
  /// Opens "<path>.tmp.<pid>" for writing; throws std::runtime_error if it cannot.
  explicit AtomicFile(const std::string& path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ostream& stream() { return out_; }
  const std::string& path() const { return path_; }
  /// Flushes, closes and renames onto the target; throws std::runtime_error on failure.
  void Commit();

 private:
  std::string path_;
  std::string tmp_path_;
  std::ofstream out_;
  bool committed_ = false;
};

}  // namespace navtwin
