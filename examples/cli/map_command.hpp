#pragma once
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
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/robust_model.hpp>

#include "args.hpp"
#include "live_corrections.hpp"
#include "map_outputs.hpp"
#include "output_set.hpp"
#include "progress.hpp"
#include "resource_limits.hpp"
#include "view_frame.hpp"

namespace knnocc::cli {

inline std::string map_help() {
  return std::string(R"(usage: knnocc map --input PATH --res R [options]     (--opt=value works too)

Builds an occupancy map and prints one summary line:
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
options:
  -r, --res R           voxel edge in metres (required, > 0)
  -m, --model octomap|knn|robust  inverse sensor model (default octomap: hit 0.7, miss 0.4,
                        clamping 0.1192..0.971, OctoMap's insertPointCloud semantics;
                        knn: the paper's k-NN model, eq 13-15, see below; robust: see below)
                        Which model for which sensor: sparse visual-SLAM keyframes with map-point
                        ids -> robust; dense depth cameras / LiDAR -> octomap (knn removes far,
                        sparser surfaces of dense clouds; robust without ids is octomap's model)
  --max-range M         points farther than M from the sensor only free space up to M and
                        mark nothing occupied (OctoMap's maxrange); < 0: no limit (default)
  --crop M              drop points farther than M from their sensor before anything else
  --discretize          reduce each cloud to its distinct endpoint voxels first (OctoMap's
                        discretize option)
  --out-voxels FILE     write `x y z logodds` per finest voxel (centre, world frame, %.6f),
                        sorted by x, y, z; written to a temporary file, then renamed
  --voxels WHICH        which voxels --out-voxels writes: occupied, free or all (default)
  --first I             start at cloud I (0-based; default 0) ...
  --count N             ... and map N clouds (default: all the rest)
  --init-map F.ot|F.bt  continue this map (OctoMap model only): a .ot holds the log-odds, so
                        mapping clouds 0..n-1 to a .ot and then --init-map it --first n gives the
                        same map as one run; a .bt holds only occupied/free (clamped values).
                        --res defaults to the map's. A k-NN map cannot be continued from a file:
                        the tracker's map points and s_p statistics are not in it.
  --save-every N        every N clouds, write the --out-bt / --out-ot files (atomically: a
                        killed run leaves the last whole snapshot)
)") + map_outputs_help() +
         R"(  -j, --threads N       threads that walk the rays of each cloud (default 1); the map is the
                        same for every N; at most the machine's hardware threads (more is capped,
                        with a note)
  --memory-limit SIZE   the most memory the command may take, e.g. 800M or 4G (default: 80 %
                        of the machine's memory, or of a lower address-space or cgroup limit);
                        the map may use 75 % of it. A scan that surely needs more is refused
                        before it is inserted; running out later is one line too (exit 2)
  --corrections DIR     SLAM pose corrections: DIR/after_NNNNNN.txt, the poses of keyframes
                        0..NNNNNN (poses.txt format) known after keyframe NNNNNN, applied then;
                        the map stays equal to mapping with the final poses (sequence folders;
                        prints `corrections N reposed_keyframes N median_ms X max_ms X`)
k-NN model (--model knn): the map point cloud is the union of the keyframes (clouds with an `id`
property: ORB-SLAM map points, each joins once; without ids every point is a new map point);
s_p = mean distance of p to its k nearest map points; the valid s_p (< s-limit) form N(mu, sigma).
An endpoint gets Prob = P_u - Phi(s_p) / Phi(mu + w sigma) (P_u - P_w); its voxel receives the sum
of logit(Prob) of its endpoints, and it casts a free ray only if Prob > P_w. Prints one more line
before the summary: knn k K map_points N valid N mu X sigma X rays R of E median_keyframe_ms T
  (defaults: the best of the sweep in README, `build/bin/bench_knn_sweep`)
  --k K                 neighbours per map point (default 8)
  --w W                 reliability threshold in sigmas above mu (default 0, in [-8, 8])
  --p-upper P           P_u, probability of the most reliable endpoints (default 0.9)
  --p-w P               P_w, probability at s = mu + w sigma (default 0.65; 0.5 < P_w < P_u < 1)
  --p-free P            free-ray probability (default 0.4, OctoMap's miss; in (0, 0.5))
  --s-limit X           valid map points have s_p < X (default: no limit)
  (--discretize does not apply to the k-NN model)
robust model (--model robust, sensor/robust_model.hpp, docs/robust_model.md): for sparse visual-SLAM
keyframes with map-point ids. A map point is believed real while P(real) >= 1/2 under a two-class
mixture of real structure and wrong matches whose rates it estimates from the sequence itself: how
often the keyframes that met a point saw through it (a ray crossed its voxel and ended more than
--margin-scale mean k-NN distances beyond), how many points of other keyframes lie near it, and the
SLAM system's found/visible counts when the clouds carry them (PLY `found`, `visible`,
`observations`). The mixture counts only while its wrong class is less supported than its real
one (else every point is believed). A believed point adds eq 13's log-odds (from two detections on
at least P_w) and casts its ray from its second detection; a point no longer believed takes its
evidence back. One keyframe adds the mean of its endpoints in a voxel. Without map-point ids it is
OctoMap's model and keeps no map point cloud (the knn line then says map_points 0).
Takes the k-NN flags above. Prints the same knn line.
  --margin-scale X      a ray sees through a point when it ends more than X mean k-NN distances
                        beyond it (default 2, in [0, 100])
exit status: 0 success, 2 bad input (one line on stderr naming the file and the problem).
)";
}

struct MapOptions {
  std::string input, which, out_voxels, init_map;
  double res = 0, max_range = -1, crop = -1, memory_limit = 0;
  bool discretize = false;
  unsigned threads = 1;
  std::size_t first = 0, count = static_cast<std::size_t>(-1), save_every = 0;
};

/// The k-NN model's flags (defaults: the documented sweep's choice); UsageError when invalid.
inline KnnModelParams knn_params(const Args& args) {
  KnnModelParams p;
  const long k = args.integer("--k", static_cast<long>(p.k));
  if (k < 1 || k > 4096) throw UsageError("--k must be in [1, 4096], got " + args.str("--k"));
  p.k = static_cast<std::size_t>(k);
  p.w = args.number("--w", p.w);
  p.p_upper = args.number("--p-upper", p.p_upper);
  p.p_w = args.number("--p-w", p.p_w);
  p.p_free = args.number("--p-free", p.p_free);
  p.s_limit = args.number("--s-limit", p.s_limit);
  try {
    p.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("k-NN model: ") + e.what());
  }
  return p;
}

/// The file an error in scan i is about: the cloud of a sequence, else the input itself.
inline std::string source_path_for_errors(const std::string& input, std::size_t i) {
  if (io::is_sequence_dir(input)) {
    try {
      return io::Sequence::open(input).cloud_path(i);
    } catch (const std::exception&) {
    }
  }
  return input + (i > 0 ? " (scan " + std::to_string(i) + ")" : "");
}

template <class Model>
int run_map_with(const Args& args, const MapOptions& opt, const Model& model) {
  const auto t0 = std::chrono::steady_clock::now();
  const MapperOptions mo{opt.max_range, opt.discretize, opt.threads, {}};
  Mapper<Model> mapper = [&] {
    if (opt.init_map.empty()) return Mapper<Model>(opt.res, model, mo);
    OccupancyMap<OcKey> init = io::read_octree(opt.init_map);
    if (opt.res > 0 && std::abs(init.grid().resolution() - opt.res) > 1e-12 * opt.res)
      throw io::Error(opt.init_map, "resolution " + std::to_string(init.grid().resolution()) +
                                        " differs from --res " + std::to_string(opt.res));
    if (lower_extension(opt.init_map) == ".bt")
      std::fprintf(stderr,
                   "knnocc map: %s: a .bt holds only occupied/free; continuing from clamped "
                   "log-odds (a .ot continues exactly)\n",
                   opt.init_map.c_str());
    return Mapper<Model>(std::move(init), model, mo);
  }();
  UpEstimator up_estimate;
  std::vector<std::string> written;
  const std::size_t map_share = map_memory_share(opt.memory_limit);
  mapper.map().set_memory_limit(map_share);
  char res_text[32];
  std::snprintf(res_text, sizeof res_text, "%g", mapper.map().grid().resolution());
  // Work that cannot fit: refused before it starts, naming the limit and what to change.
  auto too_big = [&](std::size_t i, const std::string& what) {
    return io::Error(source_path_for_errors(opt.input, i),
                     what + " at --res " + res_text + ": more than the map's share (" +
                         format_bytes(double(map_share)) + ") of --memory-limit " +
                         format_bytes(opt.memory_limit) +
                         "; use a coarser --res, a --max-range or --crop, or a higher "
                         "--memory-limit");
  };
  ScanStats total;
  std::size_t clouds = 0, rays = 0, rated = 0;
  std::vector<double> keyframe_ms;
  auto add = [&](const KeyframeStats& ks) {
    total.points += ks.scan.points;
    total.nonfinite += ks.scan.nonfinite;
    total.out_of_range += ks.scan.out_of_range;
    rays += ks.rays;
    rated += ks.rated;
    ++clouds;
  };

  // --crop: distance to the sensor, measured while the points are still in the sensor frame.
  const io::ScanSource source = io::ScanSource::open(opt.input);
  if (opt.first > source.size() || (opt.first == source.size() && source.size() > 0))
    throw UsageError("--first " + std::to_string(opt.first) + ": " + opt.input + " has " +
                     std::to_string(source.size()) + " clouds");
  const std::size_t last = opt.first + std::min(opt.count, source.size() - opt.first);
  Progress progress("map", last - opt.first);
  std::vector<Point3f> world_f;  // OctoMap model: float points, as liboctomap
  std::vector<Point3d> world;    // k-NN model: double, as the tracker keeps them
  std::vector<std::uint64_t> ids;
  std::vector<PointEvidence> evidence;  // the SLAM counters, when the clouds carry them
  for (std::size_t i = opt.first; i < last; ++i) try {
      io::Scan scan = source.load(i);
      up_estimate.add(scan.pose, scan.cloud.points);
      const auto a = std::chrono::steady_clock::now();
      const Point3d origin{scan.pose.t.x(), scan.pose.t.y(), scan.pose.t.z()};
      const std::size_t enough = map_share / kBrickBytesAtLeast;
      if constexpr (Mapper<Model>::uses_map_cloud) {
        io::keyframe_to_world(scan.pose, scan.cloud, opt.crop, world, ids, &evidence);
        const std::size_t bricks =
            at_least_bricks(origin, world, mapper.map().grid().resolution(), -1.0, false, enough);
        if (bricks > enough)
          throw too_big(i, "the points alone need more than " + std::to_string(enough) + " bricks");
        try {
          add(mapper.insert_keyframe(scan.pose.t, world, ids, evidence));
        } catch (const std::invalid_argument& e) {  // e.g. clouds with and without ids mixed
          throw io::Error(source_path_for_errors(opt.input, i), e.what());
        }
      } else {
        std::vector<Point3f>& pts = scan.cloud.points;
        if (opt.crop > 0.0) {
          std::size_t kept = 0;
          for (const Point3f& p : pts)
            if (std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z) <= opt.crop)
              pts[kept++] = p;
          pts.resize(kept);
        }
        if (io::is_identity(scan.pose))
          world_f.swap(pts);
        else
          io::transform_to_world(scan.pose, pts, world_f);
        const std::size_t bricks = at_least_bricks(
            origin, world_f, mapper.map().grid().resolution(), opt.max_range, true, enough);
        if (bricks > enough)
          throw too_big(i, "its rays need more than " + std::to_string(enough) + " bricks (" +
                               format_bytes(double(enough) * kBrickBytesAtLeast) + ")");
        add(mapper.insert_keyframe(scan.pose.t, world_f));
      }
      keyframe_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count());
      progress.update(i + 1 - opt.first);
      if (opt.save_every && (i + 1 - opt.first) % opt.save_every == 0 && i + 1 < last) {
        if (args.has("--out-bt")) io::write_bt(args.str("--out-bt"), mapper.map());
        if (args.has("--out-ot")) io::write_ot(args.str("--out-ot"), mapper.map());
      }
    } catch (const MemoryLimitError&) {
      throw too_big(i, "the map needs more memory");
    } catch (const std::bad_alloc&) {
      throw io::Error(source_path_for_errors(opt.input, i),
                      out_of_memory_text(opt.memory_limit, "reading or mapping it",
                                         mapper.map().grid().resolution()));
    }
  progress.finish();
  const auto& map = mapper.map();

  if (total.nonfinite)
    std::fprintf(stderr, "knnocc map: %s: skipped %zu points with NaN/Inf coordinates\n",
                 opt.input.c_str(), total.nonfinite);
  if (total.out_of_range)
    std::fprintf(stderr,
                 "knnocc map: %s: skipped %zu points outside the map's key range (|c| >= %g m at "
                 "--res %g); use a coarser --res (the library's WideKey maps reach 64x farther)\n",
                 opt.input.c_str(), total.out_of_range, map.grid().max_coord(), opt.res);

  io::CommitGroup outputs;  // all written, then all renamed
  if (!opt.out_voxels.empty()) {
    const io::VoxelSelection which = opt.which == "all"        ? io::VoxelSelection::all
                                     : opt.which == "occupied" ? io::VoxelSelection::occupied
                                                               : io::VoxelSelection::free;
    io::write_voxel_list(opt.out_voxels, io::voxel_records(map, which));
    written.push_back(opt.out_voxels);
  }
  write_map_outputs(map, args, up_axis(args, up_estimate.result()), model_title(model), written);
  outputs.commit();

  if constexpr (Mapper<Model>::uses_map_cloud) {
    const auto& tr = mapper.tracker();
    // Dense input (depth camera, LiDAR): the paper's s-rating removes far, sparser surfaces.
    if constexpr (!Mapper<Model>::contextual)
      if (clouds > 0 && tr.N() > 0 && (tr.mu() < 0.5 * opt.res || total.points / clouds > 20000))
        std::fprintf(stderr,
                     "knnocc map: %s: warning: dense input (mean k-NN distance %.3g m at --res %g, "
                     "%zu points per cloud): the k-NN model removes far, sparser surfaces of "
                     "dense clouds; --model octomap (or robust) keeps them\n",
                     opt.input.c_str(), tr.mu(), opt.res, total.points / clouds);
    std::sort(keyframe_ms.begin(), keyframe_ms.end());
    const double median = keyframe_ms.empty() ? 0.0 : keyframe_ms[keyframe_ms.size() / 2];
    std::printf(
        "knn k %zu map_points %zu valid %zu mu %.6f sigma %.6f rays %zu of %zu "
        "median_keyframe_ms %.3f\n",
        tr.params().k, tr.size(), tr.N(), tr.mu(), tr.sigma(), rays, rated, median);
  }
  const auto counts = map.count_voxels();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("clouds %zu points %zu occupied %zu free %zu seconds %.3f\n", clouds, total.points,
              counts.occupied, counts.free, seconds);
  print_written(written);
  return 0;
}

inline int run_map(const std::vector<std::string>& argv) {
  const Args args(
      argv, with_map_outputs({"--input",       "--res",        "--model",       "--max-range",
                              "--crop",        "--out-voxels", "--voxels",      "--threads",
                              "--k",           "--w",          "--p-upper",     "--p-w",
                              "--p-free",      "--s-limit",    "--corrections", "--init-map",
                              "--save-every",  "--first",      "--count",       "--margin-scale",
                              "--memory-limit"}),
      with_map_output_flags({"--discretize"}));
  if (args.help()) {
    std::fputs(map_help().c_str(), stdout);
    return 0;
  }
  check_map_outputs(args);
  check_outputs(requested_outputs(
      args, {"--out-voxels", "--out-bt", "--out-ot", "--out-ply", "--out-png", "--out-html"}));
  const std::string input = args.required("--input");
  if (!args.has("--res") && !args.has("--init-map"))
    throw UsageError("--res is required (see --help)");
  const double res = args.number("--res", 1.0);
  if (!(res > 0.0)) throw UsageError("--res must be > 0, got " + args.str("--res"));
  // 16-bit keys span ±32768 voxels: below 0.1 mm even a room would not fit, so refuse instead
  // of skipping nearly every point.
  if (res < 1e-4) throw UsageError("--res " + args.str("--res") + " is too small (minimum 0.0001)");
  const std::string model = args.str("--model", "octomap");
  if (model != "octomap" && model != "knn" && model != "robust")
    throw UsageError("--model must be octomap, knn or robust, got '" + model + "'");
  MapOptions opt;
  opt.input = input;
  opt.max_range = args.number("--max-range", -1.0);
  if (opt.max_range == 0.0) throw UsageError("--max-range must be > 0, or < 0 for no limit");
  opt.crop = args.number("--crop", -1.0);
  if (args.has("--crop") && !(opt.crop > 0.0)) throw UsageError("--crop must be > 0");
  opt.which = args.str("--voxels", "all");
  if (opt.which != "all" && opt.which != "occupied" && opt.which != "free")
    throw UsageError("--voxels must be occupied, free or all, got '" + opt.which + "'");
  opt.discretize = args.flag("--discretize");
  const long threads = args.integer("--threads", 1);
  if (threads < 1 || threads > 1024)
    throw UsageError("--threads must be an integer from 1 to 1024, got '" + args.str("--threads") +
                     "'");
  opt.threads = cap_threads("map", threads);
  opt.out_voxels = args.str("--out-voxels");
  opt.res = args.has("--res") ? res : 0.0;
  opt.init_map = args.str("--init-map");
  if (!opt.init_map.empty()) {
    const std::string e = lower_extension(opt.init_map);
    if (e != ".ot" && e != ".bt")
      throw UsageError("--init-map needs an OctoMap .ot or .bt file, got '" + opt.init_map + "'");
    if (model != "octomap")
      throw UsageError(
          "--init-map needs --model octomap: a k-NN map cannot be continued from a "
          "file, the tracker's map points and s_p statistics are not in it");
  }
  const long first = args.integer("--first", 0), count = args.integer("--count", -1);
  if (first < 0) throw UsageError("--first must be >= 0, got " + args.str("--first"));
  if (args.has("--count") && count < 1)
    throw UsageError("--count must be >= 1, got " + args.str("--count"));
  opt.first = static_cast<std::size_t>(first);
  if (count > 0) opt.count = static_cast<std::size_t>(count);
  const long every = args.integer("--save-every", 0);
  if (args.has("--save-every") && every < 1)
    throw UsageError("--save-every must be >= 1, got " + args.str("--save-every"));
  if (every > 0 && !args.has("--out-bt") && !args.has("--out-ot"))
    throw UsageError("--save-every needs --out-bt or --out-ot (the files it writes)");
  opt.save_every = static_cast<std::size_t>(every);

  if (args.has("--corrections"))
    for (const char* whole_run_only : {"--init-map", "--first", "--count", "--save-every"})
      if (args.has(whole_run_only))
        throw UsageError(std::string("--corrections maps the whole sequence: it cannot be "
                                     "combined with ") +
                         whole_run_only);
  opt.memory_limit = args.has("--memory-limit")
                         ? parse_memory_size("--memory-limit", args.str("--memory-limit"))
                         : default_memory_limit();
  apply_memory_limit(opt.memory_limit);

  if (model == "octomap") {
    for (const char* knn_only : {"--k", "--w", "--p-upper", "--p-w", "--p-free", "--s-limit"})
      if (args.has(knn_only)) throw UsageError(std::string(knn_only) + " needs --model knn");
    if (args.has("--margin-scale")) throw UsageError("--margin-scale needs --model robust");
    if (args.has("--corrections")) return run_map_corrections(args, opt, OctoMapModel{});
    return run_map_with(args, opt, OctoMapModel{});
  }
  if (opt.discretize) throw UsageError("--discretize applies to --model octomap only");
  if (model == "robust") {
    if (args.has("--corrections"))
      throw UsageError(
          "--corrections needs --model octomap or knn (the live mapper does not "
          "take the robust model)");
    RobustModelParams rp;
    rp.knn = knn_params(args);
    rp.margin_scale = args.number("--margin-scale", rp.margin_scale);
    if (!(rp.margin_scale >= 0 && rp.margin_scale <= 100))
      throw UsageError("--margin-scale must be in [0, 100], got " + args.str("--margin-scale"));
    return run_map_with(args, opt, RobustModel(rp));
  }
  if (args.has("--margin-scale")) throw UsageError("--margin-scale needs --model robust");
  if (args.has("--corrections")) return run_map_corrections(args, opt, KnnModel(knn_params(args)));
  return run_map_with(args, opt, KnnModel(knn_params(args)));
}

}  // namespace knnocc::cli
