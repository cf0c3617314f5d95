// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// RatedKeyframe: one keyframe as its sensor model has rated it, before any ray is cast. It holds
// all that integrating the keyframe into a map needs and nothing of the k-NN statistics or of a
// model's own state: Mapper::rate makes one, Mapper::integrate and TileIntegrator
// (tiles/tile_integrator.hpp) put it into a map. Rating is sequential (keyframe t is rated from
// the map point cloud of keyframes 0..t); integration is per voxel, so a tile of a large map can
// integrate the rated keyframes that reach it in another process and equal the same region of the
// one-process map.
//
// Three kinds, one per family of models, each with the integration's constants in
// IntegrationParams (the same for every keyframe of a run):
//   fixed    (OctoMapModel): the points only; every endpoint's voxel gets `hit`, every voxel a
//            ray crosses `miss` (ScanInserter::insert_point_cloud, with max_range and discretize);
//   rated    (KnnModel, RobustModel): one EndpointRating per point, eq 15's per-voxel sums and the
//            rays of the reliable endpoints, free voxels get `miss` (ScanInserter::insert_rated);
//   layered  (Knn2022Model): one LayeredRating per point, two layers of free space
//            (LayeredScanInserter::insert_layered with `layers`).
// A contextual model also updates voxels after the scan (RobustModel: the evidence of map points
// it now believes, or takes back): those updates are the keyframe's `edits`, applied in order
// after its scan.

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "../core/point3.hpp"
#include "../map/occupancy_map.hpp"
#include "endpoint_rating.hpp"
#include "layered_rating.hpp"

namespace knnocc {

enum class RatingKind : std::uint8_t {
  fixed,    ///< the model's hit and miss for every endpoint and ray (OctoMap's model)
  rated,    ///< an EndpointRating per point (eq 13-15)
  layered,  ///< a LayeredRating per point, two layers of free space (the 2022 model)
};

/// One voxel's update after a keyframe's scan, made by a contextual model.
struct MapEdit {
  std::uint64_t key = 0;  ///< the voxel (Key::pack())
  float delta = 0.0f;     ///< OccupancyMap::update(key, delta)
  /// Evidence taken back from a voxel that no believed point holds any more: when the update
  /// leaves it occupied (clamping kept part of the evidence, or the evidence alone made it known
  /// at 0), it is set just below the occupancy threshold.
  bool lower_if_occupied = false;
};

/// Applies one edit to `map`.
template <class Key>
void apply_edit(OccupancyMap<Key>& map, const MapEdit& e) {
  const Key k = Key::unpack(e.key);
  const float v = map.update(k, e.delta);
  if (e.lower_if_occupied && map.is_occupied(v))
    map.set(k, std::nextafter(map.params().occupancy_threshold,
                              -std::numeric_limits<float>::infinity()));
}

/// One rated keyframe (see the file comment).
struct RatedKeyframe {
  RatingKind kind = RatingKind::fixed;
  Point3f origin{};             ///< sensor position, world frame (non-finite: nothing inserted)
  std::vector<Point3f> points;  ///< world frame, as the integrator casts them
  std::vector<EndpointRating> ratings;  ///< rated: one per point
  std::vector<LayeredRating> layered;   ///< layered: one per point
  std::vector<MapEdit> edits;           ///< after the scan, in order

  void clear() {
    points.clear();
    ratings.clear();
    layered.clear();
    edits.clear();
  }
};

/// The constants of a run's integration (Mapper::integration()): with a run's rated keyframes,
/// all a map or a tile needs.
struct IntegrationParams {
  RatingKind kind = RatingKind::fixed;
  float hit = 0.0f;           ///< fixed: every endpoint's voxel
  float miss = 0.0f;          ///< fixed and rated: every voxel a ray crosses (layered: layers)
  RayLayers layers;           ///< layered
  double max_range = -1.0;    ///< OctoMap's max range (< 0: none)
  bool discretize = false;    ///< fixed: endpoints reduced to their distinct voxels first
  OccupancyParams occupancy;  ///< the map's clamping and threshold
};

}  // namespace knnocc
