#include "problems/report/decimate.h"

#include <algorithm>
#include <cmath>

namespace navtwin::report {

std::vector<std::size_t> MinMaxIndices(const std::vector<double>& y, std::size_t max_points) {
  const std::size_t n = y.size();
  std::vector<std::size_t> out;
  if (n <= max_points || max_points < 4) {
    out.resize(n);
    for (std::size_t i = 0; i < n; ++i) out[i] = i;
    return out;
  }
  const std::size_t buckets = max_points / 2 - 1;
  out.reserve(2 * buckets + 2);
  out.push_back(0);
  for (std::size_t b = 0; b < buckets; ++b) {
    const std::size_t begin = 1 + (n - 2) * b / buckets, end = 1 + (n - 2) * (b + 1) / buckets;
    std::size_t lo = end, hi = end;
    for (std::size_t i = begin; i < end; ++i) {
      if (!std::isfinite(y[i])) continue;
      if (lo == end || y[i] < y[lo]) lo = i;
      if (hi == end || y[i] > y[hi]) hi = i;
    }
    if (lo == end) {
      if (begin < end) out.push_back(begin);
      continue;
    }
    out.push_back(std::min(lo, hi));
    if (hi != lo) out.push_back(std::max(lo, hi));
  }
  out.push_back(n - 1);
  return out;
}

std::vector<std::size_t> UniformIndices(std::size_t n, std::size_t max_points) {
  std::vector<std::size_t> out;
  if (n == 0) return out;
  const std::size_t step = max_points == 0 ? 1 : std::max<std::size_t>(1, (n + max_points - 1) / max_points);
  for (std::size_t i = 0; i < n; i += step) out.push_back(i);
  if (out.back() != n - 1) out.push_back(n - 1);
  return out;
}

std::vector<double> Pick(const std::vector<double>& v, const std::vector<std::size_t>& indices) {
  std::vector<double> out;
  out.reserve(indices.size());
  for (std::size_t i : indices) out.push_back(v[i]);
  return out;
}

}  // namespace navtwin::report
