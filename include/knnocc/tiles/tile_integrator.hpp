// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// TileIntegrator: one tile of a larger map, built from rated keyframes (sensor/rated_keyframe.hpp)
// without any k-NN state: each keyframe's scan restricted to the tile (ScanInserter::set_clip,
// LayeredScanInserter::set_clip), then its edits that fall inside the tile.
//
// Why this is the one-process map: a voxel's value is a fold, in keyframe order, of at most one
// update per keyframe (occupied wins within a keyframe, then clamping), and the clipped scan gives
// every voxel of the tile exactly the update of the whole scan, its rays walked exactly as the
// whole scan walks them. Given the rated keyframes of a run in order, the tile equals the same
// region of the map Mapper builds from them in one process, bit for bit
// (tests/test_tile_integrator.cpp, tests/test_tile_mapping.cpp).
// A keyframe whose keyframe_reach() misses the tile changes nothing in it and may be left out.
//
// Thread safety: one writer (of its own map).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>

#include "../core/grid.hpp"
#include "../core/key.hpp"
#include "../insertion/layered_scan_inserter.hpp"
#include "../insertion/scan_inserter.hpp"
#include "../map/occupancy_map.hpp"
#include "../sensor/octomap_model.hpp"
#include "../sensor/rated_keyframe.hpp"

namespace knnocc {

template <class Key = OcKey>
class TileIntegrator {
 public:
  using map_type = OccupancyMap<Key>;

  /// A new, empty tile `tile` of a map at `resolution`, integrating keyframes rated under `params`
  /// (Mapper::integration()); `threads` walk each scan's rays (the tile is the same).
  TileIntegrator(double resolution, const IntegrationParams& params, const KeyBounds<Key>& tile,
                 unsigned threads = 1)
      : params_(params),
        tile_(tile),
        map_(std::make_unique<map_type>(resolution, params.occupancy)),
        scans_(*map_, OctoMapModel{params.hit, params.miss}, threads),
        layered_(*map_, OctoMapModel{}, 1) {
    detail::check_max_range(params.max_range);
    scans_.set_clip(tile);
    layered_.set_clip(tile);
  }

  const map_type& map() const { return *map_; }
  map_type& map() { return *map_; }
  const KeyBounds<Key>& bounds() const { return tile_; }
  const IntegrationParams& params() const { return params_; }

  /// One rated keyframe of the run, in the run's order (std::invalid_argument for a keyframe of
  /// another kind than the params'). Returns the clipped scan's statistics.
  ScanStats integrate(const RatedKeyframe& rk) {
    if (rk.kind != params_.kind)
      detail::invalid_argument("TileIntegrator: a keyframe of another kind of model");
    ScanStats st;
    switch (rk.kind) {
      case RatingKind::fixed:
        st = scans_.insert_point_cloud(rk.origin, rk.points, params_.max_range, params_.discretize);
        break;
      case RatingKind::rated:
        st = scans_.insert_rated(rk.origin, rk.points, rk.ratings, params_.max_range);
        break;
      case RatingKind::layered:
        st = layered_.insert_layered(rk.origin, rk.points, rk.layered, params_.layers,
                                     params_.max_range);
        break;
    }
    for (const MapEdit& e : rk.edits)
      if (tile_.contains(Key::unpack(e.key))) apply_edit(*map_, e);
    return st;
  }

 private:
  IntegrationParams params_;
  KeyBounds<Key> tile_;
  std::unique_ptr<map_type> map_;  // on the heap: the inserters point at it
  ScanInserter<Key, OctoMapModel> scans_;
  LayeredScanInserter<Key> layered_;
};

/// The keys a rated keyframe can update, or nullopt when it updates none: its origin's and points'
/// voxels (every ray ends within the box of its origin and its point: truncation at max_range or
/// at a weak layer's range only shortens it), grown by one voxel (how far rounding may carry a walk
/// past its end voxel) and by what float rounding of the truncated end points may move them, and
/// its edits' voxels. A keyframe with a non-finite origin updates nothing.
template <class Key>
std::optional<KeyBounds<Key>> keyframe_reach(const Grid<Key>& grid, const RatedKeyframe& rk) {
  const Point3f& o = rk.origin;
  std::optional<KeyBounds<Key>> out;
  auto add_key = [&](const Key& k) {
    if (!out) {
      out = KeyBounds<Key>{k, k};
      return;
    }
    for (int a = 0; a < 3; ++a) {
      out->lo[a] = std::min(out->lo[a], k[a]);
      out->hi[a] = std::max(out->hi[a], k[a]);
    }
  };
  if (std::isfinite(o.x) && std::isfinite(o.y) && std::isfinite(o.z) && !rk.points.empty()) {
    double lo[3] = {o.x, o.y, o.z}, hi[3] = {o.x, o.y, o.z};
    bool any = false;
    for (const Point3f& p : rk.points) {
      if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
      const double c[3] = {p.x, p.y, p.z};
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], c[a]);
        hi[a] = std::max(hi[a], c[a]);
      }
      any = true;
    }
    if (any) {
      // Float rounding of an end point is a few units in the last place of its coordinates.
      double extent = 0.0;
      for (int a = 0; a < 3; ++a) extent = std::max({extent, std::fabs(lo[a]), std::fabs(hi[a])});
      const double margin = grid.resolution() + 8.0 * extent * 0x1p-23;
      const double first = grid.min_coord(), last = std::nextafter(grid.max_coord(), 0.0);
      Key klo, khi;
      grid.coord_to_key(std::clamp(lo[0] - margin, first, last),
                        std::clamp(lo[1] - margin, first, last),
                        std::clamp(lo[2] - margin, first, last), klo);
      grid.coord_to_key(std::clamp(hi[0] + margin, first, last),
                        std::clamp(hi[1] + margin, first, last),
                        std::clamp(hi[2] + margin, first, last), khi);
      add_key(klo);
      add_key(khi);
    }
  }
  for (const MapEdit& e : rk.edits) add_key(Key::unpack(e.key));
  return out;
}

}  // namespace knnocc
