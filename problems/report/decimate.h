// Thinning of plotted series (never of the numbers the report scores): a figure needs at
// most a few thousand points per series to show what a million show.
#pragma once

#include <cstddef>
#include <vector>

namespace navtwin::report {

/// Indices (increasing) of the points of y to plot, at most about max_points: the series is
/// cut into max_points / 2 buckets of consecutive samples and each bucket keeps its smallest
/// and its largest finite value (so peaks, spikes and the envelope survive), plus the first
/// and the last sample. A bucket without a finite value keeps one sample, so that gaps stay
/// gaps. A series of at most max_points samples is kept whole.
std::vector<std::size_t> MinMaxIndices(const std::vector<double>& y, std::size_t max_points);

/// Every k-th index (and the last) so that at most about max_points remain: for tracks and
/// scatter of positions, where min/max of one coordinate means nothing.
std::vector<std::size_t> UniformIndices(std::size_t n, std::size_t max_points);

/// The values of v at the indices.
std::vector<double> Pick(const std::vector<double>& v, const std::vector<std::size_t>& indices);

}  // namespace navtwin::report
