// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// LayeredScanInserter: the scan integrator of a cloud-rated sensor model (sensor/cloud_model.hpp,
// Knn2022Model): one keyframe whose free space comes in two layers (sensor/layered_rating.hpp).
//
// insert_layered(origin, points, ratings, layers, max_range), per point p (sensor at o), with
// OctoMap's rules for the rest (float points, the exact DDA of raycast/dda.hpp, max_range):
//   hit             p's voxel receives ratings[i].logodds, summed over the keyframe's hits in it
//                   (in double, in point order, rounded to float once; eq 15's per-node sum);
//   RayLayer::strong the voxels from o up to p's voxel (excluded) are strong-free;
//   RayLayer::weak  the same for the ray cut at layers.weak_range (when p lies farther; the cut
//                   ray's end voxel is not freed, as with OctoMap's max_range) are weak-free.
// Each voxel gets at most one update per keyframe: a voxel holding a hit gets its sum and is not
// freed; else a strong-free voxel gets layers.strong_miss; else a weak-free voxel gets
// layers.weak_miss. Points beyond max_range (>= 0) make no hit and cast their ray truncated at
// max_range (or sooner); NaN/Inf points are skipped, an endpoint within max_range outside the key
// range gets no hit and no ray (OctoMap's behaviour), each counted in ScanStats.
//
// With no weak rays the map is the one ScanInserter::insert_rated makes from the same hits and
// rays (tests/test_layered_scan_inserter.cpp compares them, and both with a dense sampling of the
// rays). The keys of a keyframe are gathered in sorted lists and applied in key order on the
// calling thread: simple rather than fast (the 2022 model is a baseline; ScanInserter is the
// fast path of the other models). The lists are kept between keyframes for their memory.
//
// Thread safety: one writer (of its map).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <optional>
#include <vector>

#include "../core/config.hpp"
#include "../core/point3.hpp"
#include "../core/point_traits.hpp"
#include "../map/occupancy_map.hpp"
#include "../raycast/dda.hpp"
#include "../sensor/layered_rating.hpp"
#include "detail/clip.hpp"
#include "scan_stats.hpp"

namespace knnocc {

template <class Key = OcKey>
class LayeredScanInserter {
 public:
  using map_type = OccupancyMap<Key>;

  /// The integrator concept's constructor (insertion/scan_integrator.hpp); the model is not kept
  /// (insert_layered is given the layers) and the keyframe is applied on the calling thread
  /// whatever `threads` (>= 1, else std::invalid_argument).
  template <class Model>
  LayeredScanInserter(map_type& map, const Model&, unsigned threads = 1) : map_(&map) {
    if (threads < 1) detail::invalid_argument("threads must be >= 1");
  }

  map_type& map() { return *map_; }

  /// Restricts the following keyframes to the voxels of `bounds`, as ScanInserter::set_clip:
  /// every voxel inside gets exactly the update of the whole keyframe, none outside is touched.
  void set_clip(const KeyBounds<Key>& bounds) {
    detail::KeyBox b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = bounds.lo[a];
      b.hi[a] = bounds.hi[a];
    }
    clip_ = bounds;
    clip_box_ = b;
  }
  void clear_clip() { clip_.reset(); }

  /// One keyframe: ratings[i] rates points[i] (same length, else std::invalid_argument);
  /// max_range < 0: no limit, 0 or NaN rejected.
  template <class Points, class Origin>
  ScanStats insert_layered(const Origin& origin, const Points& points,
                           const std::vector<LayeredRating>& ratings, const RayLayers& layers,
                           double max_range = -1.0) {
    detail::check_max_range(max_range);
    const auto n = static_cast<std::size_t>(std::distance(std::begin(points), std::end(points)));
    if (n != ratings.size())
      detail::invalid_argument("insert_layered: one rating per point expected");
    ScanStats st;
    const Point3f o = detail::to_point3f(origin);
    if (!detail::finite(o)) {
      st.origin_valid = false;
      st.points = n;
      return st;
    }
    hits_.clear();
    strong_.clear();
    weak_.clear();
    std::size_t i = 0;
    for (const auto& p : points) {
      collect(o, detail::to_point3f(p), ratings[i], layers, i, max_range, st);
      ++i;
    }
    apply(layers, st);
    st.chunks = 1;
    return st;
  }

 private:
  struct Hit {
    std::uint64_t key;
    std::size_t order;
    float logodds;
  };

  // One point: its hit and its ray's keys (OctoMap's computeUpdate for the point).
  void collect(const Point3f& o, const Point3f& q, const LayeredRating& r, const RayLayers& layers,
               std::size_t order, double max_range, ScanStats& st) {
    ++st.points;
    if (!detail::finite(q)) {
      ++st.nonfinite;
      return;
    }
    const double range = detail::octomap_norm(q.x - o.x, q.y - o.y, q.z - o.z);
    if (max_range < 0.0 || range <= max_range) {
      Key k;
      if (!map_->grid().point_to_key(q, k)) {
        ++st.out_of_range;
        return;
      }
      if (r.hit && (!clip_ || clip_->contains(k))) hits_.push_back({k.pack(), order, r.logodds});
    } else {
      ++st.beyond_max_range;
    }
    if (r.ray == RayLayer::none) return;
    double cut = r.ray == RayLayer::weak ? layers.weak_range : -1.0;
    if (max_range >= 0.0 && (cut < 0.0 || max_range < cut)) cut = max_range;
    const Point3f end = cut >= 0.0 && range > cut ? truncate_ray(o, q, cut) : q;
    std::vector<std::uint64_t>& out = r.ray == RayLayer::strong ? strong_ : weak_;
    auto add = [&](const Key& k) {
      out.push_back(k.pack());
      ++st.ray_keys;
    };
    if (clip_)
      detail::for_each_ray_key_in(map_->grid(), o, end, clip_box_, add);
    else
      for_each_ray_key(map_->grid(), o, end, add);
  }

  static void sort_unique(std::vector<std::uint64_t>& v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  }

  // The keyframe's updates, each voxel once, in key order: hits, then strong-free voxels that
  // hold no hit, then weak-free voxels that are neither.
  void apply(const RayLayers& layers, ScanStats& st) {
    std::sort(hits_.begin(), hits_.end(), [](const Hit& a, const Hit& b) {
      return a.key != b.key ? a.key < b.key : a.order < b.order;
    });
    hit_keys_.clear();
    for (std::size_t j = 0; j < hits_.size();) {
      const std::uint64_t key = hits_[j].key;
      double sum = 0.0;
      for (; j < hits_.size() && hits_[j].key == key; ++j) sum += hits_[j].logodds;
      map_->update(Key::unpack(key), static_cast<float>(sum));
      hit_keys_.push_back(key);
      ++st.occupied_voxels;
    }
    sort_unique(strong_);
    sort_unique(weak_);
    free_.clear();
    std::set_difference(strong_.begin(), strong_.end(), hit_keys_.begin(), hit_keys_.end(),
                        std::back_inserter(free_));
    for (const std::uint64_t key : free_) map_->update(Key::unpack(key), layers.strong_miss);
    st.free_voxels += free_.size();
    // Weak-free voxels: neither hit nor strong-free (strong_ still holds every strong key).
    free_.clear();
    std::set_difference(weak_.begin(), weak_.end(), strong_.begin(), strong_.end(),
                        std::back_inserter(free_));
    weak_.clear();
    std::set_difference(free_.begin(), free_.end(), hit_keys_.begin(), hit_keys_.end(),
                        std::back_inserter(weak_));
    for (const std::uint64_t key : weak_) map_->update(Key::unpack(key), layers.weak_miss);
    st.free_voxels += weak_.size();
  }

  map_type* map_;
  std::optional<KeyBounds<Key>> clip_;  // set_clip
  detail::KeyBox clip_box_{};           // the same as a KeyBox
  // The keyframe's hits and ray keys (packed), kept for their memory.
  std::vector<Hit> hits_;
  std::vector<std::uint64_t> hit_keys_, strong_, weak_, free_;
};

}  // namespace knnocc
