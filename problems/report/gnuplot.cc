#include "problems/report/gnuplot.h"

#include <fcntl.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

extern char** environ;

namespace navtwin::report {
namespace {

/// A temporary folder, removed with everything in it when this goes out of scope.
class ScratchFolder {
 public:
  ScratchFolder() {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp != nullptr && tmp[0] != '\0' ? tmp : "/tmp") + "/navtwin-report-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw std::runtime_error("cannot create a temporary folder " + pattern + ": " + std::strerror(errno));
    }
    path_ = pattern;
  }
  ~ScratchFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::string SlurpFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Starts `gnuplot script` with stdout and stderr into files beside the script; its pid.
pid_t SpawnGnuplot(const std::string& script, const std::string& log, const std::string& figure) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::string program = "gnuplot";
  std::string arg = script;
  char* argv[] = {program.data(), arg.data(), nullptr};
  pid_t pid = 0;
  const int rc = ::posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    throw std::runtime_error("figure " + figure + ": cannot run gnuplot: " + std::strerror(rc) +
                             (rc == ENOENT ? " (install it: apt-get install gnuplot-nox)" : ""));
  }
  return pid;
}

std::string FullScript(const Figure& f, const std::string& svg_path) {
  std::ostringstream s;
  s << "set encoding utf8\n"
    << "set terminal svg size " << f.width_px << "," << f.height_px
    << " dynamic noenhanced font 'DejaVu Sans,12' background rgb 'white'\n"
    << "set output " << GnuplotQuote(svg_path) << "\n"
    << f.script << "\nunset output\n";
  return s.str();
}

}  // namespace

std::string GnuplotNumber(const char* format, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

std::string GnuplotCommon() {
  return "set grid lc rgb '#d0d0d0'\nset key top right opaque box lc rgb '#c0c0c0' font ',10'\n";
}

const char* SeriesColor(std::size_t k) {
  static const char* const kPalette[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b",
                                         "#d62728", "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"};
  return kPalette[k % 10];
}

std::string GnuplotQuote(const std::string& text) {
  std::string out = "'";
  for (char c : text) {
    if (c == '\'') out += '\'';
    if (c == '\n') {
      out += ' ';
      continue;
    }
    out += c;
  }
  return out + "'";
}

void AppendDatablock(std::string* script, const std::string& name, const std::vector<std::vector<double>>& columns) {
  *script += "$" + name + " << EOD\n";
  const std::size_t rows = columns.empty() ? 0 : columns.front().size();
  char buf[40];
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (c > 0) *script += ' ';
      const double x = columns[c][r];
      if (!std::isfinite(x)) {
        *script += "NaN";
        continue;
      }
      const auto res = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, 8);
      script->append(buf, res.ptr);
    }
    *script += '\n';
  }
  *script += "EOD\n";
}

void RenderFigures(std::vector<Figure>* figures, int jobs) {
  const ScratchFolder scratch;
  const std::size_t n = figures->size();
  std::vector<pid_t> pids(n, 0);
  const auto path = [&](std::size_t i, const char* ext) { return scratch.path() + "/" + std::to_string(i) + ext; };
  const auto finish = [&](std::size_t i, int status) {
    const Figure& f = (*figures)[i];
    const std::string log = SlurpFile(path(i, ".log"));
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      throw std::runtime_error("figure " + f.id + ": gnuplot failed (" +
                               (WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                                  : std::string("killed by a signal")) +
                               "): " + log);
    }
    (*figures)[i].svg = SlurpFile(path(i, ".svg"));
    if ((*figures)[i].svg.find("</svg>") == std::string::npos) {
      throw std::runtime_error("figure " + f.id + ": gnuplot wrote no complete SVG: " + log);
    }
  };
  // Figures start in order, at most `jobs` at once, and are collected in the same order.
  const std::size_t limit = static_cast<std::size_t>(std::max(1, jobs));
  std::size_t next = 0;
  std::string failure;
  for (std::size_t i = 0; i < n; ++i) {
    while (failure.empty() && next < n && next < i + limit) {
      std::ofstream(path(next, ".gp")) << FullScript((*figures)[next], path(next, ".svg"));
      try {
        pids[next] = SpawnGnuplot(path(next, ".gp"), path(next, ".log"), (*figures)[next].id);
      } catch (const std::exception& e) {
        failure = e.what();
      }
      ++next;
    }
    if (pids[i] == 0) continue;
    int status = 0;
    while (::waitpid(pids[i], &status, 0) < 0 && errno == EINTR) {
    }
    pids[i] = 0;
    if (!failure.empty()) continue;  // collecting the children started before the failure
    try {
      finish(i, status);
    } catch (const std::exception& e) {
      failure = e.what();
    }
  }
  if (!failure.empty()) throw std::runtime_error(failure);
}

}  // namespace navtwin::report
