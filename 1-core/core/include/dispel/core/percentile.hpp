#pragma once
/// @file
/// Percentiles of per-scan figures (times, residuals), as `dispel filter --stats` and the soak
/// report them.

#include <algorithm>
#include <cstddef>
#include <vector>

namespace dispel {

/// The @p p quantile (p in [0, 1]) of @p values by rank, without interpolation: the value of rank
/// round(p (n - 1)) in ascending order (of an even count, the median is the upper middle value).
/// 0 for no values.
template <typename T>
double percentile(std::vector<T> values, double p) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(p * static_cast<double>(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return static_cast<double>(values[k]);
}

}  // namespace dispel
