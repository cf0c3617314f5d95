// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// finite_bounds: the coordinate bounds of a block of Point3f, written so that the compiler
// vectorises it (ScanInserter's bounds pass over a large scan, before its chunks are walked).
//
// Eight points are 24 floats, whole vectors of 4 or 8: per float position the running minimum and
// maximum (a position's axis is its index mod 3), merged per axis at the end. Only for points
// that are all finite, which the same loop checks: a scan with a NaN or Inf point anywhere in the
// block takes the caller's per-point loop, which treats such points one by one.

#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstring>

#include "../../core/point3.hpp"

namespace knnocc::detail {

/// Widens lo/hi (per axis) to hold points[0..n) and returns true, or returns false, with lo/hi
/// unchanged, when any of the points has a NaN or Inf coordinate.
inline bool finite_bounds(const Point3f* points, std::size_t n, float (&lo)[3], float (&hi)[3]) {
  static_assert(sizeof(Point3f) == 3 * sizeof(float), "Point3f is three packed floats");
  constexpr std::size_t kPoints = 8, kFloats = 3 * kPoints;
  float l[kFloats], h[kFloats];
  for (std::size_t j = 0; j < kFloats; ++j) {
    l[j] = lo[j % 3];
    h[j] = hi[j % 3];
  }
  unsigned bad = 0;
  std::size_t i = 0;
  for (; i + kPoints <= n; i += kPoints) {
    float f[kFloats];
    std::memcpy(f, points + i, sizeof f);
    for (std::size_t j = 0; j < kFloats; ++j) {
      bad |= std::fabs(f[j]) <= FLT_MAX ? 0u : 1u;  // NaN fails too
      l[j] = f[j] < l[j] ? f[j] : l[j];
      h[j] = f[j] > h[j] ? f[j] : h[j];
    }
  }
  for (; i < n; ++i) {
    const float f[3] = {points[i].x, points[i].y, points[i].z};
    for (std::size_t a = 0; a < 3; ++a) {
      bad |= std::fabs(f[a]) <= FLT_MAX ? 0u : 1u;
      l[a] = f[a] < l[a] ? f[a] : l[a];
      h[a] = f[a] > h[a] ? f[a] : h[a];
    }
  }
  if (bad) return false;
  for (std::size_t j = 0; j < kFloats; ++j) {
    lo[j % 3] = l[j] < lo[j % 3] ? l[j] : lo[j % 3];
    hi[j % 3] = h[j] > hi[j % 3] ? h[j] : hi[j % 3];
  }
  return true;
}

}  // namespace knnocc::detail
