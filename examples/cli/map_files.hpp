#pragma once
// Map files as the tool's commands read them: OctoMap trees (.bt, .ot) and voxel lists (x y z
// logodds per line, as `knnocc map --out-voxels` writes them), whose resolution comes from --res.

#include <cmath>
#include <cstdio>
#include <string>

#include <knnocc/io/detail/file_text.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/voxel_list.hpp>
#include <knnocc/map/occupancy_map.hpp>

#include "map_outputs.hpp"  // lower_extension
#include "resource_limits.hpp"

namespace knnocc::cli {

/// A voxel list as a map at resolution `res`; every line must be a voxel centre of that grid
/// with a finite log-odds (io::Error naming the file and the voxel).
inline OccupancyMap<OcKey> read_voxel_list_map(const std::string& path, double res) {
  OccupancyMap<OcKey> map(res);
  const auto& g = map.grid();
  for (const io::VoxelRecord& v : io::read_voxel_list(path)) {
    OcKey k;
    const bool in_range = g.coord_to_key(v.x, v.y, v.z, k);
    if (!in_range || std::fabs(g.index_to_coord(k[0]) - v.x) > 1e-3 * res ||
        std::fabs(g.index_to_coord(k[1]) - v.y) > 1e-3 * res ||
        std::fabs(g.index_to_coord(k[2]) - v.z) > 1e-3 * res) {
      char text[200];
      std::snprintf(text, sizeof text, "(%.6f %.6f %.6f) is %s at --res %g (wrong --res?)", v.x,
                    v.y, v.z, in_range ? "not a voxel centre" : "outside the key range", res);
      throw io::Error(path, text);
    }
    if (!std::isfinite(v.logodds)) {
      char text[160];
      std::snprintf(text, sizeof text, "(%.6f %.6f %.6f) has a non-finite log-odds", v.x, v.y, v.z);
      throw io::Error(path, text);
    }
    map.set(k, v.logodds);
  }
  return map;
}

/// Whether `path` names an OctoMap tree (by extension).
inline bool is_tree_file(const std::string& path) {
  const std::string ext = lower_extension(path);
  return ext == ".bt" || ext == ".ot";
}

/// A tree, or a voxel list at `res` (> 0); a tree whose resolution differs from a given `res`
/// (> 0) is refused. With `colors`, a ColorOcTree's colours go there.
inline OccupancyMap<OcKey> read_map_file(const std::string& path, double res,
                                         io::OctreeColors* colors = nullptr) {
  if (colors) *colors = io::OctreeColors{};
  if (!is_tree_file(path)) return reading(path, [&] { return read_voxel_list_map(path, res); });
  OccupancyMap<OcKey> map = read_tree_checked(path, {}, colors);
  if (res > 0 && map.grid().resolution() != res)
    throw io::Error(path, "the tree's resolution is " +
                              io::detail::round_trip_text(map.grid().resolution()) +
                              ", not --res " + io::detail::round_trip_text(res));
  return map;
}

}  // namespace knnocc::cli
