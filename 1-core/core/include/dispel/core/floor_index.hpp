#pragma once
/// @file
/// The cell of a coordinate without a call into libm.

#include <cstdint>

namespace dispel {

/// std::floor(@p v) as an integer, for a finite @p v within the range of std::int64_t:
/// truncation, then one less for a negative value that was not whole. The grids ask it for every
/// point they index, many times a scan (std::floor is a call into libm on x86-64's baseline).
inline std::int64_t floor_index(double v) {
  const auto i = static_cast<std::int64_t>(v);
  return static_cast<double>(i) > v ? i - 1 : i;
}

}  // namespace dispel
