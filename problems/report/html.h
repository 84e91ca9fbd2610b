// The report page: one self-contained HTML file (CSS inline, figures as base64 SVG data
// URIs, nothing fetched) with the summary tables of every run folder, the figures, the
// figures left out and why, and a small script that marks the page with how many figures
// the browser loaded (body data-figures-loaded="loaded/total").
#pragma once

#include <string>
#include <vector>

#include "problems/report/gnuplot.h"
#include "problems/report/run_folder.h"

namespace navtwin::report {

/// The page for the folders and their rendered figures.
std::string ReportHtml(const std::vector<RunData>& runs, const std::vector<Figure>& figures,
                       const std::vector<std::string>& left_out);

/// Text made safe inside HTML elements and attribute values.
std::string HtmlEscape(const std::string& text);

/// Standard base64 (RFC 4648) with padding.
std::string Base64(const std::string& bytes);

}  // namespace navtwin::report
