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
#include "commands.hpp"
#include "common_options.hpp"
#include "input_guard.hpp"
#include "output_set.hpp"
#include "progress.hpp"

namespace knnocc::cli {

namespace {

CommandSpec make_track_spec() {
  CommandSpec s;
  s.name = "track";
  s.summary = "follow s_p and its normal distribution over a keyframe sequence (k-NN tracker)";
  s.usage = "knnocc track --input DIR --k K --out-stats FILE [options]";
  s.text =
      R"(Tracks s_p (mean distance of each map point to its k nearest neighbours) and the normal
distribution of the valid s_p (s_p < s-limit) over a sequence folder, keyframe by keyframe.
The map point cloud at keyframe t is every point seen in keyframes 0..t: when the clouds carry
an `id` property (ORB-SLAM map-point ids) a point joins once, at its first position; without
ids every point of every keyframe is a new map point. Prints one summary line:
  keyframes N points N N N mu X sigma X seconds S
)";
  s.groups.push_back(
      {"options",
       {Option::text("--input", "DIR",
                     "sequence folder (poses.txt + clouds/*.ply), see `knnocc map --help`")
            .alias("-i")
            .required(),
        Option::integer("--k", "K", "neighbours per point")
            .alias("-k")
            .required()
            .at_least(1)
            .at_most(4096),
        Option::number("--s-limit", "X", "valid points have s < X")
            .fallback_text("no limit")
            .above(0),
        Option::number("--crop", "M",
                       "drop points farther than M from their sensor first (the paper keeps 4 m)")
            .fallback_text("no crop")
            .above(0),
        Option::text("--affected", "POLICY",
                     "how the points a change affects are found: exact, or paper (Alg. 1 as "
                     "written, for comparison)")
            .fallback("exact")
            .one_of({"exact", "paper"}),
        Option::number("--dr", "D", "Alg. 1's radius step (--affected paper)")
            .fallback("0.1")
            .above(0),
        Option::number("--s-max", "S", "Alg. 1's radius limit, larger than --dr (--affected paper)")
            .fallback("2")
            .above(0),
        Option::text("--out-stats", "FILE",
                     "one line per keyframe: index N mu sigma new removed affected microseconds")
            .required(),
        Option::text("--out-s", "FILE",
                     "at the end, one line per map point: id x y z s (world frame; s = nan while a "
                     "point has fewer than k neighbours), sorted by id"),
        memory_limit_option()},
       ""});
  return s;
}

}  // namespace

const CommandSpec& track_spec() {
  static const CommandSpec spec = make_track_spec();
  return spec;
}

namespace {

/// --out-s: one line per map point, sorted by id.
template <class Tracker>
void write_s_file(const std::string& path, const Tracker& tracker) {
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
  io::AtomicFile s_out(path);
  s_out.write("# id x y z s\n");
  char line[160];
  for (const Row& r : rows) {
    std::snprintf(line, sizeof line, "%llu %.6f %.6f %.6f %.9g\n",
                  static_cast<unsigned long long>(r.id), r.p.x, r.p.y, r.p.z, r.s);
    s_out.write(line);
  }
  s_out.commit();
}

template <class Policy>
int run_track_with(const Args& args, const Policy& policy) {
  const std::string input = args.str("--input");
  TrackerParams params;
  params.k = static_cast<std::size_t>(args.integer("--k"));
  params.s_limit = args.number("--s-limit", std::numeric_limits<double>::infinity());
  const double crop = args.number("--crop", -1.0);
  const std::string stats_path = args.str("--out-stats");
  const OutputList files = requested_outputs(args, {"--out-stats", "--out-s"});
  check_outputs(files);
  check_outputs_not_inputs(files, {{"--input", input}});
  use_memory_limit(args);

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
    io::keyframe_to_world(seq.pose(i), seq.load_cloud(i), crop, world, ids);
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
  if (args.has("--out-s")) write_s_file(args.str("--out-s"), tracker);
  out.commit();
  outputs.commit();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("keyframes %zu points %zu N %zu mu %.6f sigma %.6f seconds %.3f\n", keyframes,
              tracker.size(), tracker.N(), tracker.mu(), tracker.sigma(), seconds);
  return 0;
}

}  // namespace

int run_track(const Args& args) {
  if (args.str("--affected") == "exact") return run_track_with(args, ExactReverseKnn{});
  const PaperAnnulus annulus{args.number("--dr"), args.number("--s-max")};
  if (!(annulus.s_max > annulus.dr)) throw UsageError("--s-max must be larger than --dr");
  return run_track_with(args, annulus);
}

}  // namespace knnocc::cli
