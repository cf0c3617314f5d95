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
#include <knnocc/tiles/tile_merge.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "common_options.hpp"
#include "input_guard.hpp"
#include "map_colors.hpp"
#include "map_files.hpp"
#include "map_outputs.hpp"
#include "output_set.hpp"
#include "progress.hpp"
#include "resource_limits.hpp"
#include "tile_set_files.hpp"

namespace knnocc::cli {

namespace {

CommandSpec make_convert_spec() {
  CommandSpec s;
  s.name = "convert";
  s.summary = "maps and clouds between formats (.bt .ot .ply .pcd .xyz .bin .png, voxel lists)";
  s.usage = "knnocc convert IN OUT [options]";
  s.text = R"(Converts a map or a point cloud; the formats follow from the file extensions.
maps:
  IN   .bt .ot (OctoMap trees), or a voxel list (x y z logodds per line, as --out-voxels
       writes) named .voxels or given with --voxel-list, which needs --res, or a tile set
       folder (knnocc map --out-tiles): .bt/.ot OUT is streamed as knnocc merge writes it;
       the other formats read it tile by tile (free voxels when --voxels or the format needs
       them and they fit --memory-limit; beyond OctoMap's key range at a coarser resolution)
  OUT  .bt .ot             OctoMap trees (knnocc convert a.bt b.bt rewrites a.bt byte for byte;
                           a ColorOcTree .ot stays one, its colours kept)
       .voxels .txt        voxel list, sorted by x, y, z (--voxels, default all)
       .ply                voxels as points (colour = a ColorOcTree's voxel colour, else
                           height; property logodds) or cubes
       .pcd .xyz .bin      voxel centres as a point cloud (--voxels, default occupied)
       .png                top and side views, coloured by height
       .yaml               a 2D grid for ROS map_server / Nav2 (OUT and OUT's .pgm) of the
                           --grid-z band along --up
clouds:
  IN   .ply .pcd .xyz .dat .txt .bin (KITTI), or an OctoMap .graph / a sequence folder (all
       scans moved to the world frame and merged)
  OUT  .ply .pcd .xyz .txt .bin (ids are kept by .ply and .pcd, colours by .ply; PLY colours
       of every type are read as map --help says and written as uchar)
Colours an OUT format cannot keep (a ColorOcTree into .bt, a coloured cloud into .xyz) are named
in one note on stderr.
A cloud becomes a map with a sensor model, not here: knnocc map --input IN --res R --out-bt OUT.
Prints what was read (`map N voxels (occupied N, free N)` or `cloud N points`), then what was
written: `wrote OUT: N occupied voxels as points` and the like.
)";
  s.groups.push_back(
      {"options",
       {Option::number("--res", "R", "voxel edge of a voxel-list input")
            .alias("-r")
            .at_least(kMinResolution),
        Option::flag("--voxel-list", "read IN as a voxel list whatever its extension"),
        Option::text("--voxels", "WHICH", "which voxels a map turns into points / lines")
            .fallback_text("occupied; all for voxel lists")
            .one_of({"occupied", "free", "all"}),
        Option::flag("--ply-cubes", ".ply from a map: one cube per voxel instead of one point"),
        Option::flag("--ply-free", ".ply from a map: free voxels too (same as --voxels all)"),
        Option::text("--encoding", "E", "for .ply and .pcd; binary_compressed for .pcd only")
            .fallback("binary")
            .one_of({"ascii", "binary", "binary_compressed"}),
        grid_z_option(), up_option("z"), memory_limit_option()},
       ""});
  s.footer =
      "exit status: 0 success, 2 bad input (one line on stderr naming the file and the problem).\n";
  s.max_positional = 2;
  return s;
}

}  // namespace

const CommandSpec& convert_spec() {
  static const CommandSpec spec = make_convert_spec();
  return spec;
}

namespace {

/// What `convert` was asked to do, checked before any work.
struct ConvertJob {
  std::string in, out, in_ext, out_ext, encoding, which;
  bool voxel_list_in = false, map_in = false, tile_set_in = false;

  io::VoxelSelection selection(const char* fallback, bool ply_free) const {
    if (ply_free) return io::VoxelSelection::all;
    return voxel_selection(which.empty() ? fallback : which);
  }
  io::PcdData pcd_data() const {
    return encoding == "ascii"    ? io::PcdData::ascii
           : encoding == "binary" ? io::PcdData::binary
                                  : io::PcdData::binary_compressed;
  }
};

ConvertJob convert_job(const Args& args) {
  if (args.positional().size() != 2) throw UsageError("needs IN and OUT (see --help)");
  ConvertJob j;
  j.in = args.positional()[0];
  j.out = args.positional()[1];
  j.in_ext = lower_extension(j.in);
  j.out_ext = lower_extension(j.out);
  if (j.out_ext == ".yaml") (void)io::ros_map_image_entry(j.out);  // a name YAML can hold
  const OutputList outputs =
      j.out_ext == ".yaml" ? OutputList{{"OUT", j.out}, {"OUT", io::ros_map_image_path(j.out)}}
                           : OutputList{{"OUT", j.out}};
  check_outputs(outputs);
  check_outputs_not_inputs(outputs, {{"IN", j.in}});
  j.encoding = args.str("--encoding");
  if (j.encoding == "binary_compressed" && j.out_ext != ".pcd")
    throw UsageError("--encoding binary_compressed is for .pcd output only");
  j.which = args.str("--voxels");
  j.voxel_list_in = j.in_ext == ".voxels" || args.flag("--voxel-list");
  j.tile_set_in = is_tile_set_path(j.in);
  j.map_in = j.voxel_list_in || is_tree_file(j.in) || j.tile_set_in;
  if (j.voxel_list_in && !args.has("--res")) throw UsageError("a voxel-list input needs --res");
  if (!j.voxel_list_in && args.has("--res"))
    throw UsageError("--res only applies to a voxel-list input");
  const bool map_only_out = j.out_ext == ".bt" || j.out_ext == ".ot" || j.out_ext == ".voxels" ||
                            j.out_ext == ".png" || j.out_ext == ".yaml";
  if ((j.out_ext == ".yaml") != args.has("--grid-z"))
    throw UsageError(args.has("--grid-z") ? "--grid-z needs a .yaml OUT (a 2D grid)"
                                          : "a 2D grid (.yaml) needs --grid-z MIN:MAX, the "
                                            "height band along --up that it shows");
  const bool cloud_out = j.out_ext == ".ply" || j.out_ext == ".pcd" || j.out_ext == ".xyz" ||
                         j.out_ext == ".txt" || j.out_ext == ".bin";
  if (!map_only_out && !cloud_out)
    throw UsageError("unknown output extension '" + j.out_ext +
                     "' (see --help: .bt .ot .voxels .txt .ply .pcd .xyz .bin .png .yaml)");
  if (!j.map_in && map_only_out)
    throw UsageError(j.in + " is a point cloud; make a map with: knnocc map --input " + j.in +
                     " --res R --out-" + j.out_ext.substr(1) + " " + j.out);
  if (!j.map_in && (args.flag("--ply-cubes") || args.flag("--ply-free") || !j.which.empty()))
    throw UsageError("--voxels, --ply-cubes and --ply-free apply to map inputs only");
  return j;
}

/// The centres of the selected voxels, sorted by key.
std::vector<Point3f> voxel_centres(const OccupancyMap<OcKey>& map, io::VoxelSelection s) {
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
  for (const auto& kv : keys)
    pts.push_back(Point3f{static_cast<float>(g.index_to_coord(kv.first[0])),
                          static_cast<float>(g.index_to_coord(kv.first[1])),
                          static_cast<float>(g.index_to_coord(kv.first[2]))});
  return pts;
}

const char* selection_name(io::VoxelSelection s) {
  return s == io::VoxelSelection::all    ? "known (occupied and free)"
         : s == io::VoxelSelection::free ? "free"
                                         : "occupied";
}

std::size_t selected(const VoxelCounts& c, io::VoxelSelection s) {
  return s == io::VoxelSelection::all    ? c.known()
         : s == io::VoxelSelection::free ? c.free
                                         : c.occupied;
}

/// The colours a map input had: a ColorOcTree stays one, its voxel colours go to .ply too.
struct MapInputColors {
  bool color_tree = false;
  const VoxelColors<OcKey>* voxels = nullptr;  ///< null: no voxel has a colour
};

/// Writes the map as OUT's format and prints what OUT holds; says once when OUT's format cannot
/// keep the input's colours.
void write_converted_map(const OccupancyMap<OcKey>& map, const ConvertJob& j, const Args& args,
                         const MapInputColors& colors = {}) {
  const std::string& out = j.out;
  const auto c = map.count_voxels();
  const bool ply_free = args.flag("--ply-free");
  const io::VoxelSelection all = j.selection("all", ply_free),
                           occ = j.selection("occupied", ply_free);
  const VoxelColorOf<OcKey> color_of = [&colors](const OcKey& k) {
    return colors.voxels ? colors.voxels->mean(k) : std::nullopt;
  };
  if (colors.voxels && j.out_ext != ".ot" && j.out_ext != ".ply")
    note_colors_not_kept("convert", j.in, "map", {out},
                         "knnocc writes it without colour; .ot and .ply keep them");
  if (j.out_ext == ".ot" && colors.color_tree) {
    io::write_color_ot(out, map, color_of);
    std::printf("wrote %s: the whole map as an OctoMap tree (a ColorOcTree)\n",
                io::printable(out).c_str());
  } else if (j.out_ext == ".bt" || j.out_ext == ".ot") {
    j.out_ext == ".bt" ? io::write_bt(out, map) : io::write_ot(out, map);
    std::printf("wrote %s: the whole map as an OctoMap tree\n", io::printable(out).c_str());
  } else if (j.out_ext == ".yaml") {
    MapFileContext ctx;
    ctx.up = up_axis(args);
    ctx.band = parse_range("--grid-z", args.str("--grid-z"));
    std::printf("%s\nwrote %s, %s\n", write_grid_file(map, out, ctx).c_str(),
                io::printable(out).c_str(), io::printable(io::ros_map_image_path(out)).c_str());
  } else if (j.out_ext == ".png") {
    write_map_png(out, map, up_axis(args), std::filesystem::path(j.in).filename().string());
    std::printf("wrote %s: a picture of the map\n", io::printable(out).c_str());
  } else if (j.out_ext == ".voxels" || j.out_ext == ".txt") {
    io::write_voxel_list(out, io::voxel_records(map, all));
    std::printf("wrote %s: %zu %s voxels\n", io::printable(out).c_str(), selected(c, all),
                selection_name(all));
  } else if (j.out_ext == ".ply") {
    io::VoxelExportOptions o;
    o.which = occ;
    o.shape = args.flag("--ply-cubes") ? io::VoxelShape::cubes : io::VoxelShape::points;
    o.binary = j.encoding != "ascii";
    io::write_voxels_ply(out, map, o, colors.voxels ? color_of : VoxelColorOf<OcKey>());
    std::printf("wrote %s: %zu %s voxels as %s\n", io::printable(out).c_str(), selected(c, occ),
                selection_name(occ), args.flag("--ply-cubes") ? "cubes" : "points");
  } else {
    const std::vector<Point3f> pts = voxel_centres(map, occ);
    if (j.out_ext == ".pcd")
      io::write_pcd(out, pts, nullptr, j.pcd_data());
    else if (j.out_ext == ".bin")
      io::write_kitti_bin(out, pts);
    else
      io::write_xyz(out, pts);
    std::printf("wrote %s: %zu %s voxel centres as points\n", io::printable(out).c_str(),
                selected(c, occ), selection_name(occ));
  }
}

// Clouds: a single file keeps its points as stored (and its ids); scan graphs and sequence
// folders are merged in the world frame.
io::Cloud read_cloud(const std::string& in) {
  const io::ScanSource source = io::ScanSource::open(in);
  if (std::string(source.kind()) == "point file") return io::read_points(in);
  io::Cloud cloud;
  Progress progress("convert", source.size());
  std::vector<Point3f> world;
  std::size_t colored = 0;
  for (std::size_t i = 0; i < source.size(); ++i) {
    const io::Scan scan = source.load(i);
    io::transform_to_world(scan.pose, scan.cloud.points, world);
    cloud.points.insert(cloud.points.end(), world.begin(), world.end());
    if (!scan.cloud.colors.empty()) ++colored;
    if (colored == i + 1)  // colours only when every scan has them
      cloud.colors.insert(cloud.colors.end(), scan.cloud.colors.begin(), scan.cloud.colors.end());
    progress.update(i + 1);
  }
  progress.finish();
  if (colored != source.size()) cloud.colors.clear();
  if (colored != 0 && colored != source.size())
    std::fprintf(stderr,
                 "knnocc convert: %s: note: %zu of its %zu scans have colours, the others none; "
                 "the merged cloud keeps no colours\n",
                 io::printable(in).c_str(), colored, source.size());
  return cloud;
}

int convert_cloud(const ConvertJob& j) {
  const io::Cloud cloud = reading(j.in, [&] { return read_cloud(j.in); });
  const std::vector<std::uint64_t>* ids = cloud.has_ids() ? &cloud.ids : nullptr;
  if (!cloud.colors.empty() && j.out_ext != ".ply")
    note_colors_not_kept("convert", j.in, "cloud", {j.out},
                         "knnocc writes it without colour; .ply keeps them");
  if (j.out_ext == ".ply")
    io::write_ply(j.out, cloud.points, ids, j.encoding != "ascii",
                  cloud.colors.empty() ? nullptr : &cloud.colors);
  else if (j.out_ext == ".pcd")
    io::write_pcd(j.out, cloud.points, ids, j.pcd_data());
  else if (j.out_ext == ".bin")
    io::write_kitti_bin(j.out, cloud.points);
  else
    io::write_xyz(j.out, cloud.points);
  std::printf("cloud %zu points\nwrote %s: %zu points\n", cloud.points.size(),
              io::printable(j.out).c_str(), cloud.points.size());
  return 0;
}

}  // namespace

/// A tile set into OUT: an OctoMap file streamed as knnocc merge writes it, the other formats
/// from the tiles read into one map (the voxels OUT shows).
int convert_tile_set(const ConvertJob& j, const Args& args) {
  if (j.out_ext == ".bt" || j.out_ext == ".ot") {
    const tiles::MergeStats st = reading(j.in, [&] {
      return tiles::merge_tile_set(j.in, j.out, j.out_ext == ".bt",
                                   map_memory_share(memory_limit_bytes()));
    });
    std::printf("tile set %zu tiles\nwrote %s: the whole map as an OctoMap tree (%llu nodes)\n",
                st.tiles, io::printable(j.out).c_str(), static_cast<unsigned long long>(st.nodes));
    return 0;
  }
  const bool free_too = j.out_ext == ".yaml" || args.flag("--ply-free") || j.which == "free" ||
                        j.which == "all" || (j.which.empty() && j.out_ext == ".voxels") ||
                        (j.which.empty() && j.out_ext == ".txt");
  const OccupancyMap<OcKey> map = read_tile_set_map(j.in, free_too, "convert");
  const auto c = map.count_voxels();
  std::printf("map %zu voxels (occupied %zu, free %zu)\n", c.known(), c.occupied, c.free);
  within_memory(j.out, "writing it", [&] { write_converted_map(map, j, args); });
  return 0;
}

int run_convert(const Args& args) {
  const ConvertJob j = convert_job(args);
  use_memory_limit(args);
  if (!j.map_in) return convert_cloud(j);
  if (j.tile_set_in) return convert_tile_set(j, args);
  io::OctreeColors tree;
  const OccupancyMap<OcKey> map =
      j.voxel_list_in
          ? reading(j.in, [&] { return read_voxel_list_map(j.in, args.number("--res")); })
          : read_map_file(j.in, 0.0, &tree);
  const auto c = map.count_voxels();
  std::printf("map %zu voxels (occupied %zu, free %zu)\n", c.known(), c.occupied, c.free);
  VoxelColors<OcKey> voxel_colors(map.grid().resolution());
  reading(j.in, [&] { add_tree_colors(voxel_colors, tree); });
  note_free_colors("convert", j.in, tree);
  const bool color_tree = tree.color_tree;
  tree = io::OctreeColors{};  // the colours are in voxel_colors now: freed before the write
  within_memory(j.out, "writing it", [&] {
    write_converted_map(map, j, args,
                        MapInputColors{color_tree, voxel_colors.empty() ? nullptr : &voxel_colors});
  });
  return 0;
}

}  // namespace knnocc::cli
