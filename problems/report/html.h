// The report page: one self-contained HTML file (CSS inline, figures as base64 SVG data
// URIs, nothing fetched) with the summary tables of every run folder, the figures, the
// figures left out and why, and a small script that marks the page with how many figures
// the browser loaded (body data-figures-loaded="loaded/total").
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "problems/report/gnuplot.h"
#include "problems/report/run_folder.h"

namespace navtwin::report {

/// An entry of the page's contents: the anchor of a section and its heading.
struct PageSection {
  std::string id;
  std::string title;
};

/// What a page holds besides its figures.
struct PageText {
  std::string title;                  ///< text: the <title> and the <h1>
  std::string intro;                  ///< HTML: one paragraph under the heading
  std::vector<PageSection> sections;  ///< the body's sections, for the contents
  std::string body;                   ///< HTML: the sections (tables) before the figures
  std::vector<std::string> notes;     ///< text: files not found, listed under "Left out"
};

/// The page frame every report shares: heading, contents, the body, the figures, what was
/// left out (`left_out`, then `text.notes`) and the script that counts the loaded figures.
std::string HtmlPage(const PageText& text, const std::vector<Figure>& figures, const std::vector<std::string>& left_out);

/// The table pieces: a number formatted (an en dash when not finite), a number cell (`bad`
/// marks it red), a left-aligned text cell, the header row (the first `text_columns`
/// columns hold names).
std::string HtmlNumber(const char* format, double x);
std::string HtmlCell(double x, const char* format = "%.4g", bool bad = false);
std::string HtmlNameCell(const std::string& text);
std::string HtmlHead(const std::vector<std::string>& names, std::size_t text_columns = 1);

/// The GNSS/INS page (navigate, smooth) for the folders and their rendered figures.
std::string ReportHtml(const std::vector<RunData>& runs, const std::vector<Figure>& figures,
                       const std::vector<std::string>& left_out);

/// Letters, digits, '-' and '_' of a figure id (others become '_'): its anchor in the page
/// and its file name with --figures_dir.
std::string HtmlAnchor(const std::string& id);

/// Text made safe inside HTML elements and attribute values.
std::string HtmlEscape(const std::string& text);

/// Standard base64 (RFC 4648) with padding.
std::string Base64(const std::string& bytes);

}  // namespace navtwin::report
