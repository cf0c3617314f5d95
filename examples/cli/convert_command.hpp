#pragma once
// knnocc convert IN OUT: maps and clouds from one format to another, chosen by extension.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <knnocc/io/kitti.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/pcd.hpp>
#include <knnocc/io/ply.hpp>
#include <knnocc/io/point_file.hpp>
#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/voxel_export.hpp>
#include <knnocc/io/voxel_list.hpp>
#include <knnocc/io/xyz.hpp>

#include "args.hpp"
#include "input_guard.hpp"
#include "map_outputs.hpp"
#include "output_set.hpp"
#include "progress.hpp"
#include "resource_limits.hpp"

namespace knnocc::cli {

inline const char* convert_help() {
  return R"(usage: knnocc convert IN OUT [options]

Converts a map or a point cloud; the formats follow from the file extensions.
maps:
  IN   .bt .ot (OctoMap trees), or a voxel list (x y z logodds per line, as --out-voxels
       writes) named .voxels or given with --voxel-list, which needs --res
  OUT  .bt .ot             OctoMap trees (knnocc convert a.bt b.bt rewrites a.bt byte for byte)
       .voxels .txt        voxel list, sorted by x, y, z (--voxels, default all)
       .ply                voxels as points (colour = height, property logodds) or cubes
       .pcd .xyz .bin      voxel centres as a point cloud (--voxels, default occupied)
       .png                top and side views, coloured by height
clouds:
  IN   .ply .pcd .xyz .dat .txt .bin (KITTI), or an OctoMap .graph / a sequence folder (all
       scans moved to the world frame and merged)
  OUT  .ply .pcd .xyz .txt .bin (ids are kept by .ply and .pcd)
A cloud becomes a map with a sensor model, not here: knnocc map --input IN --res R --out-bt OUT.
options:
  --res R               voxel edge of a voxel-list input
  --voxel-list          read IN as a voxel list whatever its extension
  --voxels WHICH        occupied, free or all: which voxels a map turns into points / lines
  --ply-cubes           .ply from a map: one cube per voxel instead of one point
  --ply-free            .ply from a map: free voxels too (same as --voxels all)
  --encoding E          ascii or binary (default) for .ply and .pcd; binary_compressed for .pcd
  --up AXIS             .png: which way is up (x, y, z, -x, -y, -z; default z)
Prints what was read (`map N voxels (occupied N, free N)` or `cloud N points`), then what was
written: `wrote OUT: N occupied voxels as points` and the like.
exit status: 0 success, 2 bad input (one line on stderr naming the file and the problem).
)";
}

namespace detail {

inline OccupancyMap<OcKey> read_voxel_list_map(const std::string& path, double res) {
  OccupancyMap<OcKey> map(res);
  const auto& g = map.grid();
  const std::vector<io::VoxelRecord> voxels = io::read_voxel_list(path);
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    const io::VoxelRecord& v = voxels[i];
    OcKey k;
    if (!g.coord_to_key(v.x, v.y, v.z, k)) {
      throw io::Error(path, "voxel " + std::to_string(i + 1) +
                                " lies outside the key range at --res " + std::to_string(res));
    }
    const double c[3] = {v.x, v.y, v.z};
    for (int a = 0; a < 3; ++a) {
      if (std::abs(g.index_to_coord(k[a]) - c[a]) > 0.01 * res) {
        throw io::Error(path, "voxel " + std::to_string(i + 1) +
                                  " is not a voxel centre at this --res (wrong --res?)");
      }
    }
    if (!std::isfinite(v.logodds)) {
      throw io::Error(path, "voxel " + std::to_string(i + 1) + " has a non-finite log-odds");
    }
    map.set(k, v.logodds);
  }
  return map;
}

}  // namespace detail

inline int run_convert(const std::vector<std::string>& argv) {
  const Args args(argv, {"--res", "--voxels", "--encoding", "--up"},
                  {"--voxel-list", "--ply-cubes", "--ply-free"}, 2);
  if (args.help()) {
    std::fputs(convert_help(), stdout);
    return 0;
  }
  if (args.positional().size() != 2) throw UsageError("needs IN and OUT (see --help)");
  const std::string in = args.positional()[0], out = args.positional()[1];
  const std::string in_ext = lower_extension(in), out_ext = lower_extension(out);
  check_outputs({{"OUT", out}});
  check_outputs_not_inputs({{"OUT", out}}, {{"IN", in}});
  const std::string encoding = args.str("--encoding", "binary");
  if (encoding != "ascii" && encoding != "binary" && encoding != "binary_compressed")
    throw UsageError("--encoding must be ascii, binary or binary_compressed, got '" + encoding +
                     "'");
  if (encoding == "binary_compressed" && out_ext != ".pcd")
    throw UsageError("--encoding binary_compressed is for .pcd output only");
  const std::string which = args.str("--voxels", "");
  if (!which.empty() && which != "occupied" && which != "free" && which != "all")
    throw UsageError("--voxels must be occupied, free or all, got '" + which + "'");

  const bool voxel_list_in = in_ext == ".voxels" || args.flag("--voxel-list");
  const bool map_in = voxel_list_in || in_ext == ".bt" || in_ext == ".ot";
  if (voxel_list_in && !args.has("--res")) throw UsageError("a voxel-list input needs --res");
  if (!voxel_list_in && args.has("--res"))
    throw UsageError("--res only applies to a voxel-list input");
  const bool map_only_out =
      out_ext == ".bt" || out_ext == ".ot" || out_ext == ".voxels" || out_ext == ".png";
  const bool cloud_out = out_ext == ".ply" || out_ext == ".pcd" || out_ext == ".xyz" ||
                         out_ext == ".txt" || out_ext == ".bin";
  if (!map_only_out && !cloud_out)
    throw UsageError("unknown output extension '" + out_ext +
                     "' (see --help: .bt .ot .voxels .txt .ply .pcd .xyz .bin .png)");
  if (!map_in && map_only_out)
    throw UsageError(in + " is a point cloud; make a map with: knnocc map --input " + in +
                     " --res R --out-" + out_ext.substr(1) + " " + out);
  if (!map_in && (args.flag("--ply-cubes") || args.flag("--ply-free") || !which.empty()))
    throw UsageError("--voxels, --ply-cubes and --ply-free apply to map inputs only");

  if (map_in) {
    OccupancyMap<OcKey> map = voxel_list_in
                                  ? detail::read_voxel_list_map(in, args.number("--res", 0.0))
                                  : read_tree_checked(in);
    const auto sel = [&](const char* fallback) {
      const std::string w = which.empty() ? fallback : which;
      if (args.flag("--ply-free")) return io::VoxelSelection::all;
      return w == "all"    ? io::VoxelSelection::all
             : w == "free" ? io::VoxelSelection::free
                           : io::VoxelSelection::occupied;
    };
    if (out_ext == ".bt") {
      io::write_bt(out, map);
    } else if (out_ext == ".ot") {
      io::write_ot(out, map);
    } else if (out_ext == ".png") {
      write_map_png(out, map, args.has("--up") ? parse_up_axis(args.str("--up")) : UpAxis{},
                    std::filesystem::path(in).filename().string());
    } else if (out_ext == ".voxels" || out_ext == ".txt") {
      io::write_voxel_list(out, io::voxel_records(map, sel("all")));
    } else if (out_ext == ".ply") {
      io::VoxelExportOptions o;
      o.which = sel("occupied");
      o.shape = args.flag("--ply-cubes") ? io::VoxelShape::cubes : io::VoxelShape::points;
      o.binary = encoding != "ascii";
      io::write_voxels_ply(out, map, o);
    } else {
      const io::VoxelSelection s = sel("occupied");
      std::vector<std::pair<OcKey, bool>> keys;
      map.for_each_voxel([&](const OcKey& k, float v) {
        const bool occ = map.is_occupied(v);
        if (s == io::VoxelSelection::all || occ == (s == io::VoxelSelection::occupied))
          keys.push_back({k, occ});
      });
      std::sort(keys.begin(), keys.end());
      std::vector<Point3f> pts;
      pts.reserve(keys.size());
      const auto& g = map.grid();
      for (const auto& [k, occ] : keys)
        pts.push_back(Point3f{static_cast<float>(g.index_to_coord(k[0])),
                              static_cast<float>(g.index_to_coord(k[1])),
                              static_cast<float>(g.index_to_coord(k[2]))});
      if (out_ext == ".pcd")
        io::write_pcd(out, pts, nullptr,
                      encoding == "ascii"    ? io::PcdData::ascii
                      : encoding == "binary" ? io::PcdData::binary
                                             : io::PcdData::binary_compressed);
      else if (out_ext == ".bin")
        io::write_kitti_bin(out, pts);
      else
        io::write_xyz(out, pts);
    }
    const auto c = map.count_voxels();
    std::printf("map %zu voxels (occupied %zu, free %zu)\n", c.known(), c.occupied, c.free);
    // What OUT holds, in the words of the selection that made it.
    auto chosen = [&](io::VoxelSelection s) {
      return s == io::VoxelSelection::all    ? c.known()
             : s == io::VoxelSelection::free ? c.free
                                             : c.occupied;
    };
    auto sel_name = [](io::VoxelSelection s) {
      return s == io::VoxelSelection::all    ? "known (occupied and free)"
             : s == io::VoxelSelection::free ? "free"
                                             : "occupied";
    };
    if (out_ext == ".bt" || out_ext == ".ot")
      std::printf("wrote %s: the whole map as an OctoMap tree\n", out.c_str());
    else if (out_ext == ".png")
      std::printf("wrote %s: a picture of the map\n", out.c_str());
    else if (out_ext == ".voxels" || out_ext == ".txt")
      std::printf("wrote %s: %zu %s voxels\n", out.c_str(), chosen(sel("all")),
                  sel_name(sel("all")));
    else if (out_ext == ".ply")
      std::printf("wrote %s: %zu %s voxels as %s\n", out.c_str(), chosen(sel("occupied")),
                  sel_name(sel("occupied")), args.flag("--ply-cubes") ? "cubes" : "points");
    else
      std::printf("wrote %s: %zu %s voxel centres as points\n", out.c_str(),
                  chosen(sel("occupied")), sel_name(sel("occupied")));
    return 0;
  }

  // Clouds: a single file keeps its points as stored (and its ids); scan graphs and sequence
  // folders are merged in the world frame.
  io::Cloud cloud;
  const io::ScanSource source = io::ScanSource::open(in);
  if (std::string(source.kind()) == "point file") {
    cloud = io::read_points(in);
  } else {
    Progress progress("convert", source.size());
    std::vector<Point3f> world;
    for (std::size_t i = 0; i < source.size(); ++i) {
      const io::Scan scan = source.load(i);
      io::transform_to_world(scan.pose, scan.cloud.points, world);
      cloud.points.insert(cloud.points.end(), world.begin(), world.end());
      progress.update(i + 1);
    }
    progress.finish();
  }
  const std::vector<std::uint64_t>* ids = cloud.ids.empty() ? nullptr : &cloud.ids;
  if (out_ext == ".ply") {
    io::write_ply(out, cloud.points, ids, encoding != "ascii");
  } else if (out_ext == ".pcd") {
    io::write_pcd(out, cloud.points, ids,
                  encoding == "ascii"    ? io::PcdData::ascii
                  : encoding == "binary" ? io::PcdData::binary
                                         : io::PcdData::binary_compressed);
  } else if (out_ext == ".bin") {
    io::write_kitti_bin(out, cloud.points);
  } else {
    io::write_xyz(out, cloud.points);
  }
  std::printf("cloud %zu points\nwrote %s: %zu points\n", cloud.points.size(), out.c_str(),
              cloud.points.size());
  return 0;
}

}  // namespace knnocc::cli
