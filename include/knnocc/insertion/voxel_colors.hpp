// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// VoxelColors: the colour of each voxel, as the mean of the colours of the points that hit it.
//
// A point hits the voxel it lies in when the scan inserter would mark that voxel occupied from
// it: finite, within max_range of the sensor by OctoMap's float norm (or max_range < 0), and
// inside the key range: the same tests as ScanInserter's. Every model's endpoints count, whatever
// the model made of them (a k-NN model may rate a point below 0.5; its colour still counts for
// its voxel), so a voxel's colour does not depend on the model. Sums are kept per voxel, so the
// mean is that of all the points of all scans, in any order; it is rounded to the nearest
// integer per channel. Writers use it for the voxels that are occupied in the map.
//
// The colours are kept beside the map, not in it: mapping without colours costs nothing.
// Memory: about 56 bytes per voxel that a coloured point hit.
//
// Thread safety: const functions may run concurrently while nobody adds.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "../core/detail/flat_index.hpp"
#include "../core/grid.hpp"
#include "../core/key.hpp"
#include "../core/point3.hpp"
#include "../core/point_traits.hpp"
#include "../core/rgb.hpp"
#include "../raycast/dda.hpp"

namespace knnocc {

template <class Key = OcKey>
class VoxelColors {
 public:
  explicit VoxelColors(double resolution) : grid_(resolution) {}

  const Grid<Key>& grid() const { return grid_; }

  /// One point's colour into voxel `key`.
  void add(const Key& key, Rgb c) {
    bool inserted = false;
    const std::uint32_t slot =
        index_.find_or_insert(key.pack(), static_cast<std::uint32_t>(sums_.size()), inserted);
    if (inserted) sums_.push_back(Sum{key.pack(), 0, 0, 0, 0});
    Sum& s = sums_[slot];
    s.r += c.r;
    s.g += c.g;
    s.b += c.b;
    ++s.n;
  }

  /// The colours of one scan's points (world frame, any point type; colors[i] belongs to
  /// points[i]) seen from `origin`, with the scan's max_range (< 0: no limit).
  template <class Points, class Origin>
  void add_scan(const Origin& origin, const Points& points, const std::vector<Rgb>& colors,
                double max_range = -1.0) {
    const Point3f o = detail::to_point3f(origin);
    std::size_t i = 0;
    for (const auto& point : points) {
      const Rgb c = colors[i++];
      const Point3f p = detail::to_point3f(point);
      if (!detail::finite(p)) continue;
      if (max_range >= 0.0 && !(detail::octomap_norm(p.x - o.x, p.y - o.y, p.z - o.z) <= max_range))
        continue;
      Key k;
      if (grid_.point_to_key(p, k)) add(k, c);
    }
  }

  /// The mean colour of the points that hit `key`; nullopt when none did.
  std::optional<Rgb> mean(const Key& key) const {
    const std::uint32_t slot = index_.find(key.pack());
    if (slot == detail::FlatIndex::kNone) return std::nullopt;
    return sums_[slot].mean();
  }

  /// Calls f(key, mean colour) for every voxel a coloured point hit (in the order of first hits).
  template <class F>
  void for_each(F&& f) const {
    for (const Sum& s : sums_) f(Key::unpack(s.key), s.mean());
  }

  std::size_t size() const { return sums_.size(); }
  bool empty() const { return sums_.empty(); }
  void clear() {
    index_.clear();
    sums_.clear();
  }
  std::size_t memory_usage() const {
    return index_.memory_usage() + sums_.capacity() * sizeof(Sum);
  }

 private:
  struct Sum {
    std::uint64_t key;
    std::uint64_t r, g, b, n;

    Rgb mean() const {
      const auto round = [this](std::uint64_t v) {
        return static_cast<std::uint8_t>((2 * v + n) / (2 * n));
      };
      return Rgb{round(r), round(g), round(b)};
    }
  };

  Grid<Key> grid_;
  detail::FlatIndex index_;
  std::vector<Sum> sums_;
};

}  // namespace knnocc
