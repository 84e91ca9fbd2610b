#include "core/io/folder.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <stdexcept>

namespace navtwin {

void EnsureFolder(const std::string& dir) {
  struct stat st;
  if (::stat(dir.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) throw std::runtime_error(dir + " exists and is not a folder");
    return;
  }
  if (::mkdir(dir.c_str(), 0755) != 0 && errno != EEXIST) throw std::runtime_error("cannot create the folder " + dir);
}

OutputFolder::~OutputFolder() {
  if (created_ && !keep_) ::rmdir(dir_.c_str());
}

bool OutputFolder::Make() {
  struct stat st;
  if (::stat(dir_.c_str(), &st) == 0) return S_ISDIR(st.st_mode);
  created_ = ::mkdir(dir_.c_str(), 0755) == 0;
  return created_;
}

}  // namespace navtwin
