// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The authors' counting (Miao et al., Sensors 22(1):139, 2022): a map against a reference map,
// cell by cell, for every finest-level cell known in both, with a tolerance of one voxel that
// each reference cell grants once.
//
//   TP  occupied in the map and matched to an occupied reference cell within +-1 voxel along each
//       axis (the cell itself or one of its 26 neighbours); the matching is one-to-one
//   FP  occupied in the map and left unmatched
//   FN  free in the map, occupied in the reference, and no TP matched to it
//   TN  free in the map and free in the reference
// A free map cell that is occupied in the reference but was matched (its surface is in the map,
// one voxel off) counts in none of them. The reference cell a TP is matched to may be unknown in
// the map: the tolerance is about where the map put the surface.
//
// Matching: a maximum bipartite matching (Hopcroft-Karp), not a greedy pass, so the counts do not
// depend on the order cells are visited in. Among the maximum matchings it takes one that covers
// as many FN candidates (reference-occupied cells the map calls free) as any matching can: TP is
// the largest number of occupied map cells that can be matched one-to-one, FN the smallest number
// of FN candidates that must stay unmatched; both are properties of the two maps, not of a
// visiting order (eval/detail/bipartite_matching.hpp says why the two stages give both). The
// authors' code was not found; a greedy matching in their order can give fewer TP, never more.
//
// The reference is any type with (the voxel-reference concept)
//   bool known(const Key&) const;      the reference says something about the cell
//   bool occupied(const Key&) const;   it is occupied there (asked only for known cells)
// MapVoxels (another map), ShapeVoxels below (reference shapes voxelised, the ground band left
// out) and PointVoxels
// (eval/reference_points.hpp: a reference point set) are three.
//
// Thread safety: const functions of const objects; may run concurrently.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "../core/key.hpp"
#include "../core/point3.hpp"
#include "../map/occupancy_map.hpp"
#include "detail/bipartite_matching.hpp"
#include "reference.hpp"

namespace knnocc::eval {

struct ConfusionCounts {
  std::size_t tp = 0, fp = 0, tn = 0, fn = 0;

  double precision() const { return tp + fp ? double(tp) / double(tp + fp) : 0.0; }
  double recall() const { return tp + fn ? double(tp) / double(tp + fn) : 0.0; }
  /// 2 TP / (2 TP + FP + FN); 0 when all three are 0.
  double f1() const {
    const double d = 2.0 * double(tp) + double(fp) + double(fn);
    return d > 0 ? 2.0 * double(tp) / d : 0.0;
  }
  /// Matthews correlation coefficient; 0 when a marginal is empty.
  double mcc() const {
    const double a = double(tp), b = double(fp), c = double(tn), d = double(fn);
    const double den = (a + b) * (a + d) * (c + b) * (c + d);
    return den > 0 ? (a * c - b * d) / std::sqrt(den) : 0.0;
  }
  ConfusionCounts& operator+=(const ConfusionCounts& o) {
    tp += o.tp;
    fp += o.fp;
    tn += o.tn;
    fn += o.fn;
    return *this;
  }
};

struct ConfusionOptions {
  /// Occupied in the map iff log-odds >= this; empty: the map's own occupancy threshold (an
  /// evaluation over thresholds maps once and counts several times).
  std::optional<float> threshold;
};

/// A map as a voxel reference: known and occupied as the map says.
template <class Key>
class MapVoxels {
 public:
  explicit MapVoxels(const OccupancyMap<Key>& map) : map_(&map) {}
  bool known(const Key& k) const { return map_->is_known(k); }
  bool occupied(const Key& k) const { return map_->is_occupied(k).value_or(false); }

 private:
  const OccupancyMap<Key>* map_;
};

/// Reference shapes (eval/reference.hpp) voxelised on a grid: a cell is occupied when its closed
/// box meets a solid (on its surface or inside it: carving the inside is wrong, though the camera
/// never sees it), free otherwise. With a ground plane, cells whose centre lies less than
/// `ground_band` (0.3 m, Table 1's band, MetricOptions) above it, or below it, are unknown: the
/// ground's cells are judged by neither count. The plane lies on voxel borders, so a ray that
/// grazes it carves a layer that merely touches it, and the ground's FN would outnumber every
/// other count (on the tree scene, 1,300 of OctoMap's 1,570 FN for 60 keyframes).
template <class Key>
class ShapeVoxels {
 public:
  ShapeVoxels(const Reference& ref, const Grid<Key>& grid, double ground_band = 0.3)
      : ref_(&ref), grid_(grid), band_(ground_band) {
    ref.bounds(grid.resolution(), lo_, hi_);  // no solid reaches a voxel centred outside these
  }
  bool known(const Key& k) const {
    return !ref_->has_ground || grid_.index_to_coord(k[2]) - ref_->ground_z >= band_;
  }
  bool occupied(const Key& k) const {
    const double r = grid_.resolution();
    const Point3d c{grid_.index_to_coord(k[0]), grid_.index_to_coord(k[1]),
                    grid_.index_to_coord(k[2])};
    if (!(c.x >= lo_.x && c.x <= hi_.x && c.y >= lo_.y && c.y <= hi_.y && c.z >= lo_.z &&
          c.z <= hi_.z))
      return false;
    return ref_->relation({c.x - r / 2, c.y - r / 2, c.z - r / 2},
                          {c.x + r / 2, c.y + r / 2, c.z + r / 2}) != BoxRelation::outside;
  }

 private:
  const Reference* ref_;
  Grid<Key> grid_;
  double band_;
  Point3d lo_, hi_;  // the solids' bounding box grown by a voxel
};

namespace detail {

// The 27 offsets of the tolerance, the cell itself first.
inline const std::vector<std::array<int, 3>>& tolerance_offsets() {
  static const std::vector<std::array<int, 3>> offsets = [] {
    std::vector<std::array<int, 3>> o{{0, 0, 0}};
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz)
          if (dx || dy || dz) o.push_back({dx, dy, dz});
    return o;
  }();
  return offsets;
}

}  // namespace detail

/// The authors' counting of `map` against `ref` (a voxel reference on the map's grid) at several
/// occupancy thresholds (log-odds: occupied iff >= threshold) at once, one count per threshold;
/// the map's cells are classified against the reference, and the edges found, once.
template <class Key, class Ref>
std::vector<ConfusionCounts> count_confusion(const OccupancyMap<Key>& map, const Ref& ref,
                                             const std::vector<float>& thresholds) {
  if (thresholds.empty()) return {};
  const float lowest = *std::min_element(thresholds.begin(), thresholds.end());
  // The cells known in both: the ones occupied at the lowest threshold (the only ones that can
  // be left vertices), and the values of the free ones occupied in the reference.
  struct Left {
    Key key;
    float value;
    bool ref_occupied;
  };
  std::vector<Left> occupied;
  std::vector<float> free_in_ref_occupied, free_in_ref_free;
  map.for_each_voxel([&](const Key& k, float v) {
    if (!ref.known(k)) return;
    const bool o = ref.occupied(k);
    if (v >= lowest)
      occupied.push_back({k, v, o});
    else
      (o ? free_in_ref_occupied : free_in_ref_free).push_back(v);
  });
  // A fixed order, for reproducible matchings.
  std::sort(occupied.begin(), occupied.end(),
            [](const Left& a, const Left& b) { return a.key.pack() < b.key.pack(); });

  // Right vertices: occupied reference cells within the tolerance of those cells, numbered in
  // key order, with their value in the map (NaN: unknown there); the edges once.
  std::vector<std::uint64_t> near;
  for (const Left& l : occupied)
    for (const auto& d : detail::tolerance_offsets()) {
      Key n;
      if (shifted_key(l.key, d[0], d[1], d[2], n)) near.push_back(n.pack());
    }
  std::sort(near.begin(), near.end());
  near.erase(std::unique(near.begin(), near.end()), near.end());
  constexpr std::uint32_t kNone = eval::detail::BipartiteMatching::kNone;
  std::vector<std::uint32_t> right(near.size(), kNone);  // index in near -> right vertex
  std::vector<float> right_value;
  for (std::size_t i = 0; i < near.size(); ++i) {
    const Key n = Key::unpack(near[i]);
    if (!ref.known(n) || !ref.occupied(n)) continue;
    right[i] = static_cast<std::uint32_t>(right_value.size());
    const auto v = map.logodds(n);
    right_value.push_back(v ? *v : std::numeric_limits<float>::quiet_NaN());
  }
  std::vector<std::uint32_t> all_offsets{0}, all_adj;
  for (const Left& l : occupied) {
    for (const auto& d : detail::tolerance_offsets()) {
      Key n;
      if (!shifted_key(l.key, d[0], d[1], d[2], n)) continue;
      const auto i = std::lower_bound(near.begin(), near.end(), n.pack()) - near.begin();
      if (right[static_cast<std::size_t>(i)] != kNone)
        all_adj.push_back(right[static_cast<std::size_t>(i)]);
    }
    all_offsets.push_back(static_cast<std::uint32_t>(all_adj.size()));
  }

  std::vector<ConfusionCounts> out;
  for (const float threshold : thresholds) {
    ConfusionCounts c;
    std::size_t candidates = 0;  // free map cells occupied in the reference
    for (const float v : free_in_ref_occupied) candidates += v < threshold;
    c.tn = free_in_ref_free.size();
    std::vector<std::uint32_t> offsets{0}, adj;
    for (std::size_t u = 0; u < occupied.size(); ++u) {
      if (occupied[u].value >= threshold) {
        adj.insert(adj.end(), all_adj.begin() + all_offsets[u],
                   all_adj.begin() + all_offsets[u + 1]);
        offsets.push_back(static_cast<std::uint32_t>(adj.size()));
      } else if (occupied[u].ref_occupied) {
        ++candidates;
      } else {
        ++c.tn;
      }
    }
    std::vector<unsigned char> is_candidate(right_value.size());  // free in the map
    for (std::size_t v = 0; v < right_value.size(); ++v)
      is_candidate[v] = right_value[v] < threshold;
    const std::size_t left = offsets.size() - 1;
    eval::detail::BipartiteMatching m(right_value.size(), std::move(offsets), std::move(adj));
    m.augment([&](std::uint32_t v) { return is_candidate[v] != 0; });  // FN candidates first
    m.augment([](std::uint32_t) { return true; });
    c.tp = m.size();
    c.fp = left - c.tp;
    std::size_t covered = 0;
    for (std::size_t v = 0; v < is_candidate.size(); ++v)
      covered += is_candidate[v] && m.match_of_right(v) != kNone;
    c.fn = candidates - covered;
    out.push_back(c);
  }
  return out;
}

/// The authors' counting of `map` against `ref` (a voxel reference on the map's grid).
template <class Key, class Ref>
ConfusionCounts count_confusion(const OccupancyMap<Key>& map, const Ref& ref,
                                const ConfusionOptions& opt = {}) {
  return count_confusion(
      map, ref,
      std::vector<float>{opt.threshold ? *opt.threshold : map.params().occupancy_threshold})[0];
}

}  // namespace knnocc::eval
