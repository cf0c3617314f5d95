#pragma once
// knnocc map: build an occupancy map from a sequence folder, a .graph file or a point file.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/voxel_list.hpp>
#include <knnocc/map/scan_inserter.hpp>

#include "args.hpp"
#include "map_outputs.hpp"
#include "progress.hpp"

namespace knnocc::cli {

inline std::string map_help() {
  return std::string(R"(usage: knnocc map --input PATH --res R [options]

Builds an occupancy map and prints one summary line:
  clouds N points N occupied N free N seconds S
(occupied/free: finest-level voxels in the map; points: points inserted, after --crop).

input (--input PATH):
  a sequence folder     poses.txt (sensor to world; TUM "stamp tx ty tz qx qy qz qw" or KITTI
                        3x4 "r11 r12 r13 tx r21 ... tz" lines) and clouds/NNNNNN.{ply,pcd,bin,xyz}
                        (points in the sensor frame, cloud i <-> pose line i); a KITTI
                        sequence: velodyne/*.bin + poses.txt + calib.txt (its Tr is applied)
  an OctoMap .graph     scans with their poses (OctoMap's ScanGraph)
  a point file          .ply, .pcd (VIEWPOINT = sensor pose), KITTI .bin, or ASCII
                        .xyz/.dat/.txt (x y z per line); sensor at the origin
options:
  --res R               voxel edge in metres (required, > 0)
  --model octomap       inverse sensor model (default octomap: hit 0.7, miss 0.4,
                        clamping 0.1192..0.971, OctoMap's insertPointCloud semantics)
  --max-range M         points farther than M from the sensor only free space up to M and
                        mark nothing occupied (OctoMap's maxrange); < 0: no limit (default)
  --crop M              drop points farther than M from their sensor before anything else
  --discretize          reduce each cloud to its distinct endpoint voxels first (OctoMap's
                        discretize option)
  --out-voxels FILE     write `x y z logodds` per finest voxel (centre, world frame, %.6f),
                        sorted by x, y, z; written to a temporary file, then renamed
  --voxels WHICH        which voxels --out-voxels writes: occupied, free or all (default)
)") + map_outputs_help() +
         R"(  --threads N           threads that walk the rays of each cloud (default 1); the map is the
                        same for every N
exit status: 0 success, 2 bad input (one line on stderr naming the file and the problem).
)";
}

inline int run_map(const std::vector<std::string>& argv) {
  const Args args(argv,
                  with_map_outputs({"--input", "--res", "--model", "--max-range", "--crop",
                                    "--out-voxels", "--voxels", "--threads"}),
                  with_map_output_flags({"--discretize"}));
  if (args.help()) {
    std::fputs(map_help().c_str(), stdout);
    return 0;
  }
  check_map_outputs(args);
  const std::string input = args.required("--input");
  if (!args.has("--res")) throw UsageError("--res is required (see --help)");
  const double res = args.number("--res", 0.0);
  if (!(res > 0.0)) throw UsageError("--res must be > 0, got " + args.str("--res"));
  // 16-bit keys span ±32768 voxels: below 0.1 mm even a room would not fit, so refuse instead
  // of skipping nearly every point.
  if (res < 1e-4) throw UsageError("--res " + args.str("--res") + " is too small (minimum 0.0001)");
  const std::string model = args.str("--model", "octomap");
  if (model == "knn")
    throw UsageError("--model knn is not available in this version yet; use --model octomap");
  if (model != "octomap") throw UsageError("--model must be octomap or knn, got '" + model + "'");
  const double max_range = args.number("--max-range", -1.0);
  if (max_range == 0.0) throw UsageError("--max-range must be > 0, or < 0 for no limit");
  const double crop = args.number("--crop", -1.0);
  if (args.has("--crop") && !(crop > 0.0)) throw UsageError("--crop must be > 0");
  const std::string which = args.str("--voxels", "all");
  if (which != "all" && which != "occupied" && which != "free")
    throw UsageError("--voxels must be occupied, free or all, got '" + which + "'");
  const bool discretize = args.flag("--discretize");
  const long threads = args.integer("--threads", 1);
  if (threads < 1 || threads > 1024)
    throw UsageError("--threads must be an integer from 1 to 1024, got '" + args.str("--threads") +
                     "'");

  const auto t0 = std::chrono::steady_clock::now();
  OccupancyMap<OcKey> map(res);
  ScanInserter<OcKey> inserter(map, {}, static_cast<unsigned>(threads));
  ScanStats total;
  std::size_t clouds = 0;
  std::vector<Point3f> world;

  // --crop: distance to the sensor, measured while the points are still in the sensor frame.
  auto apply_crop = [&](std::vector<Point3f>& pts) {
    if (crop <= 0.0) return;
    std::size_t kept = 0;
    for (const Point3f& p : pts)
      if (std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z) <= crop)
        pts[kept++] = p;
    pts.resize(kept);
  };
  auto add = [&](const ScanStats& st) {
    total.points += st.points;
    total.nonfinite += st.nonfinite;
    total.out_of_range += st.out_of_range;
    ++clouds;
  };

  const io::ScanSource source = io::ScanSource::open(input);
  Progress progress("map", source.size());
  for (std::size_t i = 0; i < source.size(); ++i) {
    io::Scan scan = source.load(i);
    const auto& t = scan.pose.t;
    apply_crop(scan.cloud.points);
    if (io::is_identity(scan.pose))
      world.swap(scan.cloud.points);
    else
      io::transform_to_world(scan.pose, scan.cloud.points, world);
    add(inserter.insert_point_cloud(Point3f{float(t.x()), float(t.y()), float(t.z())}, world,
                                    max_range, discretize));
    progress.update(i + 1);
  }

  if (total.nonfinite)
    std::fprintf(stderr, "knnocc map: %s: skipped %zu points with NaN/Inf coordinates\n",
                 input.c_str(), total.nonfinite);
  if (total.out_of_range)
    std::fprintf(stderr,
                 "knnocc map: %s: skipped %zu points outside the map's key range (|c| >= %g m at "
                 "--res %g); use a coarser --res\n",
                 input.c_str(), total.out_of_range, map.grid().max_coord(), res);

  if (args.has("--out-voxels")) {
    std::vector<io::VoxelRecord> out;
    out.reserve(map.num_voxels());
    const auto& g = map.grid();
    map.for_each_voxel([&](const OcKey& k, float v) {
      const bool occ = map.is_occupied(v);
      if (which == "all" || (which == "occupied") == occ)
        out.push_back(io::VoxelRecord{g.index_to_coord(k[0]), g.index_to_coord(k[1]),
                                      g.index_to_coord(k[2]), v});
    });
    io::write_voxel_list(args.str("--out-voxels"), std::move(out));
  }
  write_map_outputs(map, args);

  const auto counts = map.count_voxels();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("clouds %zu points %zu occupied %zu free %zu seconds %.3f\n", clouds, total.points,
              counts.occupied, counts.free, seconds);
  return 0;
}

}  // namespace knnocc::cli
