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
// with OctoMap's scan semantics: each voxel at most one update per scan, occupied wins over
// free, the voxels a ray crosses up to (not including) its end voxel are free.

#include <type_traits>
#include <utility>
#include <vector>

#include "../core/point3.hpp"
#include "../map/occupancy_map.hpp"
#include "../sensor/endpoint_rating.hpp"
#include "scan_stats.hpp"

namespace knnocc::detail {

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

/// Compiles only for a type that meets the scan-integrator concept for Model (rated or fixed); the
/// message names what is missing.
template <class I, class Key, class Model, bool Rated>
constexpr bool check_scan_integrator() {
  static_assert(std::is_constructible_v<I, OccupancyMap<Key>&, const Model&, unsigned>,
                "a scan integrator needs a constructor (OccupancyMap<Key>&, const Model&, "
                "unsigned threads) (insertion/scan_integrator.hpp)");
  if constexpr (Rated) {
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
