// navtwin info FILE: what a file holds — its kind, and per stream the sample count, time
// span, rate, gaps and fields.
#include <gflags/gflags.h>

#include <algorithm>
#include <cstdio>
#include <iostream>

#include "apps/navtwin/command.h"
#include "apps/navtwin/common_flags.h"
#include "core/io/json_writer.h"
#include "core/io/open.h"


namespace navtwin::app {
namespace {

// Text: one line per stream with aligned columns; at most kMaxFields fields are listed
// (--format=json lists them all).
void PrintText(const FileSummary& s) {
  constexpr std::size_t kMaxFields = 12;
  std::size_t width = 8;
  for (const StreamSummary& st : s.streams) width = std::max(width, st.name.size());
  std::cout << s.path << ": " << s.kind << "\n";
  for (const StreamSummary& st : s.streams) {
    char line[256];
    std::snprintf(line, sizeof line,
                  "  %-*s %9zu samples  t %.3f .. %.3f s (%.1f s)  %.2f Hz (mean %.2f)  %zu gaps (max %.3f s)\n",
                  static_cast<int>(width), st.name.c_str(), st.count, st.t_first_s, st.t_last_s,
                  st.t_last_s - st.t_first_s, st.rate_hz, st.mean_rate_hz, st.gaps, st.max_gap_s);
    std::cout << line;
    if (!st.fields.empty()) {
      std::cout << "  " << std::string(width, ' ') << " fields:";
      for (std::size_t i = 0; i < st.fields.size() && i < kMaxFields; ++i) std::cout << ' ' << st.fields[i];
      if (st.fields.size() > kMaxFields) std::cout << " ... (" << st.fields.size() - kMaxFields << " more)";
      std::cout << "\n";
    }
  }
  for (const std::string& n : s.notes) std::cout << "  note: " << n << "\n";
}

void PrintJson(const FileSummary& s) {
  JsonWriter w(std::cout);
  w.BeginObject().Field("path", s.path).Field("kind", s.kind);
  w.Key("streams").BeginArray();
  for (const StreamSummary& st : s.streams) {
    w.BeginObject()
        .Field("name", st.name)
        .Field("count", st.count)
        .Field("t_first_s", st.t_first_s)
        .Field("t_last_s", st.t_last_s)
        .Field("rate_hz", st.rate_hz)
        .Field("mean_rate_hz", st.mean_rate_hz)
        .Field("gaps", st.gaps)
        .Field("max_gap_s", st.max_gap_s);
    w.Key("fields").BeginArray();
    for (const std::string& f : st.fields) w.Value(f);
    w.EndArray().EndObject();
  }
  w.EndArray();
  w.Key("notes").BeginArray();
  for (const std::string& n : s.notes) w.Value(n);
  w.EndArray().EndObject();
  std::cout << "\n";
}

int RunInfo(const std::vector<std::string>& args) {
  if (args.size() != 1) {
    std::cerr << "usage: navtwin info FILE [--format=json]\n";
    return kExitUsage;
  }
  const FileSummary summary = DescribeFile(args[0]);
  if (FLAGS_format == "json") {
    PrintJson(summary);
  } else {
    PrintText(summary);
  }
  return kExitOk;
}

}  // namespace

Command InfoCommand() {
  return {"info", "Describe a data file: kind, time span, rates, gaps, columns or topics",
          "navtwin info FILE [--format=json]", {}, &RunInfo};
}

}  // namespace navtwin::app
