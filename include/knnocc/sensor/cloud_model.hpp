// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The cloud-rated sensor-model concept: a model that rates each keyframe from that keyframe's own
// cloud alone (Knn2022Model: the mean distance of a point to its k nearest neighbours in the same
// keyframe), with free space in two layers (sensor/layered_rating.hpp). Mapper keeps no map point
// cloud and no tracker for it; its integrator is LayeredScanInserter
// (insertion/layered_scan_inserter.hpp). A cloud-rated model has
//
//   static constexpr bool rates_cloud = true;
//   float miss_logodds() const;          the strong layer's update (RayLayers::strong_miss)
//   RayLayers ray_layers() const;        both layers' updates and the weak rays' range
//   void rate_cloud(const Point3d& origin, const std::vector<Point3d>& points,
//                   std::vector<LayeredRating>& ratings);
//       one rating per point (world frame, seen from origin), called once per keyframe with a
//       finite origin, in insertion order; the model may learn from the keyframe (running
//       statistics), so it is not const.
//
// A model is copied when a Mapper is built from it: its state starts with the Mapper's copy.

#include <type_traits>
#include <utility>
#include <vector>

#include "../core/point3.hpp"
#include "layered_rating.hpp"

namespace knnocc::detail {

template <class M, class = void>
struct rates_cloud : std::false_type {};
template <class M>
struct rates_cloud<M, std::void_t<decltype(M::rates_cloud)>> : std::bool_constant<M::rates_cloud> {
};

template <class M, class = void>
struct has_rate_cloud : std::false_type {};
template <class M>
struct has_rate_cloud<
    M, std::void_t<decltype(std::declval<M&>().rate_cloud(
           std::declval<const Point3d&>(), std::declval<const std::vector<Point3d>&>(),
           std::declval<std::vector<LayeredRating>&>()))>> : std::true_type {};

template <class M, class = void>
struct has_ray_layers : std::false_type {};
template <class M>
struct has_ray_layers<M, std::enable_if_t<std::is_convertible_v<
                             decltype(std::declval<const M&>().ray_layers()), RayLayers>>>
    : std::true_type {};

/// Compiles only for a model that meets the cloud-rated concept; the message names what is
/// missing.
template <class M>
constexpr bool check_cloud_model() {
  static_assert(has_rate_cloud<M>::value,
                "a sensor model with rates_cloud = true needs `void rate_cloud(const Point3d& "
                "origin, const std::vector<Point3d>& points, std::vector<LayeredRating>&)` "
                "(sensor/cloud_model.hpp)");
  static_assert(has_ray_layers<M>::value,
                "a sensor model with rates_cloud = true needs `RayLayers ray_layers() const` "
                "(sensor/cloud_model.hpp)");
  return true;
}

}  // namespace knnocc::detail
