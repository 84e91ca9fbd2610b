// Checks of a report page (problems/report) shared by the report tests: its figures pulled
// out of the HTML (data URIs), what an SVG drawn by gnuplot holds, the PNG signature, and
// the page rendered by headless chromium.
#pragma once

#include <stdlib.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <cstdio>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace navtwin::report_page_check {

struct PageFigure {
  std::string id;
  int series = -1;      ///< the page's data-series attribute
  std::string mime;     ///< image/svg+xml or image/png
  std::string bytes;    ///< decoded
};

inline std::string DecodeBase64(const std::string& text) {
  std::string out;
  int bits = 0;
  unsigned value = 0;
  for (char c : text) {
    int v = -1;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    else if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    else if (c >= '0' && c <= '9') v = c - '0' + 52;
    else if (c == '+') v = 62;
    else if (c == '/') v = 63;
    if (v < 0) continue;
    value = (value << 6) | static_cast<unsigned>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((value >> bits) & 0xFF);
    }
  }
  return out;
}

/// The text between `open` (after position *at) and the next `close`; advances *at.
inline std::string Between(const std::string& text, const std::string& open, const std::string& close,
                           std::size_t* at) {
  const std::size_t a = text.find(open, *at);
  if (a == std::string::npos) return "";
  const std::size_t b = text.find(close, a + open.size());
  if (b == std::string::npos) return "";
  *at = b + close.size();
  return text.substr(a + open.size(), b - a - open.size());
}

/// Every <figure id=".." data-series=".."> with its <img src="data:MIME;base64,..."> (found
/// without std::regex, which recurses per character on megabytes of base64).
inline std::vector<PageFigure> Figures(const std::string& html) {
  std::vector<PageFigure> out;
  std::size_t at = 0;
  for (;;) {
    PageFigure f;
    f.id = Between(html, "<figure id=\"", "\"", &at);
    if (f.id.empty()) break;
    f.series = std::stoi(Between(html, "data-series=\"", "\"", &at));
    f.mime = Between(html, "src=\"data:", ";base64,", &at);
    f.bytes = DecodeBase64(Between(html, "", "\"", &at));
    out.push_back(std::move(f));
  }
  return out;
}

/// The plot elements of a gnuplot SVG: its distinct <g id="gnuplot_plot_..."> groups (an
/// opaque key makes gnuplot write the groups of the keyed panel twice).
inline int PlottedSeries(const std::string& svg) {
  std::set<std::string> ids;
  std::size_t at = 0;
  for (;;) {
    const std::string id = Between(svg, "<g id=\"gnuplot_plot_", "\"", &at);
    if (id.empty()) break;
    ids.insert(id);
  }
  return static_cast<int>(ids.size());
}

/// Width and height of an SVG's root element from its viewBox (gnuplot's dynamic svg
/// terminal writes no width and height); 0 when it is not a complete SVG.
inline void SvgSize(const std::string& svg, int* width, int* height) {
  *width = *height = 0;
  const std::size_t root = svg.find("<svg");
  if (root == std::string::npos || svg.find("</svg>") == std::string::npos) return;
  std::size_t at = root;
  const std::string box = Between(svg, "viewBox=\"", "\"", &at);
  double x = 0, y = 0, w = 0, h = 0;
  if (std::sscanf(box.c_str(), "%lf %lf %lf %lf", &x, &y, &w, &h) == 4) {
    *width = static_cast<int>(w);
    *height = static_cast<int>(h);
  }
}

/// PNG signature and the IHDR chunk's width and height (false when it is not a PNG).
inline bool PngSize(const std::string& png, int* width, int* height) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (png.size() < 24 || png.compare(0, 8, std::string(reinterpret_cast<const char*>(kSignature), 8)) != 0 ||
      png.compare(12, 4, "IHDR") != 0) {
    return false;
  }
  const auto be32 = [&](std::size_t at) {
    return (static_cast<unsigned char>(png[at]) << 24) | (static_cast<unsigned char>(png[at + 1]) << 16) |
           (static_cast<unsigned char>(png[at + 2]) << 8) | static_cast<unsigned char>(png[at + 3]);
  };
  *width = static_cast<int>(be32(16));
  *height = static_cast<int>(be32(20));
  return *width > 0 && *height > 0;
}

/// The chromium program on PATH, or "" when there is none.
inline std::string ChromiumProgram() {
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    if (std::system((std::string("command -v ") + name + " >/dev/null 2>&1").c_str()) == 0) return name;
  }
  return "";
}

/// The DOM of `html_path` after its load event, from headless chromium; "" when it failed.
inline std::string DumpDom(const std::string& chromium, const std::string& html_path, const std::string& scratch) {
  const std::string out = scratch + "/dom.html";
  const std::string cmd = chromium + " --headless --disable-gpu --no-sandbox --user-data-dir=" + scratch +
                          "/profile --virtual-time-budget=10000 --dump-dom file://" + html_path + " >" + out +
                          " 2>" + scratch + "/chromium.log";
  const int status = std::system(cmd.c_str());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return "";
  std::ifstream in(out);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace navtwin::report_page_check
