// The report's figures from the loaded run folders (run_folder.h): the track, the errors
// with their ±3σ bands, σ against time, NIS per sensor, position NEES and the drift per
// outage. A figure whose data no folder has is left out with the reason.
#pragma once

#include <string>
#include <vector>

#include "problems/report/gnuplot.h"
#include "problems/report/run_folder.h"

namespace navtwin::report {

struct FigureSet {
  std::vector<Figure> figures;        ///< scripts, not yet rendered
  std::vector<std::string> left_out;  ///< "figure: why", one per figure not made
};

/// The GNSS/INS figures (navigate, smooth folders).
FigureSet BuildFigures(const std::vector<RunData>& runs);

/// One plotted error series: x, the error and its σ (empty: no band).
struct BandedSeries {
  std::string label;
  std::string color;
  std::vector<double> x;
  std::vector<double> y;
  std::vector<double> sigma;
};

/// The plot command of errors about zero: per series its ±3σ band shaded in its colour (when
/// it has σ) and its line, the y range clipped to 1.15 × the 99th percentile of
/// max(|error|, 3σ) over all series. Appends the datablocks `prefix`0, 1, ... to f->script
/// and counts the plot elements in f->series.
std::string BandedErrorPlot(const std::vector<BandedSeries>& list, const std::string& prefix, Figure* f);

}  // namespace navtwin::report
