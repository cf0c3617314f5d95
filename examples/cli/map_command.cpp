// knnocc map: build an occupancy map from a sequence folder, a .graph file or a point file.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/voxel_list.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn2022_model.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/robust_model.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "common_options.hpp"
#include "input_guard.hpp"
#include "live_corrections.hpp"
#include "map_colors.hpp"
#include "map_options.hpp"
#include "map_outputs.hpp"
#include "map_run.hpp"
#include "map_snapshots.hpp"
#include "map_tiles.hpp"
#include "output_set.hpp"
#include "progress.hpp"
#include "resource_limits.hpp"
#include "view_frame.hpp"

namespace knnocc::cli {

namespace {

const char* kMapText = R"(Builds an occupancy map and prints one summary line:
  clouds N points N occupied N free N seconds S
(occupied/free: finest-level voxels in the map; points: points inserted, after --crop), then
`wrote FILE ...` listing every file written.

input (-i, --input PATH):
  a sequence folder     poses.txt (sensor to world; TUM "stamp tx ty tz qx qy qz qw" or KITTI
                        3x4 "r11 r12 r13 tx r21 ... tz" lines) and clouds/NNNNNN.{ply,pcd,bin,xyz}
                        (points in the sensor frame, cloud i <-> pose line i); a KITTI
                        sequence: velodyne/*.bin + poses.txt + calib.txt (its Tr is applied)
  an OctoMap .graph     scans with their poses (OctoMap's ScanGraph)
  a point file          .ply, .pcd (VIEWPOINT = sensor pose), KITTI .bin, or ASCII
                        .xyz/.dat/.txt (x y z per line); sensor at the origin
Points are in the sensor frame, or in the world frame with --points-frame world. A cloud of which
fewer than 10 % of the points lie in the map's key range in their own coordinates is an error
naming the likely cause (a time stamp column, millimetres). Clouds with colour (PLY red green
blue, PCD rgb/rgba) give each occupied voxel the mean colour of the points that hit it, in .ply,
.html and .ot files (a ColorOcTree; --no-color: a plain OcTree). PLY colours of any scalar type:
uchar as is, ushort times 255/65535, other integer types as 0..255, float/double as 0..1; values
beyond the scale clamp to 0 or 255. An --init-map ColorOcTree keeps its colours (each voxel's
counts as one point). Files that keep no colour (.bt, voxel lists, .png, .yaml) get one note.
Which model for which sensor: sparse visual-SLAM keyframes with map-point ids -> robust; dense
depth cameras / LiDAR -> octomap (knn removes far, sparser surfaces of dense clouds; robust
without ids is octomap's model).
)";

const char* kKnnText =
    R"(  The map point cloud is the union of the keyframes (clouds with an `id` property: ORB-SLAM
  map points, each joins once; without ids every point is a new map point); s_p = mean distance
  of p to its k nearest map points; the valid s_p (< s-limit) form N(mu, sigma). An endpoint
  gets Prob = P_u - Phi(s_p) / Phi(mu + w sigma) (P_u - P_w); its voxel receives the sum of
  logit(Prob) of its endpoints, and it casts a free ray only if Prob > P_w. Prints one more line
  before the summary:
    knn k K map_points N valid N mu X sigma X rays R of E median_keyframe_ms T
  Defaults: the best of the sweep in docs/results.md (build/bin/bench_knn_sweep).
  --discretize does not apply to the k-NN model. The robust model takes these flags too.
)";

const char* kRobustText =
    R"(  For sparse visual-SLAM keyframes with map-point ids. A map point is believed real while
  P(real) >= 1/2 under a two-class mixture of real structure and wrong matches whose rates are
  estimated from the sequence itself: how often the keyframes that met the point saw through it
  (a ray crossed its voxel and ended more than --margin-scale mean k-NN distances beyond; each
  map point a ray ends at counts once per voxel), how many points of other keyframes lie near
  it, and the SLAM system's found/visible counts when the clouds carry them (PLY `found`,
  `visible`, `observations`). The mixture counts only while its wrong class is less supported
  than its real one (else every point is believed). A believed point adds eq 13's log-odds (from
  two detections on at least P_w while no keyframe has seen through it) and casts its ray from
  its third detection, unless the ray crosses a voxel holding another believed point; a point no
  longer believed takes its evidence back; one keyframe adds the mean of its endpoints in a
  voxel. Without map-point ids it is OctoMap's model and keeps no map point cloud (the knn line
  then says map_points 0). Prints the knn line. Where it loses: single wrong matches that one or
  two keyframes re-observe (the k-NN model keeps a few voxels fewer) and, on the stereo set,
  held-out rays pass through 56 % as many of its voxels as OctoMap's (goal 50 %). Rules,
  constants, measurements: docs/robust_model.md.
)";

const char* kKnn2022Text =
    R"(  The authors' 2022 model (Sensors 22(1):139): per cloud, d = mean distance of an inner point
  (within --inner-range of its sensor) to its --k2022 nearest inner points of the same cloud;
  p(d) = p_near - (p_near - p_far) F(d), F the normal CDF of d truncated at 0 with mu, sigma of
  every inner d (--stats); a voxel receives the sum of logit(p(d)) of its inner points (p_far
  < 0.5: evidence against) and is not freed by the same cloud; rays to inner points free with
  --p-miss, the other points' rays, cut at --inner-range, with the weaker --p-miss-outer. Give it
  the whole cloud (no --crop: it cuts at --inner-range itself). Prints one more line:
    knn2022 k K stats first-pass|online mu X sigma X inner N of P median_keyframe_ms T
  Defaults: docs/results.md (build/bin/bench_knn_sweep --model knn2022).
)";

const char* kMapFooter =
    "Outputs are never inputs: an output that is an input file (links count) or lies inside an\n"
    "input folder (the sequence, --corrections DIR) is refused before any work.\n"
    "exit status: 0 success, 2 bad input (one line on stderr naming the file and the problem).\n";

bool nonzero(double v) { return v != 0.0; }

CommandSpec make_map_spec() {
  CommandSpec s;
  s.name = "map";
  s.summary = "build an occupancy map from a sequence folder, a .graph file or a point file";
  s.usage = "knnocc map --input PATH --res R [options]     (--opt=value works too)";
  s.text = kMapText;
  s.groups.push_back(
      {"options",
       {Option::text("--input", "PATH", "a sequence folder, an OctoMap .graph or a point file")
            .alias("-i")
            .required(),
        Option::number("--res", "R", "voxel edge in metres; required unless --init-map")
            .alias("-r")
            .fallback_text("the --init-map map's")
            .at_least(kMinResolution),
        Option::text("--model", "NAME",
                     "inverse sensor model: octomap (hit 0.7, miss 0.4, clamping 0.1192..0.971, "
                     "OctoMap's insertPointCloud), knn (the paper's k-NN model, eq 13-15), "
                     "knn2022 (the authors' 2022 model) or robust (see below)")
            .alias("-m")
            .fallback("octomap")
            .one_of({"octomap", "knn", "knn2022", "robust"}),
        Option::number("--max-range", "M",
                       "points farther than M from the sensor only free space up to M and mark "
                       "nothing occupied (OctoMap's maxrange)")
            .fallback_text("no limit")
            .satisfies("> 0, or < 0 for no limit", nonzero),
        Option::number("--crop", "M", "drop points farther than M from their sensor first")
            .fallback_text("no crop")
            .above(0),
        points_frame_option(),
        Option::flag("--discretize",
                     "reduce each cloud to its distinct endpoint voxels first (OctoMap's "
                     "discretize option; octomap model only)"),
        Option::text("--out-voxels", "FILE",
                     "write `x y z logodds` per finest voxel (centre, world frame, %.6f), sorted "
                     "by x, y, z"),
        Option::text("--voxels", "WHICH", "which voxels --out-voxels writes")
            .fallback("all")
            .one_of({"occupied", "free", "all"}),
        Option::integer("--first", "I", "start at cloud I (0-based)").fallback("0").at_least(0),
        Option::integer("--count", "N", "map N clouds").fallback_text("all the rest").at_least(1),
        Option::text("--init-map", "FILE",
                     "continue this .ot or .bt map (octomap model only): mapping clouds 0..n-1 "
                     "to a .ot and then --init-map it --first n gives the same occupancy as one "
                     "run (colours: each voxel's earlier colour counts as one point); "
                     "a .bt holds only occupied/free (clamped values). A k-NN map cannot be "
                     "continued from a file: the tracker's map points are not in it"),
        Option::integer("--save-every", "N",
                        "every N clouds, write the --out-bt / --out-ot files together "
                        "(atomically: a killed run leaves the last whole snapshot); their header "
                        "says which clouds they hold (\"clouds 0 to 14 of SEQ; continue with "
                        "--first 15\", also in `knnocc info`): resume with --init-map F.ot "
                        "--first 15")
            .at_least(1),
        threads_option(), memory_limit_option(),
        Option::text("--corrections", "DIR",
                     "SLAM pose corrections: DIR/after_NNNNNN.txt, the poses of keyframes "
                     "0..NNNNNN (poses.txt format) known after keyframe NNNNNN, applied then; the "
                     "map stays equal to mapping with the final poses (sequence folders; octomap "
                     "and knn models; prints `corrections N reposed_keyframes N median_ms X "
                     "max_ms X`). Checked first: one name rule, row count, stamps within 1e-4 s "
                     "of poses.txt's (docs/live_mapping.md)")},
       ""});
  s.groups.push_back(map_output_group());
  s.groups.push_back(map_tiles_group());
  s.groups.push_back(octomap_model_group());
  s.groups.push_back(knn_model_group("k-NN model (--model knn)", kKnnText));
  s.groups.push_back(knn2022_model_group(kKnn2022Text));
  s.groups.push_back({"robust model (--model robust)",
                      {Option::number("--margin-scale", "X",
                                      "a ray sees through a map point when it ends more than X "
                                      "mean k-NN distances beyond it")
                           .fallback("2")
                           .at_least(0)
                           .at_most(100)},
                      kRobustText});
  s.footer = kMapFooter;
  return s;
}

}  // namespace

const CommandSpec& map_spec() {
  static const CommandSpec spec = make_map_spec();
  return spec;
}

namespace {

/// The map's share of --memory-limit, and the refusal of work that cannot fit in it, naming the
/// limit and what to change.
struct MapBudget {
  std::string input;
  double memory_limit = 0;
  std::size_t share = 0;
  double res = 0;

  std::size_t enough_bricks() const { return share / kBrickBytesAtLeast; }
  io::Error too_big(std::size_t i, const std::string& what) const {
    char res_text[32];
    std::snprintf(res_text, sizeof res_text, "%g", res);
    return io::Error(source_path_for_errors(input, i),
                     what + " at --res " + res_text + ": more than the map's share (" +
                         format_bytes(double(share)) + ") of --memory-limit " +
                         format_bytes(memory_limit) +
                         "; use a coarser --res, a --max-range or --crop, or a higher "
                         "--memory-limit");
  }
};

/// A new map at --res, or the --init-map map to continue (a ColorOcTree's colours into
/// `colors`, unless --no-color).
template <class Model>
Mapper<Model> make_mapper(const MapOptions& opt, const Model& model, io::OctreeColors& colors) {
  const MapperOptions mo{opt.max_range, opt.discretize, opt.threads, opt.occupancy};
  if (opt.init_map.empty()) return Mapper<Model>(opt.res, model, mo);
  OccupancyMap<OcKey> init =
      read_tree_checked(opt.init_map, opt.occupancy, opt.scans.colors ? &colors : nullptr);
  note_free_colors("map", opt.init_map, colors);
  if (opt.res > 0 && std::abs(init.grid().resolution() - opt.res) > 1e-12 * opt.res)
    throw io::Error(opt.init_map,
                    "resolution " + io::detail::round_trip_text(init.grid().resolution()) +
                        " differs from --res " + io::detail::round_trip_text(opt.res));
  if (lower_extension(opt.init_map) == ".bt")
    std::fprintf(stderr,
                 "knnocc map: %s: a .bt holds only occupied/free; continuing from clamped "
                 "log-odds (a .ot continues exactly)\n",
                 opt.init_map.c_str());
  return Mapper<Model>(std::move(init), model, mo);
}

/// Points of one scan in the world frame, kept between scans so their memory is reused.
struct WorldPoints {
  std::vector<Point3f> f;  // OctoMap model: float points, as liboctomap
  std::vector<Point3d> d;  // k-NN model: double, as the tracker keeps them
  std::vector<std::uint64_t> ids;
  std::vector<PointEvidence> evidence;  // the SLAM counters, when the clouds carry them
};

/// A prepared scan's points (MapRun::prepare: sensor frame, cropped) moved to the world frame in
/// float (as liboctomap), into `out`: the OctoMap and 2022 models' input.
void float_world(io::Scan& scan, std::vector<Point3f>& out) {
  std::vector<Point3f>& pts = scan.cloud.points;
  if (io::is_identity(scan.pose))
    out.swap(pts);
  else
    io::transform_to_world(scan.pose, pts, out);
}

/// Scan i (MapRun::prepare'd: sensor frame, cropped) into the map: moved to the world frame,
/// refused when its bricks surely pass the budget; its colours join the run's.
template <class Model>
KeyframeStats insert_scan(Mapper<Model>& mapper, io::Scan& scan, std::size_t i,
                          const MapBudget& budget, WorldPoints& w, MapRun& run) {
  const Point3d origin{scan.pose.t.x(), scan.pose.t.y(), scan.pose.t.z()};
  const double res = mapper.map().grid().resolution();
  const std::size_t enough = budget.enough_bricks();
  if constexpr (Mapper<Model>::uses_map_cloud) {
    io::keyframe_to_world(scan.pose, scan.cloud, -1.0, w.d, w.ids, &w.evidence);
    if (at_least_bricks(origin, w.d, res, -1.0, false, enough) > enough)
      throw budget.too_big(i,
                           "the points alone need more than " + std::to_string(enough) + " bricks");
    if constexpr (std::is_same_v<Model, RobustModel>)
      if (!scan.cloud.has_ids() && !w.d.empty()) run.note_missing_ids();  // an empty one: no-op
    run.add_colors(origin, w.d, scan.cloud.colors);
    try {
      return mapper.insert_keyframe(scan.pose.t, w.d, w.ids, w.evidence);
    } catch (const std::invalid_argument& e) {  // e.g. clouds with and without ids mixed
      throw io::Error(source_path_for_errors(run.input().path, i), e.what());
    }
  } else {
    float_world(scan, w.f);
    if (at_least_bricks(origin, w.f, res, run.input().max_range, true, enough) > enough)
      throw budget.too_big(i, "its rays need more than " + std::to_string(enough) + " bricks (" +
                                  format_bytes(double(enough) * kBrickBytesAtLeast) + ")");
    run.add_colors(origin, w.f, scan.cloud.colors);
    return mapper.insert_keyframe(scan.pose.t, w.f);
  }
}

/// The notes on skipped points and an empty map, the model's line and the summary line.
template <class Model>
void report_map(const Mapper<Model>& mapper, const Model& model, const MapOptions& opt,
                MapTotals& totals, std::chrono::steady_clock::time_point t0) {
  const auto& map = mapper.map();
  const ScanStats& total = totals.scan;
  note_skipped_points(opt.input, total.nonfinite, total.out_of_range, map.grid().max_coord(),
                      map.grid().resolution());
  note_empty_map(opt.input, totals.clouds, total.points, map.count_voxels().known(), model);
  print_model_line(mapper, opt, totals);
  const auto counts = map.count_voxels();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("clouds %zu points %zu occupied %zu free %zu seconds %.3f\n", totals.clouds,
              total.points, counts.occupied, counts.free, seconds);
}

/// The map files of a run, written as one set; `note` goes into the .bt/.ot headers
/// (map_snapshots.hpp). Adds their names to `written` and the lines they print (a 2D grid's
/// summary) to `notes`.
void write_map_run_files(const OccupancyMap<OcKey>& map, const Args& args, const MapOptions& opt,
                         const MapRun& run, const std::string& title, const std::string& note,
                         std::vector<std::string>& written, std::vector<std::string>& notes) {
  MapFileContext c = run.file_context(args, title);
  c.voxels = voxel_selection(opt.which);
  c.band = opt.grid_band;
  c.ply = ply_export_options(args);
  c.note = note;
  write_map_files(map, opt.files, c, written, notes);
  if (!c.colors) return;
  std::vector<std::string> colorless;
  for (const MapFile& f : opt.files)
    if (!keeps_colors(f.format)) colorless.push_back(f.path);
  note_colors_not_kept("map", opt.input, "map", colorless,
                       std::string(colorless.size() == 1 ? "a format" : "formats") +
                           " without colour; .ot, .ply and .html keep them");
}

/// The lines after the summary: what the map files said, and which were written.
void print_files(const std::vector<std::string>& written, const std::vector<std::string>& notes) {
  for (const std::string& n : notes) std::printf("%s\n", n.c_str());
  print_written(written);
}

template <class Model>
int run_map_with(const Args& args, const MapOptions& opt, const Model& model) {
  const auto t0 = std::chrono::steady_clock::now();
  io::OctreeColors init_colors;
  Mapper<Model> mapper = make_mapper(opt, model, init_colors);
  const MapBudget budget{opt.input, opt.memory_limit, map_memory_share(opt.memory_limit),
                         mapper.map().grid().resolution()};
  mapper.map().set_memory_limit(budget.share);
  const io::ScanSource source = io::ScanSource::open(opt.input);
  const std::size_t last = last_cloud(opt, source);
  // --save-every: the maps record the clouds they hold (map_snapshots.hpp).
  HeldClouds held{first_held_cloud(opt.init_map, opt.input, opt.first), last, opt.input};
  Progress progress("map", last - opt.first);
  MapRun run(opt.scans, mapper.map().grid().resolution());
  run.add_tree_colors(init_colors);
  init_colors = io::OctreeColors{};
  MapTotals totals;
  WorldPoints world;
  for (std::size_t i = opt.first; i < last; ++i) try {
      io::Scan scan = source.load(i);
      run.prepare(scan, mapper.map().grid(), source_path_for_errors(opt.input, i));
      const auto a = std::chrono::steady_clock::now();
      totals.add(insert_scan(mapper, scan, i, budget, world, run));
      totals.keyframe_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count());
      progress.update(i + 1 - opt.first);
      if (opt.save_every && (i + 1 - opt.first) % opt.save_every == 0 && i + 1 < last)
        save_snapshot(args, mapper.map(),
                      held_clouds_note(HeldClouds{held.first, i + 1, opt.input}), run.colors());
    } catch (const MemoryLimitError&) {
      throw budget.too_big(i, "the map needs more memory");
    } catch (const std::bad_alloc&) {
      throw io::Error(source_path_for_errors(opt.input, i),
                      out_of_memory_text(opt.memory_limit, "reading or mapping it", budget.res));
    }
  progress.finish();
  std::vector<std::string> written, notes;
  write_map_run_files(mapper.map(), args, opt, run, run.title(model_title(model)),
                      opt.save_every ? held_clouds_note(held) : std::string(), written, notes);
  report_map(mapper, model, opt, totals, t0);
  print_files(written, notes);
  return 0;
}

/// The map files asked for and what they need, checked before any work.
void map_file_options(const Args& args, MapOptions& opt) {
  opt.files = requested_map_files(args, {"--out-voxels", "--out-bt", "--out-ot", "--out-ply",
                                         "--out-png", "--out-html", "--out-grid"});
  const OutputList files = map_file_outputs(opt.files);
  check_outputs(files);
  OutputList outputs = files;
  if (args.has("--out-tiles")) {  // a folder: StagingDir checks it when the run starts
    outputs.emplace_back("--out-tiles", args.str("--out-tiles"));
    io::StagingDir::check_target(args.str("--out-tiles"), tiles::is_tile_set);
  }
  check_outputs_not_inputs(outputs,
                           requested_inputs(args, {"--input", "--init-map", "--corrections"}));
  check_map_file_flags(args, opt.files);
  if (args.has("--grid-z")) opt.grid_band = parse_range("--grid-z", args.str("--grid-z"));
}

/// The OctoMap model's clamping (--clamp, probabilities) as the map's parameters.
OccupancyParams occupancy_params(const Args& args) {
  OccupancyParams p;
  if (!args.has("--clamp")) return p;
  const auto [lo, hi] = parse_range("--clamp", args.str("--clamp"));
  if (!(lo > 0.0 && hi < 1.0 && lo < 0.5 && hi > 0.5))
    throw UsageError("--clamp needs probabilities 0 < MIN < 0.5 < MAX < 1, got '" +
                     args.str("--clamp") + "'");
  p.clamp_min = logodds(lo);
  p.clamp_max = logodds(hi);
  return p;
}

/// The options of a run, checked together (each option's own range is checked by Args).
MapOptions map_options(const Args& args) {
  MapOptions opt;
  map_file_options(args, opt);
  opt.occupancy = occupancy_params(args);
  opt.input = args.str("--input");
  if (!args.has("--res") && !args.has("--init-map"))
    throw UsageError("--res is required (see --help)");
  opt.res = args.has("--res") ? args.number("--res") : 0.0;
  opt.max_range = args.number("--max-range", -1.0);
  opt.crop = args.number("--crop", -1.0);
  opt.scans = MapInput{opt.input, args.str("--points-frame") == "world", opt.crop, opt.max_range,
                       !args.flag("--no-color")};
  opt.which = args.str("--voxels");
  opt.discretize = args.flag("--discretize");
  opt.threads = cap_threads("map", args.integer("--threads"));
  opt.init_map = args.str("--init-map");
  if (!opt.init_map.empty()) {
    const std::string e = lower_extension(opt.init_map);
    if (e != ".ot" && e != ".bt")
      throw UsageError("--init-map needs an OctoMap .ot or .bt file, got '" + opt.init_map + "'");
  }
  opt.first = static_cast<std::size_t>(args.integer("--first"));
  if (args.has("--count")) opt.count = static_cast<std::size_t>(args.integer("--count"));
  opt.save_every = static_cast<std::size_t>(args.integer("--save-every", 0));
  if (opt.save_every > 0 && !args.has("--out-bt") && !args.has("--out-ot"))
    throw UsageError("--save-every needs --out-bt or --out-ot (the files it writes)");
  if (args.has("--corrections"))
    for (const char* whole_run_only : {"--init-map", "--first", "--count", "--save-every"})
      if (args.has(whole_run_only))
        throw UsageError(std::string("--corrections maps the whole sequence: it cannot be "
                                     "combined with ") +
                         whole_run_only);
  opt.memory_limit = use_memory_limit(args);
  return opt;
}

/// --stats first-pass: mu and sigma of d over the clouds the run maps, each moved to the world
/// frame as the mapping pass moves it (the authors' first pass; the input is read twice).
Knn2022Params knn2022_first_pass(const MapOptions& opt, const Knn2022Params& p) {
  const io::ScanSource source = io::ScanSource::open(opt.input);
  const std::size_t last = last_cloud(opt, source);
  Knn2022FirstPass pass(p);
  std::vector<Point3f> f;
  std::vector<Point3d> d;
  MapRun run(opt.scans, opt.res);
  const Grid<OcKey> grid(opt.res);
  for (std::size_t i = opt.first; i < last; ++i) {
    io::Scan scan = source.load(i);
    run.prepare(scan, grid, source_path_for_errors(opt.input, i));
    float_world(scan, f);
    d.clear();
    for (const Point3f& q : f) d.push_back(Point3d{q.x, q.y, q.z});
    pass.add(Point3d{scan.pose.t.x(), scan.pose.t.y(), scan.pose.t.z()}, d);
  }
  return pass.params();
}

/// Flags that belong to another model than --model's.
void check_model_flags(const Args& args, const std::string& model) {
  if (model == "octomap" || model == "knn2022")
    for (const char* knn_only : {"--k", "--w", "--p-upper", "--p-w", "--p-free", "--s-limit"})
      if (args.has(knn_only))
        throw UsageError(std::string(knn_only) + " needs --model knn (or robust)");
  if (model != "octomap")
    for (const char* octomap_only : {"--prob-hit", "--prob-miss", "--clamp"})
      if (args.has(octomap_only))
        throw UsageError(std::string(octomap_only) + " needs --model octomap");
  if (model != "knn2022")
    for (const char* flag : kKnn2022Flags)
      if (args.has(flag)) throw UsageError(std::string(flag) + " needs --model knn2022");
  if (model != "robust" && args.has("--margin-scale"))
    throw UsageError("--margin-scale needs --model robust");
  if (model != "octomap" && args.flag("--discretize"))
    throw UsageError("--discretize applies to --model octomap only");
  if (model != "octomap" && args.has("--init-map"))
    throw UsageError(
        "--init-map needs --model octomap: a k-NN map cannot be continued from a "
        "file, the tracker's map points and s_p statistics are not in it");
  if ((model == "robust" || model == "knn2022") && args.has("--corrections"))
    throw UsageError(
        "--corrections needs --model octomap or knn (the live mapper does not "
        "take the " +
        model + " model)");
}

}  // namespace

/// The model flags the user gave, as text (what a tile set's index records of the model).
std::string model_options_text(const Args& args) {
  std::string text;
  for (const OptionGroup& g : map_spec().groups) {
    if (g.title.find("model") == std::string::npos) continue;
    for (const Option& o : g.options) {
      if (!args.has(o.name())) continue;
      text += (text.empty() ? "" : " ") + o.name();
      if (o.takes_value()) text += " " + args.str(o.name());
    }
  }
  return text;
}

/// The run as a tile set when --out-tiles asks for one, with the key width chosen.
template <class Model>
int run_map_tiles_with(const Args& args, const MapOptions& opt, const Model& model,
                       const TileOptions& t) {
  if (t.key_bits == 21)
    return run_map_tiles<Model, WideKey>(opt, model, t, model_options_text(args));
  return run_map_tiles<Model, OcKey>(opt, model, t, model_options_text(args));
}

/// One run of a model: a tile set, or the map in one process.
template <class Model>
int run_model(const Args& args, const MapOptions& opt, const TileOptions& t, const Model& model) {
  if (!t.dir.empty()) return run_map_tiles_with(args, opt, model, t);
  if (t.key_bits == 21) return run_map_wide(opt, model);
  return run_map_with(args, opt, model);
}

int run_map(const Args& args) {
  const std::string model = args.str("--model");
  check_model_flags(args, model);
  const MapOptions opt = map_options(args);
  const TileOptions tiles = tile_options(args, opt);
  const auto files = [&](const OccupancyMap<OcKey>& map, const MapRun& run,
                         const std::string& title, std::vector<std::string>& written,
                         std::vector<std::string>& notes) {
    write_map_run_files(map, args, opt, run, title, {}, written, notes);
  };
  if (model == "octomap") {
    const OctoMapModel om =
        OctoMapModel::from_probabilities(args.number("--prob-hit"), args.number("--prob-miss"));
    if (args.has("--corrections")) return run_map_corrections(args, opt, om, files);
    return run_model(args, opt, tiles, om);
  }
  if (model == "knn2022") {
    bool first_pass = true;
    Knn2022Params p = knn2022_params(args, first_pass);
    if (first_pass) p = knn2022_first_pass(opt, p);
    return run_model(args, opt, tiles, Knn2022Model(p));
  }
  if (model == "robust") {
    RobustModelParams rp;
    rp.knn = knn_params(args);
    rp.margin_scale = args.number("--margin-scale");
    return run_model(args, opt, tiles, RobustModel(rp));
  }
  if (args.has("--corrections"))
    return run_map_corrections(args, opt, KnnModel(knn_params(args)), files);
  return run_model(args, opt, tiles, KnnModel(knn_params(args)));
}

}  // namespace knnocc::cli
