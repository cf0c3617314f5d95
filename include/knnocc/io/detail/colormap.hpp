// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal: the height colour ramp of voxel exports and map pictures (blue - cyan - green -
// yellow - red, like the "jet" ramps of octovis and CloudCompare).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace knnocc::io::detail {

/// Colour of t in [0, 1] (clamped; NaN gives the low end).
inline std::array<std::uint8_t, 3> height_colour(double t) {
  if (!(t > 0.0)) t = 0.0;
  if (t > 1.0) t = 1.0;
  static const double stops[5][3] = {{0.15, 0.25, 0.85},
                                     {0.10, 0.75, 0.90},
                                     {0.20, 0.80, 0.25},
                                     {0.95, 0.85, 0.15},
                                     {0.85, 0.15, 0.10}};
  const double s = t * 4.0;
  const int i = std::min(3, static_cast<int>(s));
  const double f = s - i;
  std::array<std::uint8_t, 3> c{};
  for (int k = 0; k < 3; ++k) {
    const double v = stops[i][k] + (stops[i + 1][k] - stops[i][k]) * f;
    c[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(std::lround(255.0 * v));
  }
  return c;
}

}  // namespace knnocc::io::detail
