#pragma once
// What `knnocc map` does around the mapper, with or without --corrections: each scan made ready
// (world-frame clouds moved into the sensor frame, --crop), the checks on what was read (a cloud
// that misses the key range, --model robust without ids), and what the map files show besides the
// map (the up direction, the camera path, the voxels' colours: the mean colour of the points that
// hit each voxel, include/knnocc/insertion/ voxel_colors.hpp).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <knnocc/core/grid.hpp>
#include <knnocc/insertion/voxel_colors.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/trajectory.hpp>
#include <knnocc/map/occupancy_map.hpp>

#include "map_outputs.hpp"
#include "view_frame.hpp"

namespace knnocc::cli {

/// How scans are read and inserted (the options that change the points, not the model).
struct MapInput {
  std::string path;           ///< --input
  bool world_points = false;  ///< --points-frame world
  double crop = -1.0;         ///< --crop (< 0: none)
  double max_range = -1.0;    ///< --max-range (< 0: none)
  bool colors = true;         ///< false: --no-color
};

using io::crop_cloud;  // --crop (io/cloud.hpp)

/// Refuses a cloud of which fewer than 10 % of the finite points lie within the key range in
/// their own coordinates: whatever the pose, such a cloud is in other units or one of its
/// columns is not a coordinate. io::Error naming `file` and the likely cause. (Points that a pose
/// moves out of the key range are skipped and counted, as the map's notes say.)
template <class Key>
void check_key_range(const io::Cloud& cloud, const Grid<Key>& grid, const std::string& file) {
  const double limit = grid.max_coord();
  std::size_t finite = 0, out = 0;
  double worst = 0.0;
  for (const Point3f& p : cloud.points) {
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
    ++finite;
    const double m = std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
    if (m < limit) continue;
    ++out;
    worst = std::max(worst, m);
  }
  if (finite == 0 || out * 10 < finite * 9) return;
  char text[512];
  std::snprintf(text, sizeof text,
                "%zu of %zu points lie outside the map's key range (|c| < %g m at --res %g), up "
                "to %.3g m away: %s",
                out, finite, limit, grid.resolution(), worst,
                worst >= 1e8 && worst < 1e10
                    ? "values near 1e9 are Unix time stamps: is the first column a time stamp "
                      "('stamp x y z')? The file must hold x y z only"
                    : "is the cloud in millimetres (the map takes metres), or --res too fine?");
  throw io::Error(file, text);
}

/// The per-scan work and checks of a map run, and what its map files show.
class MapRun {
 public:
  explicit MapRun(MapInput input, double res) : in_(std::move(input)), colors_(res) {}

  const MapInput& input() const { return in_; }

  /// Scan i read from `file`: its points moved into the sensor frame (--points-frame world),
  /// checked against the key range, cropped; the up estimate and the path take its pose.
  template <class Key>
  void prepare(io::Scan& scan, const Grid<Key>& grid, const std::string& file) {
    if (in_.world_points) io::transform_to_sensor(scan.pose, scan.cloud.points);
    up_.add(scan.pose, scan.cloud.points);
    path_.push_back(Point3d{scan.pose.t.x(), scan.pose.t.y(), scan.pose.t.z()});
    check_key_range(scan.cloud, grid, file);
    crop_cloud(scan.cloud, in_.crop);
    points_ += scan.cloud.points.size();
  }

  /// --model robust without map-point ids: says once what runs instead.
  void note_missing_ids() {
    if (robust_without_ids_) return;
    robust_without_ids_ = true;
    std::fprintf(stderr,
                 "knnocc map: %s: warning: --model robust needs map-point ids (an `id` property) "
                 "and these clouds have none: it runs as OctoMap's model (hit 0.7, miss 0.4) and "
                 "keeps no map point cloud\n",
                 in_.path.c_str());
  }
  /// The title of the model that really ran.
  std::string title(const char* model_title) const {
    return robust_without_ids_ ? "OctoMap model (robust without ids)" : model_title;
  }

  /// The colours of one scan's points (world frame) seen from `origin`.
  template <class Origin, class Points>
  void add_colors(const Origin& origin, const Points& world,
                  const std::vector<knnocc::Rgb>& colors) {
    if (in_.colors && !colors.empty()) colors_.add_scan(origin, world, colors, in_.max_range);
  }
  /// An --init-map's colours (ColorOcTree), each voxel's as one point (unless --no-color).
  void add_tree_colors(const io::OctreeColors& tree) {
    if (in_.colors)
      for (const auto& [key, rgb] : tree.voxels) colors_.add(key, rgb);
  }
  const VoxelColors<OcKey>* colors() const { return colors_.empty() ? nullptr : &colors_; }

  /// Points after --crop, over all scans.
  std::size_t points() const { return points_; }

  /// What the map files show: `args`' up (or the estimate), the run's colours and path.
  MapFileContext file_context(const Args& args, const std::string& title) const {
    MapFileContext c;
    c.up = up_axis(args, up_.result());
    c.title = title;
    c.colors = colors();
    c.path = path_;
    return c;
  }

 private:
  MapInput in_;
  UpEstimator up_;
  std::vector<Point3d> path_;
  VoxelColors<OcKey> colors_;
  std::size_t points_ = 0;
  bool robust_without_ids_ = false;
};

}  // namespace knnocc::cli
