// Output files appear whole or not at all: data goes to a temporary file in the same
// folder, renamed over the target by Commit(). A writer destroyed without Commit()
// (an exception, bad input) removes the temporary, so no partial output is left; a
// committed file that belongs to a larger output which then fails is removed by Revoke().
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
  /// Undoes a Commit (a later step of an all-or-nothing output failed): removes the file.
  /// Before Commit it does nothing (the destructor removes the temporary).
  void Revoke();

 private:
  std::string path_;
  std::string tmp_path_;
  std::ofstream out_;
  bool committed_ = false;
};

}  // namespace navtwin
