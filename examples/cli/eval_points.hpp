#pragma once
// knnocc eval against a reference point set (a room model's vertices, eval/reference_points.hpp)
// and the authors' counting line (eval/confusion.hpp) that every reference comparison prints.

#include <cstdio>
#include <string>
#include <vector>

#include <knnocc/eval/confusion.hpp>
#include <knnocc/eval/reference_points.hpp>
#include <knnocc/io/point_file.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/map/occupancy_map.hpp>

#include "args.hpp"
#include "map_outputs.hpp"  // lower_extension

namespace knnocc::cli {

/// A reference file of points (.ply, .pcd, .xyz) rather than reference shapes (reference.txt).
inline bool is_point_reference(const std::string& path) {
  const std::string e = lower_extension(path);
  return e == ".ply" || e == ".pcd" || e == ".xyz";
}

inline void print_confusion(const eval::ConfusionCounts& c) {
  std::printf("tp %zu fp %zu tn %zu fn %zu f1 %.4f mcc %.4f\n", c.tp, c.fp, c.tn, c.fn, c.f1(),
              c.mcc());
}

/// `map` against the points of `ref_path`: precision, recall (of the reference cells near the
/// points of --seen-by SEQ, within --crop, when given) and the authors' counting.
inline int run_eval_points(const Args& args, const OccupancyMap<OcKey>& map,
                           const std::string& ref_path) {
  const io::Cloud ref = io::read_points(ref_path);
  if (ref.points.empty()) throw io::Error(ref_path, "no points in the reference");
  const eval::PointVoxels<OcKey> voxels(ref.points, map.grid());
  eval::PointVoxels<OcKey>::KeySet seen;
  if (args.has("--seen-by")) {
    const double crop = args.number("--crop", -1.0);
    const io::Sequence seq = io::Sequence::open(args.str("--seen-by"));
    std::vector<Point3d> world;
    std::vector<std::uint64_t> ids;
    for (std::size_t i = 0; i < seq.size(); ++i) {
      io::keyframe_to_world(seq.pose(i), seq.load_cloud(i), crop, world, ids);
      for (const Point3d& p : world) {
        OcKey k;
        if (map.grid().point_to_key(p, k)) seen.insert(k);
      }
    }
  }
  const eval::PointCoverage c =
      eval::point_coverage(map, voxels, args.has("--seen-by") ? &seen : nullptr);
  std::printf(
      "reference_points %zu cells %zu occupied %zu near %zu precision %.4f visible %zu covered %zu "
      "recall %.4f\n",
      ref.points.size(), voxels.cells().size(), c.occupied, c.near, c.precision(), c.visible,
      c.covered, c.recall());
  print_confusion(eval::count_confusion(map, voxels));
  return 0;
}

}  // namespace knnocc::cli
