// Figures drawn by gnuplot: each figure is a gnuplot script (its data inline as
// datablocks) that RenderFigures runs through the svg terminal, one gnuplot child process
// per figure, in a temporary folder that is removed afterwards.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace navtwin::report {

struct Figure {
  std::string id;       ///< anchor in the page, e.g. "pos_errors"
  std::string title;    ///< heading above the figure
  std::string caption;  ///< what it shows (units, bounds, what was thinned)
  std::string script;   ///< gnuplot commands after the terminal and output lines
  int width_px = 1000;
  int height_px = 560;
  int series = 0;       ///< plot elements the script draws (one <g id="gnuplot_plot_..."> each)
  std::string svg;      ///< the drawing, filled by RenderFigures
};

/// Appends "$name << EOD", one line per row of the columns (same length; NaN written as
/// NaN, which gnuplot leaves out), "EOD".
void AppendDatablock(std::string* script, const std::string& name, const std::vector<std::vector<double>>& columns);

/// x formatted with the printf `format` (for scripts and captions).
std::string GnuplotNumber(const char* format, double x);

/// The settings every figure starts with: the grid and the key's box.
std::string GnuplotCommon();

/// The k-th colour of the report's palette (ten colours, repeating).
const char* SeriesColor(std::size_t k);

/// A gnuplot single-quoted string ('' for a quote).
std::string GnuplotQuote(const std::string& text);

/// Runs gnuplot on every figure's script, at most `jobs` at a time, and stores the SVG.
/// Throws std::runtime_error naming the figure, gnuplot's exit status and its stderr when
/// gnuplot cannot be started, fails or writes no drawing.
void RenderFigures(std::vector<Figure>* figures, int jobs);

}  // namespace navtwin::report
