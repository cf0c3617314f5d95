// knnocc eval: a map against reference shapes (the paper's Table 1 metrics).

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/eval/multiview.hpp>
#include <knnocc/eval/observation_stats.hpp>
#include <knnocc/eval/reference.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/io/voxel_list.hpp>
#include <knnocc/map/occupancy_map.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "common_options.hpp"
#include "eval_heldout.hpp"
#include "eval_points.hpp"
#include "eval_tune.hpp"
#include "map_files.hpp"
#include "resource_limits.hpp"

namespace knnocc::cli {

namespace {

const char* kEvalText =
    R"(Compares a map (an OctoMap .bt/.ot file, or a voxel list from `knnocc map --out-voxels`: x y z
logodds per finest voxel, which needs --res; occupied = logodds >= 0) with reference shapes
(`reference.txt` from `knnocc sim`: ground, ellipsoid and cuboid lines) and prints the paper's
Table 1 metrics on one line:
  occupied N free N shell N in_shell N covered N irrelevant N evaluated N
  precision X shell_recall X free_inside N
  shell        voxels on the reference's boundary at resolution R
  in_shell     occupied voxels on the shell                  ("nodes in reference shell")
  covered      occupied voxels on the shell or inside it     ("nodes covered by reference")
  irrelevant   occupied voxels farther than --inflate from the shapes, not counting the ground
               band (centres less than --ground-band above the ground)
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
>= --min-views keyframes), how the map points are observed (what the simulator is calibrated on,
docs/evaluation.md):
  views 1 F 2 F 3 F 4 F 5 F 6-10 F 11-20 F 21+ F   share of map points seen by that many keyframes
  span median S p90 S within5 F    last - first keyframe index of the points seen by >= 2;
                                   within5: their share seen only within 5 consecutive keyframes
  detection p10 F median F p90 F multiview_median F
                                   views / keyframes whose view contains the point (observers
                                   count), over all points and over those seen by >= 2
  view h_deg A..B v_deg A..B range_median M..M behind N
                                   the view, estimated from the data: the 0.5 %-99.5 % angles of
                                   all observations in their camera frame (x right, y down, z
                                   forward), and each keyframe's own nearest..farthest point
                                   (medians over the keyframes); occlusion is not modelled, so
                                   detection rates are lower bounds
and, with --map (a map of that sequence), the proxies
  occupied N isolated N multiview N reference_kept N lost N free_multiview N far N
  isolated        occupied voxels without an occupied voxel among their 26 neighbours
  multiview       voxels holding a multi-view map point
  reference_kept  of those, occupied in the --against map (e.g. `--model octomap`'s)
  lost            of those, not occupied in --map
                  (both need --against: without it they print n/a, with a note on stderr)
  free_multiview  multi-view voxels that are free in --map
  far             occupied voxels farther than --far from every multi-view voxel

Held-out (--heldout SEQ: a sequence with map-point ids): the keyframes split into --folds F
interleaved folds (fold f: keyframes i with i % F == f); each fold is scored against a map of
the other folds' keyframes, built with --model (all: one line each) at --res (default 0.1) with
the model's defaults (knn2022: its flags below), as `knnocc map` builds it; sums over the folds:
  heldout MODEL folds F points N recall X rays N seen_through N occupied N seen_through_share X
          floor N seen_both N [seen_through/octomap X % empty_only/octomap X %]
  points        map points that >= --min-views (2) held-out keyframes observe
  recall        of those, the share whose voxel is occupied
  rays          the held-out rays to those points
  seen_through  occupied voxels such a ray passes through before its end voxel (data the map was
                not built from saw them empty), and their share of the occupied voxels
  floor         the fewest seen_through voxels of any maps with MODEL's recall: held-out points
                lie in voxels that other held-out rays cross (depth edges, grazing rays, noise)
  seen_both     of the seen_through voxels, those holding a point of `points`: held-out keyframes
                saw them both empty and occupied (a depth edge); empty_only: the others
With the OctoMap model, a last line gives the floor at its recall less 2 percentage points:
  heldout_floor recall X (octomap's - 0.02) seen_through N (X % of octomap's)
It needs no ground truth and no rule of any model. With nothing to score (no map point seen by
--min-views held-out keyframes of one fold: too many --folds, or --min-views above every count) it
exits 2 naming why, and prints no score. A keyframe of zero points whose file declares the id
property is a keyframe with ids (an empty one).

The OctoMap model at its best (--tune-octomap SEQ --reference REF): SEQ mapped with the OctoMap
model at every hit {0.55 0.6 0.7 0.8 0.9 0.97} x miss {0.05 0.1 0.2 0.3 0.4 0.45 0.49} x
occupancy threshold {0.5 0.6 0.7 0.8 0.9} (--res, default 0.1; --crop), each map counted against
REF (shapes or points, as above); prints OctoMap's defaults, the best F1 (octomap*) and the next
four:
  octomap* hit H miss M threshold T tp N fp N tn N fn N f1 X mcc X
and, against reference points, the precision/recall and counting lines of octomap*'s map
(--seen-by as above). The reference picks the setting: an oracle baseline (as in the authors'
2022 paper), not a setting a user could choose without ground truth. The held-out evaluation
has no such line: it has no reference to pick by, and choosing by the held-out keyframes would
trade its two scores against each other by a rule of our own.
)";

// The groups of --heldout, the 2022 model's flags and --tune-octomap.
void add_heldout_groups(CommandSpec& s) {
  s.groups.push_back(
      {"held-out keyframes (--heldout)",
       {Option::text("--heldout", "SEQ", "a sequence folder whose clouds carry map-point ids"),
        Option::text("--model", "NAME", "the model whose maps are scored, or all")
            .alias("-m")
            .fallback("all")
            .one_of({"octomap", "knn", "knn2022", "robust", "all"}),
        Option::integer("--folds", "F", "interleaved folds")
            .fallback(std::to_string(eval::HeldoutOptions{}.folds))
            .at_least(2)
            .at_most(1000),
        Option::number("--margin", "M", "each held-out ray stops M short of its point")
            .fallback(format_number(eval::HeldoutOptions{}.end_margin))
            .at_least(0)
            .below(1000)},
       ""});
  s.groups.push_back(
      {"the OctoMap model at its best (--tune-octomap)",
       {Option::text("--tune-octomap", "SEQ",
                     "a sequence folder to map at every setting, scored against --reference")},
       ""});
  s.groups.push_back(knn2022_model_group(
      "  --heldout --model knn2022 (or all) maps the training keyframes with these; it maps them\n"
      "  uncropped (the model cuts at --inner-range) and scores against the --crop keyframes.\n"));
}

CommandSpec make_eval_spec() {
  const eval::MetricOptions m;
  const eval::MultiviewOptions v;
  CommandSpec s;
  s.name = "eval";
  s.summary = "compare a map with reference shapes (Table 1), or with a keyframe sequence's ids";
  s.usage =
      "knnocc eval --map FILE --reference FILE [--res R] [--inflate M] [--ground-band M]\n"
      "       knnocc eval --map FILE --reference POINTS.ply [--seen-by SEQ [--crop M]] [--res R]\n"
      "       knnocc eval --ids SEQ [--map FILE [--against FILE]] [--crop M] [--res R] "
      "[--min-views N]\n"
      "                   [--far M]\n"
      "       knnocc eval --heldout SEQ [--model octomap|knn|knn2022|robust|all] [--folds F]\n"
      "                   [--res R] [--crop M] [--min-views N] [--margin M]\n"
      "       knnocc eval --tune-octomap SEQ --reference FILE [--seen-by SEQ] [--res R] "
      "[--crop M]";
  s.text = kEvalText;
  s.groups.push_back(
      {"options",
       {Option::text("--map", "FILE", "the map: .bt, .ot, or a voxel list (needs --res)"),
        Option::number("--res", "R", "voxel edge of a voxel-list map; a tree's must equal it")
            .alias("-r")
            .at_least(kMinResolution),
        Option::text("--reference", "FILE",
                     "reference shapes (`knnocc sim`'s reference.txt), or reference points "
                     "(.ply .pcd .xyz)"),
        Option::text("--seen-by", "SEQ",
                     "reference points: count recall over the reference voxels near this "
                     "sequence's points only"),
        Option::number("--inflate", "M",
                       "occupied voxels farther than M from the shapes are "
                       "irrelevant")
            .fallback(format_number(m.inflate))
            .at_least(0),
        Option::number("--ground-band", "M",
                       "occupied voxels less than M above the ground are "
                       "not counted")
            .fallback(format_number(m.ground_band))
            .at_least(0),
        memory_limit_option()},
       ""});
  s.groups.push_back(
      {"without ground truth (--ids)",
       {Option::text("--ids", "SEQ", "a sequence folder whose clouds carry map-point ids"),
        Option::text("--against", "FILE", "a second map of the sequence (reference_kept)"),
        Option::number("--crop", "M", "keep the points within M of their camera")
            .fallback_text("no crop")
            .above(0),
        Option::integer("--min-views", "N",
                        "keyframes that make a map point multi-view (--ids), or held-out "
                        "keyframes that must observe a point (--heldout)")
            .fallback_text(std::to_string(v.min_views) + " (--ids), " +
                           std::to_string(eval::HeldoutOptions{}.min_views) + " (--heldout)")
            .at_least(1)
            .at_most(1000),
        Option::number("--far", "M", "occupied voxels farther than M from every multi-view voxel")
            .fallback(format_number(v.far))
            .at_least(0)},
       ""});
  add_heldout_groups(s);
  return s;
}

}  // namespace

const CommandSpec& eval_spec() {
  static const CommandSpec spec = make_eval_spec();
  return spec;
}

namespace {

// A map file (tree, or voxel list at --res).
OccupancyMap<OcKey> read_map(const Args& args, const std::string& path) {
  if (!is_tree_file(path) && !args.has("--res"))
    throw UsageError("--res is required for a voxel list (the map's voxel size)");
  return read_map_file(path, args.number("--res", 0.0));
}

// The observation lines of --ids (eval/observation_stats.hpp).
void print_observations(const std::vector<eval::ObservedKeyframe>& kfs) {
  const eval::ViewModel view = eval::estimate_view(kfs);
  const eval::ObservationSummary s = eval::summarize(eval::observe_points(kfs, view));
  std::printf("views 1 %.4f 2 %.4f 3 %.4f 4 %.4f 5 %.4f 6-10 %.4f 11-20 %.4f 21+ %.4f\n",
              s.views[0], s.views[1], s.views[2], s.views[3], s.views[4], s.views[5], s.views[6],
              s.views[7]);
  std::printf("span median %g p90 %g within5 %.4f\n", s.span_median, s.span_p90, s.within5);
  std::printf("detection p10 %.3f median %.3f p90 %.3f multiview_median %.3f\n", s.detection_p10,
              s.detection_median, s.detection_p90, s.detection_median_multiview);
  std::vector<double> lo, hi;
  for (std::size_t i = 0; i < kfs.size(); ++i)
    if (!kfs[i].points.empty()) {
      lo.push_back(view.r_lo[i]);
      hi.push_back(view.r_hi[i]);
    }
  const double deg = 180.0 / M_PI;
  std::printf("view h_deg %.1f..%.1f v_deg %.1f..%.1f range_median %.2f..%.2f behind %zu\n",
              view.h_lo * deg, view.h_hi * deg, view.v_lo * deg, view.v_hi * deg,
              eval::detail::quantile(lo, 0.5), eval::detail::quantile(hi, 0.5), view.behind);
}

// knnocc eval --ids: quality without ground truth (eval/multiview.hpp).
int run_eval_ids(const Args& args) {
  const std::string seq_path = args.str("--ids");
  const double crop = args.number("--crop", -1.0);
  eval::MultiviewOptions opt;
  opt.min_views = static_cast<std::uint32_t>(args.integer("--min-views", opt.min_views));
  opt.far = args.number("--far");
  const io::Sequence seq = io::Sequence::open(seq_path);
  eval::MapPointViews mpv;
  std::vector<eval::ObservedKeyframe> kfs(seq.size());
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const io::Cloud cloud = seq.load_cloud(i);
    if (!cloud.has_ids())
      throw io::Error(seq_path, "cloud " + std::to_string(i) + " has no map-point ids");
    io::keyframe_to_world(seq.pose(i), cloud, crop, kfs[i].points, kfs[i].ids);
    mpv.add_keyframe(kfs[i].points, kfs[i].ids);
    const Eigen::Matrix3d r = seq.pose(i).q.toRotationMatrix();
    for (int a = 0; a < 9; ++a) kfs[i].rotation[static_cast<std::size_t>(a)] = r(a / 3, a % 3);
    kfs[i].origin = {seq.pose(i).t.x(), seq.pose(i).t.y(), seq.pose(i).t.z()};
  }
  std::printf("map_points %zu seen_once %.4f multiview_points %zu median_views %g\n", mpv.size(),
              mpv.seen_once_fraction(), mpv.count_at_least(opt.min_views), mpv.median_views());
  print_observations(kfs);
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
  // Without a reference map there is nothing kept or lost to count: n/a, not 0.
  const std::string kept = against ? std::to_string(m.reference_kept) : "n/a",
                    lost = against ? std::to_string(m.lost) : "n/a";
  if (!against)
    std::fprintf(stderr,
                 "knnocc eval: note: reference_kept and lost need --against (a reference map of "
                 "the same sequence)\n");
  std::printf(
      "occupied %zu isolated %zu multiview %zu reference_kept %s lost %s free_multiview %zu "
      "far %zu\n",
      m.occupied, m.isolated, m.multiview, kept.c_str(), lost.c_str(), m.free_multiview, m.far);
  return 0;
}

}  // namespace

namespace {

int run_eval_any(const Args& args) {
  if (args.has("--heldout")) return run_eval_heldout(args);
  if (args.has("--tune-octomap")) return run_eval_tune(args);
  if (args.has("--ids")) return run_eval_ids(args);
  const std::string map_path = args.required("--map");
  const std::string ref_path = args.required("--reference");
  eval::MetricOptions opt;
  opt.inflate = args.number("--inflate");
  opt.ground_band = args.number("--ground-band");
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
  print_confusion(
      eval::count_confusion(map, eval::ShapeVoxels<OcKey>(ref, map.grid(), opt.ground_band)));
  return 0;
}

}  // namespace

int run_eval(const Args& args) {
  use_memory_limit(args);
  // Running out of memory names what is evaluated (a file being read names itself first).
  std::string subject = "eval";
  for (const char* o : {"--heldout", "--tune-octomap", "--ids", "--map"})
    if (args.has(o)) {
      subject = args.str(o);
      break;
    }
  return within_memory(subject, "evaluating it", [&] { return run_eval_any(args); });
}

}  // namespace knnocc::cli
