#pragma once
// knnocc map --out-tiles DIR: the run as a tile set (include/knnocc/tiles/, docs/tiles.md). Every
// scan is rated once, in order, into a folder of rated keyframes inside the staged output; then
// the tiles the keyframes reach are mapped, as many at once as the memory limit allows, each from
// the keyframes that reach it, and written; the index is written last, the -o files are merged
// from the staged tiles, and the folder is committed as a whole. Coloured clouds: the tiles keep
// no colours (plain OcTrees; a note says so). Maps
// beyond OctoMap's 16-bit key range use 21-bit keys (--key-bits 21, or chosen from the poses).

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <knnocc/io/atomic_file.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/scan_source.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/tiles/rating_pass.hpp>
#include <knnocc/tiles/tile_mapping.hpp>
#include <knnocc/tiles/tile_merge.hpp>

#include "args.hpp"
#include "map_options.hpp"
#include "map_run.hpp"
#include "output_set.hpp"
#include "progress.hpp"
#include "resource_limits.hpp"

namespace knnocc::cli {

/// How a run is cut into tiles.
struct TileOptions {
  std::string dir;          ///< --out-tiles ("" without)
  int depth = 6;            ///< tile depth in OctoMap's tree (--tile-depth, or from --tile-size)
  int key_bits = 16;        ///< 16 or 21
  bool keep_rated = false;  ///< --keep-rated
};

/// The options of a map into tiles (map --help's "tiles" group).
inline OptionGroup map_tiles_group() {
  return {
      "tiles (maps larger than one process; docs/tiles.md)",
      {Option::text("--out-tiles", "DIR",
                    "write the map as a tile set: DIR/index.txt and one OctoMap .ot per tile "
                    "(octovis opens each), every scan rated once, then one tile mapped at a "
                    "time; a new or empty folder, or an earlier tile set (replaced). -o/--out-bt "
                    "/--out-ot files are then merged from the tiles (knnocc merge)"),
       Option::integer("--tile-depth", "D",
                       "tiles are the octree's nodes at depth D of OctoMap's 16-level tree: "
                       "2^(16-D) voxels per edge (0: one tile)")
           .fallback("6")
           .at_least(0)
           .at_most(13),
       Option::number("--tile-size", "M",
                      "instead of --tile-depth: the depth whose tile edge is the largest not "
                      "above M metres")
           .above(0),
       Option::flag("--keep-rated",
                    "keep the rated keyframes in DIR/rated (rated.txt and one .rkf per cloud): "
                    "what mapping any tile again, alone or elsewhere, reads (docs/tiles.md)"),
       Option::text("--key-bits", "BITS",
                    "16 (OctoMap's keys: +-32768 voxels) or 21 (+-2^20 voxels, tile sets only); "
                    "by default 16, or 21 with a note when the poses go beyond 16 bits' range")
           .fallback_text("16, or 21 from the poses")
           .one_of({"16", "21"})},
      "  The tile set equals the one-process map: `knnocc merge DIR -o MAP.bt` gives the bytes "
      "of\n  `knnocc map -o MAP.bt`. Prints `tiles N depth D edge_m E key_bits K` before the "
      "summary.\n"};
}

/// The tile depth whose tiles' edge is the largest not above `metres` at `res` (at least a brick,
/// at most OctoMap's whole key range, or half of it with wide keys).
inline int depth_for_tile_size(double metres, double res, int key_bits) {
  int depth = key_bits == 16 ? 0 : 1;
  while (depth < 13 && std::ldexp(res, 16 - depth) > metres) ++depth;
  return depth;
}

/// --key-bits: given, or 16 unless the sensors travel beyond 16-bit keys' range: then 21 for a
/// tile set, with a note; a map in one process (one .bt/.ot holds 16-bit keys only) keeps 16 bits
/// and a note says that the points beyond are skipped and what maps them.
inline int choose_key_bits(const Args& args, const MapOptions& opt, bool tiles) {
  const std::string given = args.str("--key-bits");
  if (given == "16" || given == "21") return given == "21" ? 21 : 16;
  if (!(opt.res > 0)) return 16;  // --init-map: the map file's own keys
  double reach = 0.0;
  try {
    const io::ScanSource source = io::ScanSource::open(opt.input);
    reach = io::sensor_reach(source, opt.first, last_cloud(opt, source));
  } catch (const std::exception&) {
    return 16;  // the run itself says what is wrong with the input
  }
  const double margin = opt.crop > 0 ? opt.crop : opt.max_range > 0 ? opt.max_range : 0.0;
  const double range = 32768.0 * opt.res;
  if (reach + margin < range) return 16;
  char text[300];
  std::snprintf(text, sizeof text,
                "the sensor travels %.1f m from the origin, beyond the +-%.1f m of OctoMap's "
                "16-bit keys at --res %g",
                reach, range, opt.res);
  if (!tiles) {
    std::fprintf(stderr,
                 "knnocc map: %s: note: %s: points there are skipped (--out-tiles DIR maps them "
                 "with 21-bit keys)\n",
                 opt.input.c_str(), text);
    return 16;
  }
  std::fprintf(stderr, "knnocc map: %s: %s: mapping with 21-bit keys (--key-bits 21)\n",
               opt.input.c_str(), text);
  return 21;
}

/// The tile options of a run, checked against the others; dir empty without --out-tiles.
inline TileOptions tile_options(const Args& args, const MapOptions& opt) {
  TileOptions t;
  t.dir = args.str("--out-tiles");
  const bool tiles = !t.dir.empty();
  if (!tiles) {
    for (const char* flag : {"--tile-depth", "--tile-size", "--keep-rated"})
      if (args.has(flag)) throw UsageError(std::string(flag) + " needs --out-tiles DIR");
    t.key_bits = choose_key_bits(args, opt, false);
    if (t.key_bits == 21) {
      for (const char* flag : {"--init-map", "--save-every", "--corrections"})
        if (args.has(flag)) throw UsageError(std::string(flag) + " needs 16-bit keys");
      for (const MapFile& f : opt.files)
        if (f.format != MapFormat::bt && f.format != MapFormat::ot)
          throw UsageError(f.option + " " + f.path +
                           ": with --key-bits 21 and no --out-tiles only .bt/.ot files are "
                           "written (when the map fits OctoMap's key range)");
    }
    return t;
  }
  for (const char* flag : {"--init-map", "--save-every", "--corrections"})
    if (args.has(flag))
      throw UsageError(std::string(flag) + " cannot be combined with --out-tiles");
  for (const MapFile& f : opt.files)
    if (f.format != MapFormat::bt && f.format != MapFormat::ot)
      throw UsageError(f.option + " " + f.path +
                       ": with --out-tiles only .bt/.ot files are written (merged from the "
                       "tiles); knnocc view and convert read the tile set for the others");
  // A file inside the tile set's folder would go with the folder when a later run replaces it.
  const std::filesystem::path folder = std::filesystem::weakly_canonical(t.dir);
  for (const MapFile& f : opt.files) {
    const auto rel = std::filesystem::weakly_canonical(f.path).lexically_relative(folder);
    if (!rel.empty() && *rel.begin() != "..")
      throw UsageError(f.option + " " + f.path + ": inside the --out-tiles folder " + t.dir +
                       "; write it beside the tile set");
  }
  if (args.has("--tile-depth") && args.has("--tile-size"))
    throw UsageError("give --tile-depth or --tile-size, not both");
  t.key_bits = choose_key_bits(args, opt, true);
  t.keep_rated = args.flag("--keep-rated");
  if (args.has("--tile-depth")) t.depth = static_cast<int>(args.integer("--tile-depth"));
  if (args.has("--tile-size"))
    t.depth = depth_for_tile_size(args.number("--tile-size"), opt.res, t.key_bits);
  if (t.key_bits == 21 && t.depth == 0)
    throw UsageError("--tile-depth 0 (one tile of OctoMap's whole key range) needs 16-bit keys");
  return t;
}

namespace detail {

// The rating pass into `rated`; returns its totals (for the summary) and fills `totals`.
template <class Model, class Key>
tiles::RatingTotals rate_run(const MapOptions& opt, Mapper<Model, Key>& rater,
                             const std::string& rated, MapRun& run, MapTotals& totals,
                             bool& coloured) {
  const io::ScanSource source = io::ScanSource::open(opt.input);
  const std::size_t last = last_cloud(opt, source);
  tiles::RatedStoreWriter<Key> writer(rated, opt.res);
  Progress progress("rate", last - opt.first);
  std::size_t at = opt.first;
  auto prepare = [&](io::Scan& scan, std::size_t i) {
    at = i;
    run.prepare(scan, rater.map().grid(), source_path_for_errors(opt.input, i));
    if (!scan.cloud.colors.empty()) coloured = true;
    if constexpr (std::is_same_v<Model, RobustModel>)
      if (!scan.cloud.has_ids() && !scan.cloud.points.empty()) run.note_missing_ids();
  };
  auto rated_one = [&](std::size_t i, const KeyframeStats& ks, double ms) {
    totals.rays += ks.rays;
    totals.rated += ks.rated;
    totals.keyframe_ms.push_back(ms);
    progress.update(i + 1 - opt.first);
  };
  try {
    const tiles::RatingTotals t =
        tiles::rate_sequence(source, opt.first, last, rater, writer, prepare, rated_one);
    progress.finish();
    totals.clouds = t.clouds;
    totals.scan.points = t.points;
    totals.scan.nonfinite = t.nonfinite;
    totals.scan.out_of_range = t.out_of_range;
    return t;
  } catch (const std::invalid_argument& e) {  // e.g. clouds with and without ids mixed
    throw io::Error(source_path_for_errors(opt.input, at), e.what());
  } catch (const std::bad_alloc&) {
    throw io::Error(source_path_for_errors(opt.input, at),
                    out_of_memory_text(opt.memory_limit, "rating it", opt.res));
  }
}

// The .bt/.ot files asked for besides the tile set, merged from it as a stream.
inline void merge_outputs(const MapOptions& opt, const std::string& dir,
                          std::vector<std::string>& written) {
  for (const MapFile& f : opt.files) {
    try {
      tiles::merge_tile_set(dir, f.path, f.format == MapFormat::bt,
                            map_memory_share(opt.memory_limit));
    } catch (const io::Error& e) {
      if (e.file() != dir) throw;
      throw io::Error(f.path, e.problem());  // not the staged folder's name: the file asked for
    }
    written.push_back(f.path);
  }
}

}  // namespace detail

/// The run as a tile set (see the file comment); prints the model's line, a tiles line and the
/// summary line as `knnocc map` does.
template <class Model, class Key>
int run_map_tiles(const MapOptions& opt, const Model& model, const TileOptions& t,
                  const std::string& model_options) {
  const auto t0 = std::chrono::steady_clock::now();
  io::StagingDir staging(t.dir, tiles::is_tile_set);  // a non-empty other folder: refused now
  const std::string rated = (std::filesystem::path(staging.path()) / "rated").string();
  std::filesystem::create_directory(rated);
  const MapperOptions mo{opt.max_range, opt.discretize, opt.threads, opt.occupancy};
  Mapper<Model, Key> rater(opt.res, model, mo);
  MapRun run(opt.scans, opt.res);
  MapTotals totals;
  bool coloured = false;
  detail::rate_run(opt, rater, rated, run, totals, coloured);
  const tiles::RatedStore store = tiles::RatedStore::open(rated);
  const tiles::RunDescription what{model_name(model), model_options, opt.input, opt.first,
                                   totals.clouds};
  Progress progress("tiles", 1);
  const tiles::TileSetIndex ix = tiles::write_tile_set<Key>(
      store, staging.path(), t.depth, what, opt.threads, map_memory_share(opt.memory_limit),
      [&](std::size_t done, std::size_t of) {
        progress.retotal(of);
        progress.update(done);
      });
  progress.finish();
  if (!t.keep_rated) std::filesystem::remove_all(rated);
  std::vector<std::string> written{t.dir};
  {
    // The merged files are written before the tile set is committed and renamed after it: a merge
    // that fails (a map beyond OctoMap's key range, a file that cannot be written) leaves nothing.
    io::CommitGroup group;
    detail::merge_outputs(opt, staging.path(), written);
    staging.commit();
    group.commit();
  }
  if (coloured && opt.scans.colors)
    std::fprintf(stderr,
                 "knnocc map: %s: note: the clouds have colours; a tile set keeps none (plain "
                 "OcTrees; without --out-tiles an .ot is a ColorOcTree)\n",
                 opt.input.c_str());
  note_skipped_points(opt.input, totals.scan.nonfinite, totals.scan.out_of_range,
                      rater.map().grid().max_coord(), rater.map().grid().resolution());
  note_empty_map(opt.input, totals.clouds, totals.scan.points, ix.occupied() + ix.free(), model);
  print_model_line(rater, opt, totals);
  std::printf("tiles %zu depth %d edge_m %g key_bits %d\n", ix.tiles.size(), t.depth,
              std::ldexp(opt.res, 16 - t.depth), t.key_bits);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("clouds %zu points %zu occupied %llu free %llu seconds %.3f\n", totals.clouds,
              totals.scan.points, static_cast<unsigned long long>(ix.occupied()),
              static_cast<unsigned long long>(ix.free()), seconds);
  print_written(written);
  return 0;
}

/// A map of 21-bit keys as one OctoMap file: where every voxel lies inside OctoMap's key range it
/// is written at OctoMap's keys (the 16-bit map's bytes); otherwise io::Error naming the extent.
template <class Key>
void write_wide_tree(const OccupancyMap<Key>& map, const MapFile& f) {
  constexpr std::int64_t shift = Key::center - OcKey::center;
  std::int64_t reach = 0;
  map.for_each_voxel([&](const Key& k, float) {
    for (int a = 0; a < 3; ++a)
      reach =
          std::max({reach, Key::center - std::int64_t{k[a]}, std::int64_t{k[a]} + 1 - Key::center});
  });
  if (reach > 32768) {
    char text[300];
    std::snprintf(text, sizeof text,
                  "the map reaches %.1f m from its origin, beyond the +-%.1f m a .bt/.ot holds at "
                  "--res %g: write it as a tile set (--out-tiles DIR)",
                  double(reach) * map.resolution(), 32768.0 * map.resolution(), map.resolution());
    throw io::Error(f.path, text);
  }
  const std::array<std::int64_t, 3> s{shift, shift, shift};
  io::AtomicFile out(f.path);
  if (f.format == MapFormat::bt)
    out.write(io::detail::OctreeEncoder<false, false, Key>(map, "", {}, s).encode());
  else
    out.write(io::detail::OctreeEncoder<true, false, Key>(map, "", {}, s).encode());
  out.commit();
}

/// The run in one process with 21-bit keys (--key-bits 21 without --out-tiles): the summary line,
/// and .bt/.ot files where the map fits OctoMap's key range.
template <class Model>
int run_map_wide(const MapOptions& opt, const Model& model) {
  const auto t0 = std::chrono::steady_clock::now();
  const MapperOptions mo{opt.max_range, opt.discretize, opt.threads, opt.occupancy};
  Mapper<Model, WideKey> mapper(opt.res, model, mo);
  mapper.map().set_memory_limit(map_memory_share(opt.memory_limit));
  const io::ScanSource source = io::ScanSource::open(opt.input);
  const std::size_t last = last_cloud(opt, source);
  MapRun run(opt.scans, opt.res);
  MapTotals totals;
  tiles::WorldScan w;
  bool coloured = false;
  Progress progress("map", last - opt.first);
  for (std::size_t i = opt.first; i < last; ++i) try {
      io::Scan scan = source.load(i);
      run.prepare(scan, mapper.map().grid(), source_path_for_errors(opt.input, i));
      coloured = coloured || !scan.cloud.colors.empty();
      if constexpr (std::is_same_v<Model, RobustModel>)
        if (!scan.cloud.has_ids() && !scan.cloud.points.empty()) run.note_missing_ids();
      w.load<Mapper<Model, WideKey>>(scan);
      const auto a = std::chrono::steady_clock::now();
      totals.add(w.insert(mapper));
      totals.keyframe_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count());
      progress.update(i + 1 - opt.first);
    } catch (const std::invalid_argument& e) {
      throw io::Error(source_path_for_errors(opt.input, i), e.what());
    } catch (const std::bad_alloc&) {
      throw io::Error(source_path_for_errors(opt.input, i),
                      out_of_memory_text(opt.memory_limit, "mapping it", opt.res));
    }
  progress.finish();
  std::vector<std::string> written;
  {
    io::CommitGroup group;
    for (const MapFile& f : opt.files) {
      write_wide_tree(mapper.map(), f);
      written.push_back(f.path);
    }
    group.commit();
  }
  if (coloured && opt.scans.colors && !written.empty())
    std::fprintf(stderr,
                 "knnocc map: %s: note: the clouds have colours; a 21-bit map keeps none (plain "
                 "OcTrees; with 16-bit keys an .ot is a ColorOcTree)\n",
                 io::printable(opt.input).c_str());
  const ScanStats& total = totals.scan;
  note_skipped_points(opt.input, total.nonfinite, total.out_of_range,
                      mapper.map().grid().max_coord(), mapper.map().grid().resolution());
  const auto counts = mapper.map().count_voxels();
  note_empty_map(opt.input, totals.clouds, total.points, counts.known(), model);
  print_model_line(mapper, opt, totals);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("clouds %zu points %zu occupied %zu free %zu seconds %.3f\n", totals.clouds,
              total.points, counts.occupied, counts.free, seconds);
  print_written(written);
  return 0;
}

}  // namespace knnocc::cli
