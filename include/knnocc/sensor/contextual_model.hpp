// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The contextual-model hook: how Mapper (mapper.hpp) hands a whole keyframe to a stateful sensor
// model that rates its points from more than their own mean k-NN distance (RobustModel: the
// keyframes that observed each map point, and those that should have and did not). The model
// keeps whatever it remembers per map point (its ledger); Mapper keeps nothing of the kind and
// holds no rule of any one model.
//
// A contextual model is a rated model (sensor/sensor_model.hpp: uses_map_cloud = true,
// `float miss_logodds() const`, a tracker_type) that has, instead of `rate(double s, ...)`,
//
//   template <class Key, class Tracker>
//   void rate_keyframe(const KeyframeView<Key, Tracker>& keyframe,
//                      std::vector<EndpointRating>& ratings);
//       before the scan: one rating per point of keyframe.points. Mapper sizes `ratings` and has
//       rated the points with id kNoId already ({0, true}: beyond max_range, non-finite or outside
//       the key range, only their truncated ray); the model rates the others and leaves those.
//       A rating {0, false} leaves the endpoint out of the scan: its voxel is not touched (an
//       update of 0 would make it known, and occupied).
//   template <class Key, class Tracker>
//   void settle_keyframe(const KeyframeView<Key, Tracker>& keyframe,
//                        const std::vector<EndpointRating>& ratings, std::vector<MapEdit>& edits);
//       then: the model learns from the keyframe and may append updates of single voxels to
//       `edits` (sensor/rated_keyframe.hpp: evidence of map points it held back and now accepts,
//       evidence it takes back), which are applied, in order, after the keyframe's scan.
//
// Both are called once per keyframe with a finite origin, in insertion order, before the
// keyframe's scan. A contextual model rates from the keyframe, the tracker and its own state,
// never from the map's values: that is what makes a rated keyframe (sensor/rated_keyframe.hpp)
// all a map or a tile of one needs. The model is copied when a Mapper is built from it
// (LiveMapper builds fresh Mappers from one pristine copy), so a model's state starts empty in
// every Mapper it is given to.
//
// Thread safety: a contextual model is written by its Mapper's insert; const queries are safe
// while no insert runs.

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

#include "../core/grid.hpp"
#include "../core/point3.hpp"
#include "../core/point_evidence.hpp"
#include "endpoint_rating.hpp"
#include "rated_keyframe.hpp"

namespace knnocc {

/// One keyframe as a contextual model sees it (read-only).
template <class Key, class Tracker>
struct KeyframeView {
  /// Keyframes Mapper inserted before this one (0 for the first; keyframes with a non-finite
  /// origin are not counted).
  std::size_t index;
  Point3d origin;                      ///< sensor position, world frame
  const std::vector<Point3d>& points;  ///< world frame
  /// One map-point id per point; kNoId (2^64 - 1) for a point that only casts its truncated ray.
  /// Keyframes without map-point ids (has_ids false) get the point's index as its id.
  const std::vector<std::uint64_t>& ids;
  bool has_ids;
  /// One per point when the source gives the SLAM system's counters (core/point_evidence.hpp),
  /// else empty.
  const std::vector<PointEvidence>& evidence;
  /// The map point cloud's k-NN statistics (empty for keyframes without ids when the model
  /// declares map_cloud_without_ids = false).
  const Tracker& tracker;
  const Grid<Key>& grid;  ///< the map's grid (keys of points)
};

namespace detail {

template <class M, class Key, class Tracker, class = void>
struct has_rate_keyframe : std::false_type {};
template <class M, class Key, class Tracker>
struct has_rate_keyframe<M, Key, Tracker,
                         std::void_t<decltype(std::declval<M&>().rate_keyframe(
                             std::declval<const KeyframeView<Key, Tracker>&>(),
                             std::declval<std::vector<EndpointRating>&>()))>> : std::true_type {};

template <class M, class Key, class Tracker, class = void>
struct has_settle_keyframe : std::false_type {};
template <class M, class Key, class Tracker>
struct has_settle_keyframe<M, Key, Tracker,
                           std::void_t<decltype(std::declval<M&>().settle_keyframe(
                               std::declval<const KeyframeView<Key, Tracker>&>(),
                               std::declval<const std::vector<EndpointRating>&>(),
                               std::declval<std::vector<MapEdit>&>()))>> : std::true_type {};

/// A model that declares either half of the hook is a contextual model.
template <class M, class Key, class Tracker>
inline constexpr bool is_contextual_v =
    has_rate_keyframe<M, Key, Tracker>::value || has_settle_keyframe<M, Key, Tracker>::value;

/// Compiles only for a model that has both halves of the hook; the message names what is missing.
template <class M, class Key, class Tracker>
constexpr bool check_contextual_model() {
  static_assert(has_rate_keyframe<M, Key, Tracker>::value,
                "a contextual sensor model needs `template <class Key, class Tracker> void "
                "rate_keyframe(const KeyframeView<Key, Tracker>&, std::vector<EndpointRating>&)` "
                "(sensor/contextual_model.hpp)");
  static_assert(has_settle_keyframe<M, Key, Tracker>::value,
                "a contextual sensor model needs `template <class Key, class Tracker> void "
                "settle_keyframe(const KeyframeView<Key, Tracker>&, const "
                "std::vector<EndpointRating>&, std::vector<MapEdit>&)` "
                "(sensor/contextual_model.hpp)");
  return true;
}

}  // namespace detail
}  // namespace knnocc
