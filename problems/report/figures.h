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

FigureSet BuildFigures(const std::vector<RunData>& runs);

}  // namespace navtwin::report
