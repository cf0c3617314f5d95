// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// KeyRounding: Grid::point_to_key without std::floor, for per-point loops.
//
// Grid computes floor(c * (1.0 / r)) with std::floor, which on baseline x86-64 (no SSE4.1 round
// instruction) is a branchy sequence that mispredicts on coordinates of mixed sign. Here: the
// same double product, truncation to an integer and a correction when truncation rounded up
// (negative non-integers). The range test is the same: floor(s) >= -center iff s >= -center,
// floor(s) < center iff s < center, for an integer center. The tests compare the results with
// Grid and liboctomap.

#include <cstdint>

#include "../config.hpp"
#include "../grid.hpp"
#include "../point3.hpp"

namespace knnocc::detail {

template <class Key>
class KeyRounding {
 public:
  explicit KeyRounding(const Grid<Key>& grid) : inv_res_(1.0 / grid.resolution()) {}

  /// Grid::point_to_key(p, key) for a float point, the key as three integers.
  KNNOCC_ALWAYS_INLINE bool point_to_key(const Point3f& p, std::int64_t (&key)[3]) const {
    return index(p.x, key[0]) && index(p.y, key[1]) && index(p.z, key[2]);
  }

  /// The factor that scales a coordinate to voxels (1 / resolution).
  double inverse_resolution() const { return inv_res_; }

  /// Grid::coord_to_index for one float coordinate.
  KNNOCC_ALWAYS_INLINE bool index(float c, std::int64_t& out) const {
    const double s = inv_res_ * static_cast<double>(c);
    constexpr auto center = static_cast<double>(Key::center);
    if (!(s >= -center && s < center)) return false;  // NaN fails too
    const auto t = static_cast<std::int64_t>(s);      // towards zero
    out = t - (static_cast<double>(t) > s) + Key::center;
    return true;
  }

 private:
  double inv_res_;
};

}  // namespace knnocc::detail
