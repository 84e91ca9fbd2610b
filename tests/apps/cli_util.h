// Running the built navtwin command from the CLI tests: its exit code, stdout and stderr,
// plus the small file and JSON helpers those tests share.
#pragma once

#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace navtwin::cli_test {

struct RunResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

inline std::string ReadAll(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/// A new empty folder under the test's temporary directory.
inline std::string MakeTempDir(const std::string& tag) {
  std::string tmpl = ::testing::TempDir() + "navtwin_" + tag + "_XXXXXX";
  EXPECT_NE(::mkdtemp(tmpl.data()), nullptr);
  return tmpl;
}

/// Runs `navtwin ARGS` (the binary in NAVTWIN_BIN_DIR) and captures its output.
inline RunResult Navtwin(const std::string& args) {
  static const std::string dir = MakeTempDir("cli_io");
  const std::string out = dir + "/stdout", err = dir + "/stderr";
  const std::string cmd = std::string(NAVTWIN_BIN_DIR) + "/navtwin " + args + " >" + out + " 2>" + err;
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadAll(out);
  r.err = ReadAll(err);
  return r;
}

/// How often `what` occurs in `text` (non-overlapping starts counted one by one).
inline std::size_t Occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

inline bool Exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

/// The number after "key": following `anchor` in a flat piece of JSON (enough for the
/// command's fixed outputs); NaN when absent.
inline double JsonNumberAfter(const std::string& json, const std::string& anchor, const std::string& key) {
  const std::size_t at = json.find(anchor);
  if (at == std::string::npos) return NAN;
  std::smatch m;
  const std::string rest = json.substr(at);
  if (!std::regex_search(rest, m, std::regex("\"" + key + "\":(-?[0-9.eE+-]+)"))) return NAN;
  return std::stod(m[1]);
}

}  // namespace navtwin::cli_test
