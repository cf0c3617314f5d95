// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Grid: resolution plus coordinate <-> key conversion, with OctoMap's exact arithmetic.
//
//   key(c)    = floor(c * (1.0 / r)) + center   (c promoted to double first, as OctoMap does
//                                               with its float points: 0.7f * 10 -> 6)
//   centre(k) = (double(k - center) + 0.5) * r
// A coordinate is in range when its key fits the key type; conversions say so instead of
// wrapping around.
//
// Thread safety: immutable after construction.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>

#include "config.hpp"
#include "key.hpp"
#include "point_traits.hpp"

namespace knnocc {

template <class Key = OcKey>
class Grid {
 public:
  using key_type = Key;
  using index_type = typename Key::index_type;
  static constexpr int depth = Key::depth;

  /// Smallest accepted resolution (1 micrometre): below it a map could not even hold a sensor's
  /// own noise, so a smaller value is taken for a unit mistake.
  static constexpr double min_resolution = 1e-6;

  /// Largest accepted resolution: the key range, +-center voxels, still fits a float (the
  /// coordinates points and rays are handled in): about 1e34 m for OcKey.
  static constexpr double max_resolution =
      static_cast<double>(std::numeric_limits<float>::max()) / static_cast<double>(Key::center);

  /// resolution: voxel edge in metres; finite, in [min_resolution, max_resolution].
  explicit Grid(double resolution) : res_(resolution), inv_res_(1.0 / resolution) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", resolution);
    if (!(resolution > 0.0) || !std::isfinite(resolution) || !std::isfinite(inv_res_))
      detail::invalid_argument(std::string("resolution must be a finite number > 0, got ") + text);
    if (resolution < min_resolution)
      detail::invalid_argument(std::string("resolution ") + text +
                               " m is below the minimum of 1e-6 m (a unit mistake?)");
    if (resolution > max_resolution)
      detail::invalid_argument(std::string("resolution ") + text +
                               " m is above the maximum: its key range would not fit a float");
    // Rounded to float through memory: GCC 12's SLP vectorizer at -O2 dropped the float round
    // trip of static_cast<float>(step * res * 0.5) where the walks' set-up computed it per border
    // (the border at 0.0 of a 0.05 m voxel came out 0 instead of -3.7e-10), which changed the
    // voxels of rays ending exactly on a border.
    const volatile float half = static_cast<float>(resolution * 0.5);
    half_float_ = static_cast<double>(half);
  }

  double resolution() const { return res_; }

  /// OctoMap's half-voxel in computeRayKeys, static_cast<float>(resolution * 0.5), as a double:
  /// a voxel's borders lie at its centre -+ this in the walks' set-up.
  double half_voxel_float() const { return half_float_; }

  /// Edge length of a node at tree depth d (0 = root, depth = leaf).
  double node_size(int d) const { return std::ldexp(res_, depth - d); }

  /// Smallest and largest coordinate that still has a key: [-center r, center r).
  double min_coord() const { return -static_cast<double>(Key::center) * res_; }
  double max_coord() const { return static_cast<double>(Key::center) * res_; }

  /// One axis: false (and `out` untouched) when c is NaN/Inf or outside the key range.
  bool coord_to_index(double c, index_type& out) const {
    const double scaled = std::floor(inv_res_ * c);
    // Compare in double before any integer cast: NaN fails both tests.
    if (!(scaled >= -static_cast<double>(Key::center) && scaled < static_cast<double>(Key::center)))
      return false;
    out = static_cast<index_type>(static_cast<std::int64_t>(scaled) + Key::center);
    return true;
  }

  bool coord_to_key(double x, double y, double z, Key& out) const {
    Key k;
    if (!coord_to_index(x, k.k[0]) || !coord_to_index(y, k.k[1]) || !coord_to_index(z, k.k[2]))
      return false;
    out = k;
    return true;
  }

  /// Key of any point type (see point_traits.hpp); float coordinates are promoted to double.
  template <class P>
  bool point_to_key(const P& p, Key& out) const {
    return coord_to_key(static_cast<double>(point_x(p)), static_cast<double>(point_y(p)),
                        static_cast<double>(point_z(p)), out);
  }

  /// Centre coordinate of a finest-level index.
  double index_to_coord(index_type k) const {
    return (static_cast<double>(static_cast<std::int64_t>(k) - Key::center) + 0.5) * res_;
  }

  /// Centre coordinate, along one axis, of the depth-d node containing leaf index k
  /// (OctoMap's keyToCoord(key, depth)).
  double index_to_coord(index_type k, int d) const {
    if (d == 0) return 0.0;
    if (d >= depth) return index_to_coord(k);
    const double cells = std::ldexp(1.0, depth - d);
    return (std::floor((static_cast<double>(k) - static_cast<double>(Key::center)) / cells) + 0.5) *
           node_size(d);
  }

  /// The leaf key with its low (depth - d) bits replaced by 1 followed by zeros: the key OctoMap
  /// uses for the depth-d node that contains `key`.
  static Key key_at_depth(const Key& key, int d) {
    if (d >= depth) return key;
    const int shift = depth - d;
    Key out;
    for (int i = 0; i < 3; ++i) {
      // Arithmetic shift floors negative offsets; multiplying back avoids shifting a negative.
      const std::int64_t v = (static_cast<std::int64_t>(key[i]) - Key::center) >> shift;
      out[i] = static_cast<index_type>(v * (std::int64_t{1} << shift) +
                                       (std::int64_t{1} << (shift - 1)) + Key::center);
    }
    return out;
  }

 private:
  double res_;
  double inv_res_;
  double half_float_ = 0.0;
};

}  // namespace knnocc
