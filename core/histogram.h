#pragma once
// Binning for every histogram fvm draws or tabulates (the reports' distance errors and Monte Carlo distributions,
// the test piece's error table): one rule, so that a value on a bin edge falls in the same bin everywhere.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace fvm {

// How many of `values` fall in each of `bins` bins [first_edge + i width, first_edge + (i + 1) width); values below
// the first bin count in it, values beyond the last in the last.
inline std::vector<int> BinCounts(const std::vector<double>& values, double first_edge, double width, int bins) {
  std::vector<int> counts(static_cast<std::size_t>(std::max(bins, 0)), 0);
  if (bins <= 0) return counts;
  for (const double v : values) {
    ++counts[static_cast<std::size_t>(std::clamp(static_cast<int>(std::floor((v - first_edge) / width)), 0, bins - 1))];
  }
  return counts;
}

}  // namespace fvm
