#pragma once
// knnocc track: run the k-NN tracker (paper section 3.2, Alg. 2) over a keyframe sequence.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <knnocc/io/atomic_file.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/knn/tracker.hpp>

#include "args.hpp"
#include "input_guard.hpp"
#include "output_set.hpp"
#include "progress.hpp"

namespace knnocc::cli {

inline const char* track_help() {
  return R"(usage: knnocc track --input DIR --k K --out-stats FILE [options]

Tracks s_p (mean distance of each map point to its k nearest neighbours) and the normal
distribution of the valid s_p (s_p < s-limit) over a sequence folder, keyframe by keyframe.
The map point cloud at keyframe t is every point seen in keyframes 0..t: when the clouds carry
an `id` property (ORB-SLAM map-point ids) a point joins once, at its first position; without
ids every point of every keyframe is a new map point.

options:
  --input DIR          sequence folder (poses.txt + clouds/*.ply), see `knnocc map --help`
  --k K                neighbours per point (>= 1)
  --s-limit X          valid points have s < X (default: no limit)
  --max-range M        drop points farther than M from their sensor (the paper keeps 4 m)
  --affected POLICY    exact (default) or paper (Alg. 1 as written, for comparison)
  --dr D, --s-max S    Alg. 1's radius step and limit for --affected paper (default 0.1, 2.0)
  --out-stats FILE     one line per keyframe: index N mu sigma new removed affected microseconds
  --out-s FILE         at the end, one line per map point: id x y z s (world frame; s = nan
                       while a point has fewer than k neighbours), sorted by id
Prints one summary line: keyframes N points N N N mu X sigma X seconds S.
)";
}

template <class Policy>
int run_track_with(const Args& args, const Policy& policy) {
  const std::string input = args.required("--input");
  TrackerParams params;
  const long k = args.integer("--k", 0);
  if (!args.has("--k")) throw UsageError("--k is required (see --help)");
  if (k < 1 || k > 4096) throw UsageError("--k must be in [1, 4096], got " + args.str("--k"));
  params.k = static_cast<std::size_t>(k);
  params.s_limit = args.number("--s-limit", std::numeric_limits<double>::infinity());
  if (!(params.s_limit > 0.0)) throw UsageError("--s-limit must be > 0");
  const double max_range = args.number("--max-range", -1.0);
  if (args.has("--max-range") && !(max_range > 0.0)) throw UsageError("--max-range must be > 0");
  const std::string stats_path = args.required("--out-stats");
  const OutputList files = requested_outputs(args, {"--out-stats", "--out-s"});
  check_outputs(files);
  check_outputs_not_inputs(files, {{"--input", input}});

  const auto seq = io::Sequence::open(input);
  KnnTracker<Policy> tracker(params, policy);
  std::string stats;
  KeyframeUnion map_cloud;
  std::vector<Point3d> world;
  std::vector<std::uint64_t> ids;
  std::size_t keyframes = 0;
  const auto t0 = std::chrono::steady_clock::now();
  Progress progress("track", seq.size());
  for (std::size_t i = 0; i < seq.size(); ++i) {
    io::keyframe_to_world(seq.pose(i), seq.load_cloud(i), max_range, world, ids);
    ChangeSet cs;
    try {
      cs = map_cloud.add(world, ids);
    } catch (const std::invalid_argument& e) {  // ids repeated in the keyframe, or mixed
      throw io::Error(seq.cloud_path(i), e.what());
    }
    const auto a = std::chrono::steady_clock::now();
    const TrackerUpdate up = tracker.apply(cs);
    const double us =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count();
    char line[256];
    std::snprintf(line, sizeof line, "%zu %zu %.9g %.9g %zu %zu %zu %.1f\n", i, tracker.N(),
                  tracker.mu(), tracker.sigma(), up.added + up.moved, up.removed + up.moved,
                  up.affected, us);
    stats += line;
    ++keyframes;
    progress.update(i + 1);
  }
  progress.finish();
  if (map_cloud.skipped_nonfinite())
    std::fprintf(stderr, "knnocc track: %s: skipped %zu points with NaN/Inf coordinates\n",
                 input.c_str(), map_cloud.skipped_nonfinite());

  io::CommitGroup outputs;  // both written, then both renamed
  io::AtomicFile out(stats_path);
  out.write("# index N mu sigma new removed affected microseconds\n");
  out.write(stats);
  if (args.has("--out-s")) {
    struct Row {
      std::uint64_t id;
      Point3d p;
      double s;
    };
    std::vector<Row> rows;
    tracker.for_each_point([&](std::uint64_t id, const Point3d& p, double s) {
      rows.push_back({id, p, s});
    });
    std::sort(rows.begin(), rows.end(), [](const Row& x, const Row& y) { return x.id < y.id; });
    io::AtomicFile s_out(args.str("--out-s"));
    s_out.write("# id x y z s\n");
    char line[160];
    for (const Row& r : rows) {
      std::snprintf(line, sizeof line, "%llu %.6f %.6f %.6f %.9g\n",
                    static_cast<unsigned long long>(r.id), r.p.x, r.p.y, r.p.z, r.s);
      s_out.write(line);
    }
    s_out.commit();
  }
  out.commit();
  outputs.commit();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("keyframes %zu points %zu N %zu mu %.6f sigma %.6f seconds %.3f\n", keyframes,
              tracker.size(), tracker.N(), tracker.mu(), tracker.sigma(), seconds);
  return 0;
}

inline int run_track(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"--input", "--k", "--s-limit", "--max-range", "--out-stats", "--out-s",
                   "--affected", "--dr", "--s-max"},
                  {});
  if (args.help()) {
    std::fputs(track_help(), stdout);
    return 0;
  }
  const std::string policy = args.str("--affected", "exact");
  if (policy == "exact") return run_track_with(args, ExactReverseKnn{});
  if (policy == "paper") {
    const PaperAnnulus annulus{args.number("--dr", 0.1), args.number("--s-max", 2.0)};
    if (!(annulus.dr > 0.0) || !(annulus.s_max > annulus.dr))
      throw UsageError("--dr must be > 0 and --s-max larger than --dr");
    return run_track_with(args, annulus);
  }
  throw UsageError("--affected must be exact or paper, got '" + policy + "'");
}

}  // namespace knnocc::cli
