// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The rating pass of a run: every scan of a source rated in order by one Mapper (Mapper::rate:
// the k-NN statistics, the robust model's ledger, the 2022 model's per-keyframe k-NN; the map is
// never touched) and written to a folder of rated keyframes (tiles/rated_store.hpp), from which
// tiles are mapped in any order and any process (tiles/tile_mapping.hpp).
//
// WorldScan is how `knnocc map` hands a scan to a Mapper, whether it inserts the scan or rates
// it: the same arithmetic in both, so a rated keyframe is what the one-process map integrates.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "../core/point3.hpp"
#include "../core/point_evidence.hpp"
#include "../io/scan_source.hpp"
#include "../io/sequence.hpp"
#include "../io/trajectory.hpp"
#include "../mapper.hpp"
#include "rated_store.hpp"

namespace knnocc::tiles {

/// One scan in the world frame as Mapper<Model> takes it: float points for the models that cast
/// them as given (OctoMap's model and the 2022 model, with liboctomap's float arithmetic), double
/// points for the models that keep a map point cloud (as the tracker keeps them), with the
/// map-point ids and the SLAM system's counters.
struct WorldScan {
  Point3d origin;
  std::vector<Point3f> f;
  std::vector<Point3d> d;
  std::vector<std::uint64_t> ids;
  std::vector<PointEvidence> evidence;

  /// `scan` (sensor frame, its pose sensor to world) moved to the world frame for MapperT; the
  /// scan's points may be taken (moved) when its pose is the identity.
  template <class MapperT>
  void load(io::Scan& scan) {
    origin = Point3d{scan.pose.t.x(), scan.pose.t.y(), scan.pose.t.z()};
    if constexpr (MapperT::uses_map_cloud) {
      io::keyframe_to_world(scan.pose, scan.cloud, -1.0, d, ids, &evidence);
    } else {
      std::vector<Point3f>& pts = scan.cloud.points;
      if (io::is_identity(scan.pose))
        f.swap(pts);
      else
        io::transform_to_world(scan.pose, pts, f);
    }
  }
  /// The number of points loaded.
  template <class MapperT>
  std::size_t size() const {
    return MapperT::uses_map_cloud ? d.size() : f.size();
  }
  template <class MapperT>
  KeyframeStats insert(MapperT& m) const {
    if constexpr (MapperT::uses_map_cloud)
      return m.insert_keyframe(origin, d, ids, evidence);
    else
      return m.insert_keyframe(origin, f);
  }
  template <class MapperT>
  KeyframeStats rate(MapperT& m, RatedKeyframe& out) const {
    if constexpr (MapperT::uses_map_cloud)
      return m.rate(origin, d, ids, evidence, out);
    else
      return m.rate(origin, f, {}, {}, out);
  }
};

/// Adds what one rated keyframe holds to `t`: its points, those that are not finite or whose
/// endpoint lies outside the key range within max_range (what ScanStats counts when it is
/// integrated), and the rating's counts.
template <class Key>
void count_rated(const Grid<Key>& grid, const RatedKeyframe& rk, const KeyframeStats& ks,
                 std::size_t points, double max_range, RatingTotals& t) {
  ++t.clouds;
  t.points += points;
  t.rated += ks.rated;
  t.rays += ks.rays;
  for (const Point3f& q : rk.points) {
    const knnocc::detail::EndpointFate fate =
        knnocc::detail::endpoint_fate(grid, q, rk.origin, max_range);
    t.nonfinite += fate == knnocc::detail::EndpointFate::nonfinite;
    t.out_of_range += fate == knnocc::detail::EndpointFate::out_of_range;
  }
}

/// The rating pass: scans [first, last) of `source`, each made ready by prepare(scan, i) (e.g.
/// cropped), rated by `mapper` and written to `out` in order; rated(i, stats, milliseconds of
/// the rating) after scan i. Returns the run's totals; `out` is finished (rated.txt written).
template <class MapperT, class Key>
RatingTotals rate_sequence(
    const io::ScanSource& source, std::size_t first, std::size_t last, MapperT& mapper,
    RatedStoreWriter<Key>& out, const std::function<void(io::Scan&, std::size_t)>& prepare,
    const std::function<void(std::size_t, const KeyframeStats&, double)>& rated) {
  RatingTotals totals;
  WorldScan w;
  RatedKeyframe rk;
  for (std::size_t i = first; i < last; ++i) {
    io::Scan scan = source.load(i);
    if (prepare) prepare(scan, i);
    w.load<MapperT>(scan);
    const auto t0 = std::chrono::steady_clock::now();
    const KeyframeStats ks = w.rate(mapper, rk);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    count_rated(mapper.map().grid(), rk, ks, w.size<MapperT>(), mapper.options().max_range, totals);
    out.add(rk);
    if (rated) rated(i, ks, ms);
  }
  out.finish(mapper.integration(), totals);
  return totals;
}

}  // namespace knnocc::tiles
