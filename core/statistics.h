#pragma once
// The few order statistics and means every module quotes, written once.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace fvm {

// The element at n / 2 of the sorted values (the upper of the two middle ones for even n): what a robust scale
// (MAD) or a least-median search takes. NaN for none. Reorders `values`: for a search that reuses its buffer.
template <typename T>
double HighMedianInPlace(std::vector<T>& values) {
  if (values.empty()) return NAN;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return static_cast<double>(*mid);
}
template <typename T>
double HighMedian(std::vector<T> values) {
  return HighMedianInPlace(values);
}

// The median: for even n the mean of the two middle values. NaN for none.
template <typename T>
double Median(std::vector<T> values) {
  if (values.empty()) return NAN;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  if (values.size() % 2 == 1) return static_cast<double>(*mid);
  return 0.5 * (static_cast<double>(*mid) + static_cast<double>(*std::max_element(values.begin(), mid)));
}

// Root mean square; 0 for none.
inline double Rms(const std::vector<double>& values) {
  double sum = 0;
  for (const double v : values) sum += v * v;
  return values.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(values.size()));
}

}  // namespace fvm
