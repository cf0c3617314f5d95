// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// LayeredRating: what a cloud-rated sensor model (sensor/cloud_model.hpp, e.g. Knn2022Model) says
// about one point of a keyframe; LayeredScanInserter::insert_layered applies a keyframe of them.
// Free space comes in two layers: a strong one (rays to the points the model trusts, e.g.
// OctoMap's miss probability) and a weak one (rays cut at a range, a weaker miss probability).

#include <cstdint>

namespace knnocc {

/// Which free-space layer a point's ray updates.
enum class RayLayer : std::uint8_t {
  none,    ///< no ray
  strong,  ///< a ray to the point (truncated at max_range); its voxels get RayLayers::strong_miss
  weak,    ///< a ray cut at RayLayers::weak_range; its voxels get RayLayers::weak_miss
};

struct LayeredRating {
  float logodds = 0.0f;           ///< added to the point's voxel (summed per voxel) when `hit`
  bool hit = false;               ///< the point marks its voxel (never freed by this keyframe)
  RayLayer ray = RayLayer::none;  ///< the layer its ray updates
};

/// The two layers' updates, the same for every point of a keyframe.
struct RayLayers {
  float strong_miss = 0.0f;  ///< log-odds of a voxel a strong ray crosses
  float weak_miss = 0.0f;    ///< log-odds of a voxel only weak rays cross
  double weak_range = -1.0;  ///< weak rays end this far from the sensor (< 0: at their point)
};

}  // namespace knnocc
