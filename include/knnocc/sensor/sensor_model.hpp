// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The sensor-model concept: what Mapper (mapper.hpp) asks of its Model, the inverse sensor model
// that turns a keyframe's endpoints into log-odds updates.
//
// Every model has
//   float miss_logodds() const;      the update of a voxel a ray crosses (once per scan)
// and is of one of four kinds:
//   - fixed (OctoMapModel, paper eq 4): static constexpr bool uses_map_cloud = false (or absent),
//       float hit_logodds() const;   the update of a voxel holding endpoints (once per scan,
//                                    occupied wins over free)
//   - rated (KnnModel, eq 13-15): static constexpr bool uses_map_cloud = true,
//       EndpointRating rate(double s, const RunningNormal& distribution) const;
//                                    one endpoint's occupied log-odds (a voxel receives the sum
//                                    over its endpoints, eq 15) and whether it casts a free ray
//                                    (eq 14), from the endpoint's mean k-NN distance s (NaN when
//                                    it has none) and the distribution of the map cloud's s
//   - contextual (RobustModel): uses_map_cloud = true and, instead of rate(), the hook of
//       sensor/contextual_model.hpp (rate_keyframe, settle_keyframe): a stateful model that
//       rates a whole keyframe and keeps its own per-map-point state;
//   a rated or contextual model also names, so that Mapper can keep the map cloud's statistics
//   without being told how:
//       using tracker_type = ...;    the tracker Mapper keeps by default (knn/tracker_concept.hpp)
//       TrackerParams tracker_params() const;   optional: how that tracker is constructed
//     (a Mapper given a constructed tracker needs neither).
// The fourth kind, cloud-rated (Knn2022Model), rates each keyframe from its own cloud alone, with
// free space in two layers: static constexpr bool rates_cloud = true, see sensor/cloud_model.hpp.
// examples/custom_policies.cpp writes a rated model of its own.

#include <type_traits>
#include <utility>

#include "../stats/welford.hpp"
#include "cloud_model.hpp"
#include "contextual_model.hpp"
#include "endpoint_rating.hpp"

namespace knnocc {
namespace detail {

template <class M, class = void>
struct uses_map_cloud : std::false_type {};
template <class M>
struct uses_map_cloud<M, std::void_t<decltype(M::uses_map_cloud)>>
    : std::bool_constant<M::uses_map_cloud> {};

// Optional for a contextual model: `static constexpr bool map_cloud_without_ids = false` when it
// rates keyframes without map-point ids from nothing the map point cloud gives (RobustModel);
// Mapper then keeps no map point cloud for such keyframes.
template <class M, class = void>
struct map_cloud_without_ids : std::true_type {};
template <class M>
struct map_cloud_without_ids<M, std::void_t<decltype(M::map_cloud_without_ids)>>
    : std::bool_constant<M::map_cloud_without_ids> {};

template <class M, class = void>
struct has_miss_logodds : std::false_type {};
template <class M>
struct has_miss_logodds<
    M, std::void_t<decltype(static_cast<float>(std::declval<const M&>().miss_logodds()))>>
    : std::true_type {};

template <class M, class = void>
struct has_hit_logodds : std::false_type {};
template <class M>
struct has_hit_logodds<
    M, std::void_t<decltype(static_cast<float>(std::declval<const M&>().hit_logodds()))>>
    : std::true_type {};

template <class M, class = void>
struct has_rate : std::false_type {};
template <class M>
struct has_rate<
    M, std::enable_if_t<std::is_convertible_v<decltype(std::declval<const M&>().rate(
                                                  0.0, std::declval<const RunningNormal&>())),
                                              EndpointRating>>> : std::true_type {};

/// Compiles only for a type that meets the sensor-model concept with Mapper's Key and Tracker;
/// the message names what is missing.
template <class M, class Key, class Tracker>
constexpr bool check_sensor_model() {
  static_assert(has_miss_logodds<M>::value,
                "a sensor model needs `float miss_logodds() const` (sensor/sensor_model.hpp)");
  if constexpr (rates_cloud<M>::value) {
    check_cloud_model<M>();
  } else if constexpr (uses_map_cloud<M>::value) {
    if constexpr (is_contextual_v<M, Key, Tracker>) {
      check_contextual_model<M, Key, Tracker>();
    } else {
      static_assert(has_rate<M>::value,
                    "a sensor model with uses_map_cloud = true needs `EndpointRating rate(double "
                    "s, const RunningNormal&) const`, or the contextual hook rate_keyframe and "
                    "settle_keyframe (sensor/sensor_model.hpp, sensor/contextual_model.hpp)");
    }
  } else {
    static_assert(has_hit_logodds<M>::value,
                  "a sensor model without uses_map_cloud needs `float hit_logodds() const` "
                  "(sensor/sensor_model.hpp)");
  }
  return true;
}

}  // namespace detail
}  // namespace knnocc
