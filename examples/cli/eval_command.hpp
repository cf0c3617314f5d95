#pragma once
// knnocc eval: a map against reference shapes (the paper's Table 1 metrics).

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/eval/multiview.hpp>
#include <knnocc/eval/reference.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/io/voxel_list.hpp>
#include <knnocc/map/occupancy_map.hpp>

#include "args.hpp"
#include "eval_heldout.hpp"
#include "eval_points.hpp"
#include "map_outputs.hpp"  // lower_extension
#include "resource_limits.hpp"

namespace knnocc::cli {

inline const char* eval_help() {
  return R"(usage: knnocc eval --map FILE --reference FILE [--res R] [--inflate M] [--ground-band M]
       knnocc eval --map FILE --reference POINTS.ply [--seen-by SEQ [--crop M]] [--res R]
       knnocc eval --ids SEQ [--map FILE [--against FILE]] [--crop M] [--res R] [--min-views N]
                   [--far M]
       knnocc eval --heldout SEQ [--model octomap|knn|robust|all] [--folds F] [--res R]
                   [--crop M] [--min-views N]

Compares a map (an OctoMap .bt/.ot file, or a voxel list from `knnocc map --out-voxels`: x y z
logodds per finest voxel, which needs --res; occupied = logodds >= 0) with reference shapes (`reference.txt` from `knnocc sim`: ground,
ellipsoid and cuboid lines) and prints the paper's Table 1 metrics on one line:
  occupied N free N shell N in_shell N covered N irrelevant N evaluated N
  precision X shell_recall X free_inside N
  shell        voxels on the reference's boundary at resolution R
  in_shell     occupied voxels on the shell                  ("nodes in reference shell")
  covered      occupied voxels on the shell or inside it     ("nodes covered by reference")
  irrelevant   occupied voxels farther than --inflate (0.3 m) from the shapes, not counting the
               ground band (centres less than --ground-band, 0.3 m, above the ground)
  evaluated    occupied voxels above the ground band; precision = 1 - irrelevant / evaluated
  shell_recall in_shell / shell
  free_inside  free voxels entirely inside a shape (space wrongly carved)
and the authors' counting (Miao et al., Sensors 2022) on a second line:
  tp N fp N tn N fn N f1 X mcc X
  over the voxels known in the map: TP occupied and matched one-to-one (a maximum matching) to
  a reference-occupied voxel within one voxel along each axis, FP the other occupied ones, FN
  free but reference-occupied and matched by no TP, TN free in both; the reference shapes are
  voxelised: a voxel is occupied when it meets a shape (surface or inside), free otherwise, and
  unknown (not counted) in the ground band (centres less than 0.3 m above the ground, or below).

Against reference points (--reference .ply/.pcd/.xyz, e.g. a room model's vertices):
  reference_points N cells N occupied N near N precision X visible N covered N recall X
  near     occupied voxels within one voxel of a reference point    (precision = near/occupied)
  visible  reference voxels within one voxel of a point of --seen-by SEQ (a sequence folder,
           --crop M as in `knnocc map`); every reference voxel without --seen-by
  covered  visible reference voxels within one voxel of an occupied voxel (recall)
  then the counting line against the points' voxels (free: the rest of their bounding box grown
  by a voxel). Vertices alone put a flat face's points at its corners: distances to them are
  upper bounds, so precision is a lower bound and FP, FN are upper bounds.

Without ground truth (--ids SEQ: a sequence folder whose clouds carry map-point ids, e.g. ORB-SLAM
keyframes; --crop M keeps the points within M of their camera, as `knnocc map --crop`): prints
  map_points N seen_once F multiview_points N median_views V
(seen_once: fraction of the distinct map points one keyframe alone observes; multiview: seen by
>= --min-views keyframes, default 3) and, with --map (a map of that sequence), the proxies
  occupied N isolated N multiview N reference_kept N lost N free_multiview N far N
  isolated        occupied voxels without an occupied voxel among their 26 neighbours
  multiview       voxels holding a multi-view map point
  reference_kept  of those, occupied in the --against map (e.g. `--model octomap`'s; else 0)
  lost            of those, not occupied in --map
  free_multiview  multi-view voxels that are free in --map
  far             occupied voxels farther than --far (0.3 m) from every multi-view voxel

Held-out (--heldout SEQ: a sequence with map-point ids): the keyframes split into --folds F
(default 5) interleaved folds (fold f: keyframes i with i % F == f); each fold is scored against
a map of the other folds' keyframes, built with --model (default all: one line each) at --res
(default 0.1) with the model's defaults, as `knnocc map` builds it; sums over the folds:
  heldout MODEL folds F points N recall X rays N seen_through N occupied N seen_through_share X
  points        map points that >= --min-views (2) held-out keyframes observe
  recall        of those, the share whose voxel is occupied
  rays          the held-out rays to those points
  seen_through  occupied voxels such a ray passes through before its end voxel (data the map was
                not built from saw them empty), and their share of the occupied voxels
It needs no ground truth and no rule of any model.
)";
}

// A voxel list as a map at resolution res; every line must be a voxel centre of that grid.
inline OccupancyMap<OcKey> read_voxel_map(const std::string& path, double res) {
  OccupancyMap<OcKey> map(res);
  for (const io::VoxelRecord& v : io::read_voxel_list(path)) {
    OcKey k;
    if (!map.grid().coord_to_key(v.x, v.y, v.z, k) ||
        std::fabs(map.grid().index_to_coord(k[0]) - v.x) > 1e-3 * res ||
        std::fabs(map.grid().index_to_coord(k[1]) - v.y) > 1e-3 * res ||
        std::fabs(map.grid().index_to_coord(k[2]) - v.z) > 1e-3 * res) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "(%.6f %.6f %.6f) is not a voxel centre at --res %g (wrong --res?)", v.x, v.y,
                    v.z, res);
      throw io::Error(path, text);
    }
    map.set(k, v.logodds);
  }
  return map;
}

// A map file (tree, or voxel list at --res).
inline OccupancyMap<OcKey> read_map(const Args& args, const std::string& path) {
  const std::string ext = lower_extension(path);
  const bool tree = ext == ".bt" || ext == ".ot";
  if (!tree && !args.has("--res"))
    throw UsageError("--res is required for a voxel list (the map's voxel size)");
  const double res = args.number("--res", 0.0);
  if (args.has("--res") && !(res >= 1e-4))
    throw UsageError("--res must be >= 0.0001, got " + args.str("--res"));
  OccupancyMap<OcKey> map = tree ? read_tree_checked(path) : read_voxel_map(path, res);
  if (tree && args.has("--res") && map.grid().resolution() != res)
    throw io::Error(path, "the tree's resolution is " + std::to_string(map.grid().resolution()) +
                              ", not --res " + args.str("--res"));
  return map;
}

// knnocc eval --ids: quality without ground truth (eval/multiview.hpp).
inline int run_eval_ids(const Args& args) {
  const std::string seq_path = args.str("--ids");
  const double crop = args.number("--crop", -1.0);
  if (args.has("--crop") && !(crop > 0)) throw UsageError("--crop must be > 0");
  eval::MultiviewOptions opt;
  const long views = args.integer("--min-views", opt.min_views);
  if (views < 1 || views > 1000) throw UsageError("--min-views must be in [1, 1000]");
  opt.min_views = static_cast<std::uint32_t>(views);
  opt.far = args.number("--far", opt.far);
  if (!(opt.far >= 0)) throw UsageError("--far must be >= 0");
  const io::Sequence seq = io::Sequence::open(seq_path);
  eval::MapPointViews mpv;
  std::vector<Point3d> world;
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const io::Cloud cloud = seq.load_cloud(i);
    if (cloud.ids.empty())
      throw io::Error(seq_path, "cloud " + std::to_string(i) + " has no map-point ids");
    io::keyframe_to_world(seq.pose(i), cloud, crop, world, ids);
    mpv.add_keyframe(world, ids);
  }
  std::printf("map_points %zu seen_once %.4f multiview_points %zu median_views %g\n", mpv.size(),
              mpv.seen_once_fraction(), mpv.count_at_least(opt.min_views), mpv.median_views());
  if (!args.has("--map")) return 0;
  const OccupancyMap<OcKey> map = read_map(args, args.str("--map"));
  std::optional<OccupancyMap<OcKey>> against;
  if (args.has("--against")) {
    against.emplace(read_map(args, args.str("--against")));
    if (against->grid().resolution() != map.grid().resolution())
      throw io::Error(args.str("--against"), "its resolution differs from --map's");
  }
  const eval::MultiviewMetrics m =
      eval::evaluate_multiview(map, mpv, against ? &*against : nullptr, opt);
  std::printf(
      "occupied %zu isolated %zu multiview %zu reference_kept %zu lost %zu free_multiview %zu "
      "far %zu\n",
      m.occupied, m.isolated, m.multiview, m.reference_kept, m.lost, m.free_multiview, m.far);
  return 0;
}

inline int run_eval(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"--map", "--reference", "--res", "--inflate", "--ground-band", "--ids",
                   "--against", "--crop", "--min-views", "--far", "--heldout", "--model", "--folds",
                   "--seen-by", "--margin"},
                  {});
  if (args.help()) {
    std::fputs(eval_help(), stdout);
    return 0;
  }
  if (args.has("--heldout")) return run_eval_heldout(args);
  if (args.has("--ids")) return run_eval_ids(args);
  const std::string map_path = args.required("--map");
  const std::string ref_path = args.required("--reference");
  eval::MetricOptions opt;
  opt.inflate = args.number("--inflate", opt.inflate);
  opt.ground_band = args.number("--ground-band", opt.ground_band);
  if (!(opt.inflate >= 0) || !(opt.ground_band >= 0))
    throw UsageError("--inflate and --ground-band must be >= 0");
  if (is_point_reference(ref_path))
    return run_eval_points(args, read_map(args, map_path), ref_path);
  const eval::Reference ref = eval::read_reference(ref_path);
  const OccupancyMap<OcKey> map = read_map(args, map_path);
  const eval::Metrics m = eval::evaluate(map, ref, opt);
  std::printf(
      "occupied %zu free %zu shell %zu in_shell %zu covered %zu irrelevant %zu evaluated %zu "
      "precision %.4f shell_recall %.4f free_inside %zu\n",
      m.occupied, m.free, m.shell, m.in_shell, m.covered, m.irrelevant, m.evaluated, m.precision(),
      m.shell_recall(), m.free_inside);
  print_confusion(eval::count_confusion(map, eval::ShapeVoxels<OcKey>(ref, map.grid())));
  return 0;
}

}  // namespace knnocc::cli
