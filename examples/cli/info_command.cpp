// knnocc info FILE: what a map, cloud, scan graph or sequence folder holds.

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/pcd.hpp>
#include <knnocc/io/ply.hpp>
#include <knnocc/io/point_file.hpp>
#include <knnocc/io/scan_source.hpp>
#include <knnocc/tiles/tile_set.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "common_options.hpp"
#include "map_files.hpp"
#include "progress.hpp"
#include "resource_limits.hpp"

namespace knnocc::cli {

namespace {

CommandSpec make_info_spec() {
  CommandSpec s;
  s.name = "info";
  s.summary = "what a map (.bt/.ot), tile set, cloud, scan graph or sequence folder holds";
  s.usage = "knnocc info PATH";
  s.text = R"(Prints what PATH holds, one "key: value" line each:
  .bt / .ot             OctoMap tree: type, resolution, nodes, leaves (occupied / free, depths),
                        finest voxels they cover, bounding box; the whole tree is validated
  .ply .pcd .xyz .dat .txt .bin
                        point cloud: points, non-finite points, ids, bounding box (finite points);
                        PCD: fields, encoding, viewpoint
  .graph                OctoMap scan graph: scans, points, edges, box of the world-frame points
  a sequence folder     clouds and poses (every cloud is read), box of the world-frame points
  a tile set folder     knnocc map --out-tiles / knnocc tile: resolution, key bits, tile depth and
                        edge, model, clouds, tiles, voxels, bounds of the tiles; every tile is
                        checked (size, SHA-256, resolution, voxels inside its tile)
)";
  s.groups.push_back({"options", {memory_limit_option()}, ""});
  s.footer =
      "exit status: 0 success, 2 bad input (one line on stderr naming the file and the problem).\n";
  s.max_positional = 1;
  return s;
}

}  // namespace

const CommandSpec& info_spec() {
  static const CommandSpec spec = make_info_spec();
  return spec;
}

namespace detail {

struct Box {
  double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  double hi[3] = {-std::numeric_limits<double>::infinity(),
                  -std::numeric_limits<double>::infinity(),
                  -std::numeric_limits<double>::infinity()};
  std::size_t finite = 0, nonfinite = 0;

  void add(const Point3f& p) {
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) {
      ++nonfinite;
      return;
    }
    ++finite;
    const double v[3] = {p.x, p.y, p.z};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], v[a]);
      hi[a] = std::max(hi[a], v[a]);
    }
  }
  void print(const char* what) const {
    if (finite == 0) {
      std::printf("%s: none\n", what);
      return;
    }
    std::printf("%s: x [%.3f, %.3f] y [%.3f, %.3f] z [%.3f, %.3f]\n", what, lo[0], hi[0], lo[1],
                hi[1], lo[2], hi[2]);
  }
};

}  // namespace detail

namespace {

int info_tree(const std::string& path) {
  const io::OctreeInfo t = io::inspect_octree(path);
  check_tree_resolution(path, t.resolution);  // what map and convert accept, info accepts
  std::printf("format: OctoMap %s tree (%s), id %s\n", t.binary ? "binary" : "full",
              t.binary ? ".bt" : ".ot", io::printable(t.id).c_str());
  if (!t.note.empty()) std::printf("note: %s\n", io::printable(t.note).c_str());
  std::printf("resolution: %g\n", t.resolution);
  std::printf("nodes: %llu\n", static_cast<unsigned long long>(t.nodes));
  std::printf("leaves: %llu (occupied %llu, free %llu), depths %d-%d\n",
              static_cast<unsigned long long>(t.occupied_leaves + t.free_leaves),
              static_cast<unsigned long long>(t.occupied_leaves),
              static_cast<unsigned long long>(t.free_leaves), t.min_leaf_depth, t.max_leaf_depth);
  std::printf("finest voxels: %llu (occupied %llu, free %llu)\n",
              static_cast<unsigned long long>(t.occupied_voxels + t.free_voxels),
              static_cast<unsigned long long>(t.occupied_voxels),
              static_cast<unsigned long long>(t.free_voxels));
  if (t.occupied_leaves + t.free_leaves > 0) {
    std::printf("bounds: x [%.3f, %.3f] y [%.3f, %.3f] z [%.3f, %.3f]\n", t.min[0], t.max[0],
                t.min[1], t.max[1], t.min[2], t.max[2]);
  }
  return 0;
}

int info_point_file(const std::string& path, const io::ScanSource& source) {
  const std::string ext = lower_extension(path);
  if (ext == ".pcd") (void)source.load(0);  // its VIEWPOINT checked as `map` checks it
  io::PcdInfo pcd;
  const io::Cloud cloud = ext == ".pcd" ? io::read_pcd(path, &pcd) : io::read_points(path);
  detail::Box box;
  for (const Point3f& p : cloud.points) box.add(p);
  if (ext == ".pcd") {
    std::string fields;
    for (const auto& f : pcd.fields) fields += (fields.empty() ? "" : " ") + f;
    const char* data = pcd.data == io::PcdData::ascii    ? "ascii"
                       : pcd.data == io::PcdData::binary ? "binary"
                                                         : "binary_compressed";
    std::printf("format: PCD %s, fields %s, width %llu height %llu\n", data,
                io::printable(fields).c_str(), static_cast<unsigned long long>(pcd.width),
                static_cast<unsigned long long>(pcd.height));
    const double* v = pcd.viewpoint;
    std::printf("viewpoint: %g %g %g %g %g %g %g\n", v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
  }
  std::printf("points: %zu\n", cloud.points.size());
  std::printf("non-finite points: %zu\n", box.nonfinite);
  std::printf("ids: %s\n", cloud.has_ids() ? "yes" : "no");
  box.print("bounds");
  return 0;
}

// A tile set: its index, and every tile read and checked against it.
int info_tile_set(const std::string& dir) {
  const tiles::TileSetIndex ix = tiles::read_index(dir);
  std::printf("format: knnocc tile set (%s)\n", tiles::kIndexName);
  std::printf("resolution: %g\n", ix.resolution);
  std::printf("key bits: %d\n", ix.key_bits);
  std::printf("tile depth: %d (edge %lld voxels, %g m)\n", ix.tile_depth,
              static_cast<long long>(ix.tile_edge()), double(ix.tile_edge()) * ix.resolution);
  std::printf("model: %s%s%s\n", io::printable(ix.model).c_str(),
              ix.model_options.empty() ? "" : " ", io::printable(ix.model_options).c_str());
  if (!ix.source.empty())
    std::printf("source: %s (clouds %llu to %llu)\n", io::printable(ix.source).c_str(),
                static_cast<unsigned long long>(ix.first),
                static_cast<unsigned long long>(ix.first + ix.count - (ix.count > 0)));
  std::printf("tiles: %zu\n", ix.tiles.size());
  std::printf("finest voxels: %llu (occupied %llu, free %llu)\n",
              static_cast<unsigned long long>(ix.occupied() + ix.free()),
              static_cast<unsigned long long>(ix.occupied()),
              static_cast<unsigned long long>(ix.free()));
  std::uint64_t bytes = 0;
  const std::int64_t center = ix.key_bits == 16 ? OcKey::center : WideKey::center;
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  Progress progress("info", ix.tiles.size());
  for (std::size_t i = 0; i < ix.tiles.size(); ++i) {
    const tiles::TileEntry& t = ix.tiles[i];
    bytes += t.bytes;
    for (std::size_t a = 0; a < 3; ++a) {
      const double l = double(t.keys[a] - center) * ix.resolution,
                   h = double(t.keys[a + 3] + 1 - center) * ix.resolution;
      lo[a] = i == 0 ? l : std::min(lo[a], l);
      hi[a] = i == 0 ? h : std::max(hi[a], h);
    }
    if (ix.key_bits == 16)
      tiles::check_tile_nodes(dir, ix, t, tiles::read_tile<OcKey>(dir, ix, t));
    else
      tiles::check_tile_nodes(dir, ix, t, tiles::read_tile<WideKey>(dir, ix, t));
    progress.update(i + 1);
  }
  progress.finish();
  std::printf("files: %llu bytes\n", static_cast<unsigned long long>(bytes));
  if (!ix.tiles.empty())
    std::printf("bounds of the tiles: x [%.3f, %.3f] y [%.3f, %.3f] z [%.3f, %.3f]\n", lo[0], hi[0],
                lo[1], hi[1], lo[2], hi[2]);
  std::printf("checked: every tile matches the index\n");
  return 0;
}

// A scan graph or a sequence folder: every scan, in the world frame.
int info_scans(const io::ScanSource& source) {
  detail::Box box, sensors;
  std::size_t points = 0;
  Progress progress("info", source.size());
  std::vector<Point3f> world;
  for (std::size_t i = 0; i < source.size(); ++i) {
    const io::Scan scan = source.load(i);
    io::transform_to_world(scan.pose, scan.cloud.points, world);
    points += world.size();
    for (const Point3f& p : world) box.add(p);
    sensors.add(Point3f{static_cast<float>(scan.pose.t.x()), static_cast<float>(scan.pose.t.y()),
                        static_cast<float>(scan.pose.t.z())});
    progress.update(i + 1);
  }
  progress.finish();
  std::printf("format: %s\n", source.kind());
  std::printf("scans: %zu\n", source.size());
  if (std::string(source.kind()) == "scan graph") {
    std::printf("edges: %zu\n", source.graph()->edges.size());
  }
  std::printf("points: %zu\n", points);
  std::printf("non-finite points: %zu\n", box.nonfinite);
  box.print("bounds");
  sensors.print("sensor positions");
  return 0;
}

}  // namespace

int run_info(const Args& args) {
  if (args.positional().empty()) throw UsageError("needs a file or folder (see --help)");
  use_memory_limit(args);
  const std::string path = args.positional()[0];
  std::printf("file: %s\n", path.c_str());
  return reading(path, [&] {
    if (is_tree_file(path)) return info_tree(path);
    if (tiles::is_tile_set(path)) return info_tile_set(path);
    const io::ScanSource source = io::ScanSource::open(path);
    if (std::string(source.kind()) == "point file") return info_point_file(path, source);
    return info_scans(source);
  });
}

}  // namespace knnocc::cli
