// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The scan-integrator concept: what Mapper (mapper.hpp) asks of the part that applies one scan's
// updates to the map (its Integrator; ScanInserter by default):
//   Integrator(OccupancyMap<Key>& map, const Model& model, unsigned threads);
//   for a fixed sensor model (sensor/sensor_model.hpp):
//     ScanStats insert_point_cloud(const Origin&, const Points&, double max_range, bool
//     discretize);
//   for a rated one:
//     ScanStats insert_rated(const Origin&, const Points&, const std::vector<EndpointRating>&,
//                            double max_range);
//   for a cloud-rated one (sensor/cloud_model.hpp):
//     ScanStats insert_layered(const Origin&, const Points&, const std::vector<LayeredRating>&,
//                              const RayLayers&, double max_range);
// with OctoMap's scan semantics: each voxel at most one update per scan, occupied wins over
// free, the voxels a ray crosses up to (not including) its end voxel are free.
// default_integrator_t<Key, Model> is Mapper's default: LayeredScanInserter for a cloud-rated
// model, ScanInserter otherwise.

#include <type_traits>
#include <utility>
#include <vector>

#include "../core/point3.hpp"
#include "../map/occupancy_map.hpp"
#include "../sensor/cloud_model.hpp"
#include "../sensor/endpoint_rating.hpp"
#include "../sensor/layered_rating.hpp"
#include "scan_stats.hpp"

namespace knnocc {
template <class Key, class Model>
class ScanInserter;
template <class Key>
class LayeredScanInserter;
}  // namespace knnocc

namespace knnocc::detail {

template <class Key, class Model, bool Layered = rates_cloud<Model>::value>
struct default_integrator {
  using type = ScanInserter<Key, Model>;
};
template <class Key, class Model>
struct default_integrator<Key, Model, true> {
  using type = LayeredScanInserter<Key>;
};
template <class Key, class Model>
using default_integrator_t = typename default_integrator<Key, Model>::type;

template <class I, class = void>
struct has_insert_point_cloud : std::false_type {};
template <class I>
struct has_insert_point_cloud<I, std::enable_if_t<std::is_convertible_v<
                                     decltype(std::declval<I&>().insert_point_cloud(
                                         std::declval<const Point3f&>(),
                                         std::declval<const std::vector<Point3f>&>(), 0.0, false)),
                                     ScanStats>>> : std::true_type {};

template <class I, class = void>
struct has_insert_rated : std::false_type {};
template <class I>
struct has_insert_rated<
    I, std::enable_if_t<std::is_convertible_v<
           decltype(std::declval<I&>().insert_rated(
               std::declval<const Point3d&>(), std::declval<const std::vector<Point3d>&>(),
               std::declval<const std::vector<EndpointRating>&>(), 0.0)),
           ScanStats>>> : std::true_type {};

template <class I, class = void>
struct has_insert_layered : std::false_type {};
template <class I>
struct has_insert_layered<
    I, std::enable_if_t<std::is_convertible_v<decltype(std::declval<I&>().insert_layered(
                                                  std::declval<const Point3d&>(),
                                                  std::declval<const std::vector<Point3d>&>(),
                                                  std::declval<const std::vector<LayeredRating>&>(),
                                                  std::declval<const RayLayers&>(), 0.0)),
                                              ScanStats>>> : std::true_type {};

/// Compiles only for a type that meets the scan-integrator concept for Model (cloud-rated, rated
/// or fixed); the message names what is missing.
template <class I, class Key, class Model, bool Rated>
constexpr bool check_scan_integrator() {
  static_assert(std::is_constructible_v<I, OccupancyMap<Key>&, const Model&, unsigned>,
                "a scan integrator needs a constructor (OccupancyMap<Key>&, const Model&, "
                "unsigned threads) (insertion/scan_integrator.hpp)");
  if constexpr (rates_cloud<Model>::value) {
    static_assert(has_insert_layered<I>::value,
                  "a scan integrator for a cloud-rated sensor model needs `ScanStats "
                  "insert_layered(origin, points, const std::vector<LayeredRating>&, const "
                  "RayLayers&, double max_range)` (insertion/scan_integrator.hpp)");
  } else if constexpr (Rated) {
    static_assert(
        has_insert_rated<I>::value,
        "a scan integrator for a rated sensor model needs `ScanStats insert_rated(origin, "
        "points, const std::vector<EndpointRating>&, double max_range)` "
        "(insertion/scan_integrator.hpp)");
  } else {
    static_assert(has_insert_point_cloud<I>::value,
                  "a scan integrator for a fixed sensor model needs `ScanStats "
                  "insert_point_cloud(origin, points, double max_range, bool discretize)` "
                  "(insertion/scan_integrator.hpp)");
  }
  return true;
}

}  // namespace knnocc::detail
