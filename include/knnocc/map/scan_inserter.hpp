#pragma once
// ScanInserter: OctoMap's insertPointCloud(points, origin, max_range, discretize) on an
// OccupancyMap, with the same map as result.
//
// Per point p (sensor at origin o):
//   |p - o| <= max_range (or max_range < 0): the voxels from o up to p's voxel are free, p's voxel
//                                            is occupied;
//   otherwise: only the ray truncated at max_range frees voxels (its end voxel is not freed).
// Within one scan occupied wins over free and each voxel is updated at most once, so the result
// does not depend on point order. discretize = true first reduces the endpoints to the centres of
// their distinct voxels.
//
// Bad points never reach the map: NaN/Inf points are skipped and counted; an endpoint outside
// the key range gets no occupied update and no ray (OctoMap's behaviour), and is counted.
//
// The per-scan bookkeeping is a mask per touched brick (no hash set of keys), kept between scans
// so a warmed-up inserter allocates nothing per point. One inserter per thread.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "../core/config.hpp"
#include "../core/point3.hpp"
#include "../core/point_traits.hpp"
#include "../detail/flat_index.hpp"
#include "../raycast/dda.hpp"
#include "../sensor/octomap_model.hpp"
#include "occupancy_map.hpp"

namespace knnocc {

/// What one insert_point_cloud call did.
struct ScanStats {
  std::size_t points = 0;            ///< points given
  std::size_t nonfinite = 0;         ///< skipped: NaN or Inf coordinate
  std::size_t out_of_range = 0;      ///< endpoints outside the key range (no update from them)
  std::size_t beyond_max_range = 0;  ///< points farther than max_range (truncated free ray only)
  std::size_t ray_keys = 0;          ///< voxels visited by rays, before de-duplication
  std::size_t occupied_voxels = 0;   ///< voxels that received the hit update
  std::size_t free_voxels = 0;       ///< voxels that received the miss update
  bool origin_valid = true;          ///< false: origin NaN/Inf, nothing was inserted
};

template <class Key = OcKey, class Model = OctoMapModel>
class ScanInserter {
 public:
  using map_type = OccupancyMap<Key>;

  explicit ScanInserter(map_type& map, Model model = {}) : map_(&map), model_(model) {}

  const Model& model() const { return model_; }
  map_type& map() { return *map_; }

  /// Inserts one scan of world-frame points seen from `origin`. max_range < 0: no limit;
  /// max_range == 0 or NaN is rejected (std::invalid_argument; abort without exceptions).
  template <class Points, class Origin>
  ScanStats insert_point_cloud(const Origin& origin, const Points& points, double max_range = -1.0,
                               bool discretize = false) {
    if (max_range == 0.0 || std::isnan(max_range))
      detail::invalid_argument("max_range must be > 0, or < 0 for no limit");
    ScanStats st;
    const Point3f o{static_cast<float>(point_x(origin)), static_cast<float>(point_y(origin)),
                    static_cast<float>(point_z(origin))};
    if (!detail::finite(o)) {
      st.origin_valid = false;
      for (const auto& p : points) (void)p, ++st.points;
      return st;
    }
    const Grid<Key>& grid = map_->grid();
    if (discretize) {
      endpoints_.clear();
      for (const auto& p : points) {
        ++st.points;
        const Point3f q = to_point3f(p);
        Key k;
        if (!detail::finite(q))
          ++st.nonfinite;
        else if (!grid.point_to_key(q, k))
          ++st.out_of_range;
        else
          endpoints_.push_back(k.pack());
      }
      std::sort(endpoints_.begin(), endpoints_.end());
      endpoints_.erase(std::unique(endpoints_.begin(), endpoints_.end()), endpoints_.end());
      for (const std::uint64_t packed : endpoints_) {
        const Key k = Key::unpack(packed);
        integrate(o,
                  Point3f{static_cast<float>(grid.index_to_coord(k[0])),
                          static_cast<float>(grid.index_to_coord(k[1])),
                          static_cast<float>(grid.index_to_coord(k[2]))},
                  max_range, st);
      }
    } else {
      for (const auto& p : points) {
        ++st.points;
        const Point3f q = to_point3f(p);
        if (!detail::finite(q)) {
          ++st.nonfinite;
          continue;
        }
        integrate(o, q, max_range, st);
      }
    }
    apply(st);
    return st;
  }

 private:
  struct Scratch {
    std::uint64_t coord = 0;
    VoxelMask hit, miss;
  };

  template <class P>
  static Point3f to_point3f(const P& p) {
    return Point3f{static_cast<float>(point_x(p)), static_cast<float>(point_y(p)),
                   static_cast<float>(point_z(p))};
  }

  void integrate(const Point3f& o, const Point3f& p, double max_range, ScanStats& st) {
    const Grid<Key>& grid = map_->grid();
    auto mark_free = [&](const Key& k) {
      ++st.ray_keys;
      scratch_for(k).miss.set(BrickLayout<Key>::local_of(k));
    };
    if (max_range < 0.0 || detail::octomap_norm(p.x - o.x, p.y - o.y, p.z - o.z) <= max_range) {
      Key k;
      if (!grid.point_to_key(p, k)) {
        ++st.out_of_range;  // OctoMap's ray check fails on the same endpoint
        return;
      }
      for_each_ray_key(grid, o, p, mark_free);
      scratch_for(k).hit.set(BrickLayout<Key>::local_of(k));
    } else {
      ++st.beyond_max_range;
      for_each_ray_key(grid, o, truncate_ray(o, p, max_range), mark_free);
    }
  }

  Scratch& scratch_for(const Key& k) {
    const std::uint64_t c = BrickLayout<Key>::brick_of(k);
    if (last_ != detail::FlatIndex::kNone && c == last_coord_) return scratch_[last_];
    bool inserted = false;
    const auto next = static_cast<std::uint32_t>(used_);
    last_ = index_.find_or_insert(c, next, inserted);
    last_coord_ = c;
    if (inserted) {
      if (used_ == scratch_.size()) scratch_.emplace_back();
      Scratch& s = scratch_[used_++];
      s.coord = c;
      s.hit.clear();
      s.miss.clear();
    }
    return scratch_[last_];
  }

  // Occupied wins; every touched voxel gets exactly one update.
  void apply(ScanStats& st) {
    const float hit = model_.hit_logodds(), miss = model_.miss_logodds();
    for (std::size_t j = 0; j < used_; ++j) {
      Scratch& s = scratch_[j];
      auto& brick = map_->brick_for_write(s.coord);
      s.hit.for_each([&](int i) {
        map_->update_voxel(brick, i, hit);
        ++st.occupied_voxels;
      });
      for (std::size_t w = 0; w < s.miss.w.size(); ++w) s.miss.w[w] &= ~s.hit.w[w];
      s.miss.for_each([&](int i) {
        map_->update_voxel(brick, i, miss);
        ++st.free_voxels;
      });
    }
    used_ = 0;
    index_.clear();
    last_ = detail::FlatIndex::kNone;
  }

  map_type* map_;
  Model model_;
  detail::FlatIndex index_;       // brick coordinate -> scratch slot, this scan
  std::vector<Scratch> scratch_;  // grows to the largest scan seen, then reused
  std::size_t used_ = 0;
  std::uint64_t last_coord_ = 0;
  std::uint32_t last_ = detail::FlatIndex::kNone;
  std::vector<std::uint64_t> endpoints_;  // discretize: distinct endpoint keys
};

/// One-shot convenience: OctoMap's insertPointCloud with the default model. For many scans keep
/// a ScanInserter, which reuses its scratch memory.
template <class Key, class Points, class Origin>
ScanStats insert_point_cloud(OccupancyMap<Key>& map, const Origin& origin, const Points& points,
                             double max_range = -1.0, bool discretize = false,
                             OctoMapModel model = {}) {
  ScanInserter<Key, OctoMapModel> inserter(map, model);
  return inserter.insert_point_cloud(origin, points, max_range, discretize);
}

}  // namespace knnocc
