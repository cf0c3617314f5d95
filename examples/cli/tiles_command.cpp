// knnocc merge and knnocc tile: a tile set (docs/tiles.md) into one OctoMap file as a stream, a
// map file into a tile set, and, only when asked, maps of different runs fused.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <knnocc/io/atomic_file.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/tiles/tile_merge.hpp>
#include <knnocc/tiles/tile_set.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "common_options.hpp"
#include "input_guard.hpp"
#include "map_colors.hpp"
#include "map_files.hpp"
#include "map_outputs.hpp"
#include "map_tiles.hpp"
#include "output_set.hpp"
#include "progress.hpp"
#include "resource_limits.hpp"
#include "tile_set_files.hpp"

namespace knnocc::cli {

namespace {

constexpr std::size_t kMaxFuseInputs = 256;

CommandSpec make_merge_spec() {
  CommandSpec s;
  s.name = "merge";
  s.summary = "a tile set into one OctoMap file, streamed (or maps of different runs, --fuse)";
  s.usage =
      "knnocc merge DIR -o MAP.bt|MAP.ot [options]\n"
      "       knnocc merge MAP1 MAP2... --fuse -o MAP.bt|MAP.ot";
  s.text =
      R"(Joins the tile set in DIR (knnocc map --out-tiles, knnocc tile) into one OctoMap file, holding
about one tile in memory: the tree above the tiles is planned from the index, then each tile is
read, checked (size, SHA-256, resolution, voxels inside its tile, the index's summary of it) and
streamed in the file's node order. The file is byte for byte the one `knnocc map -o MAP.bt`
writes for the same run. A tile set of 21-bit keys that reaches beyond OctoMap's key range is
refused with its extent and the finest resolution that would hold it. Prints
  merged N tiles nodes N bytes N seconds S
Maps of different runs that overlap cannot be merged exactly (clamping applies after every
update, so the order of all updates matters): several inputs are refused unless --fuse, which
adds the inputs' log-odds per voxel (a voxel known in any input) and clamps the sum into the
clamping range once. That is an approximation: it does not equal mapping both runs.
)";
  s.groups.push_back(
      {"options",
       {Option::text("--output", "FILE", "the merged map: .bt or .ot").alias("-o").required(),
        Option::flag("--fuse",
                     "several maps (.bt, .ot or tile sets of one resolution): per-voxel sum of "
                     "log-odds, clamped (not equal to mapping the runs together)"),
        memory_limit_option()},
       ""});
  s.footer =
      "exit status: 0 success, 2 bad input (one line on stderr naming the file and the problem).\n";
  s.max_positional = kMaxFuseInputs;
  s.positional_limit_why = "inputs to --fuse";
  return s;
}

CommandSpec make_tile_spec() {
  CommandSpec s;
  s.name = "tile";
  s.summary = "a .bt/.ot map cut into a tile set (one .ot per tile and an index)";
  s.usage = "knnocc tile MAP --out-tiles DIR [--tile-depth D | --tile-size M]";
  s.text =
      R"(Cuts a map file into the tiles of --tile-depth (nodes of OctoMap's tree at that depth) and
writes them as a tile set: DIR/index.txt and one .ot per tile that holds voxels (octovis opens
each). knnocc merge DIR -o MAP.ot then gives MAP's own bytes for a map knnocc wrote. Prints
  tiles N depth D edge_m E occupied N free N
)";
  s.groups.push_back(
      {"options",
       {Option::text("--out-tiles", "DIR", "the tile set: a new or empty folder, or a tile set")
            .required(),
        Option::integer("--tile-depth", "D", "2^(16-D) voxels per tile edge (0: one tile)")
            .fallback("6")
            .at_least(0)
            .at_most(13),
        Option::number("--tile-size", "M",
                       "instead of --tile-depth: the largest tile edge not above M metres")
            .above(0),
        memory_limit_option()},
       ""});
  s.footer =
      "exit status: 0 success, 2 bad input (one line on stderr naming the file and the problem).\n";
  s.max_positional = 1;
  return s;
}

}  // namespace

const CommandSpec& merge_spec() {
  static const CommandSpec spec = make_merge_spec();
  return spec;
}
const CommandSpec& tile_spec() {
  static const CommandSpec spec = make_tile_spec();
  return spec;
}

namespace {

/// -o's format: true for .bt; UsageError for anything but .bt/.ot.
bool binary_output(const std::string& out) {
  const std::string e = lower_extension(out);
  if (e != ".bt" && e != ".ot")
    throw UsageError("-o " + out + ": merge writes an OctoMap .bt or .ot file");
  return e == ".bt";
}

/// One input of --fuse as a map: a map file, or a tile set read tile by tile.
OccupancyMap<OcKey> read_fuse_input(const std::string& in) {
  if (is_tile_set_path(in)) {
    const tiles::TileSetIndex ix = tiles::read_index(in);
    OccupancyMap<OcKey> map(ix.resolution, ix.params.occupancy);
    tiles::detail::check_fits_octomap(in, ix);
    for (const tiles::TileEntry& e : ix.tiles) {
      const OccupancyMap<OcKey> t = reading(
          in, [&] { return tiles::read_tile<OcKey>(in, ix, e, 0, /*as_octomap_keys=*/true); });
      t.for_each_voxel([&](const OcKey& k, float v) { map.set(k, v); });
    }
    return map;
  }
  if (!is_tree_file(in)) throw io::Error(in, "not a .bt/.ot map or a tile set folder");
  OccupancyMap<OcKey> map = read_tree_checked(in, {}, nullptr);
  // The header says it: expanding the colours of every voxel only to print this would cost as
  // much memory again as the map.
  if (io::inspect_octree(in).id == "ColorOcTree")
    std::fprintf(stderr,
                 "knnocc merge: %s: note: a ColorOcTree, its colours are not kept (--fuse adds "
                 "log-odds; the fused map has no colours)\n",
                 io::printable(in).c_str());
  return map;
}

/// --fuse: the per-voxel sum of the inputs' log-odds, clamped once.
int fuse(const Args& args, const std::string& out) {
  const std::vector<std::string>& ins = args.positional();
  const OccupancyMap<OcKey> first = read_fuse_input(ins[0]);
  OccupancyParams unclamped = first.params();  // the sums, clamped at the end
  unclamped.clamp_min = -std::numeric_limits<float>::max();
  unclamped.clamp_max = std::numeric_limits<float>::max();
  OccupancyMap<OcKey> sum(first.resolution(), unclamped);
  auto add = [&](const OccupancyMap<OcKey>& m, const std::string& name) {
    if (m.resolution() != first.resolution())
      throw io::Error(name, "resolution " + io::detail::round_trip_text(m.resolution()) +
                                " differs from " + ins[0] + "'s " +
                                io::detail::round_trip_text(first.resolution()));
    m.for_each_voxel([&](const OcKey& k, float v) {
      const std::optional<float> s = sum.logodds(k);
      sum.set(k, (s ? *s : 0.0f) + v);
    });
  };
  add(first, ins[0]);
  for (std::size_t i = 1; i < ins.size(); ++i) add(read_fuse_input(ins[i]), ins[i]);
  OccupancyMap<OcKey> fused(first.resolution(), first.params());
  sum.for_each_voxel([&](const OcKey& k, float v) { fused.set(k, v); });  // clamped once
  binary_output(out) ? io::write_bt(out, fused) : io::write_ot(out, fused);
  const auto c = fused.count_voxels();
  std::printf("fused %zu maps voxels %zu occupied %zu free %zu\nwrote %s\n", ins.size(), c.known(),
              c.occupied, c.free, io::printable(out).c_str());
  return 0;
}

}  // namespace

int run_merge(const Args& args) {
  const std::vector<std::string>& ins = args.positional();
  if (ins.empty()) throw UsageError("needs a tile set folder (see --help)");
  const std::string out = args.str("--output");
  binary_output(out);
  OutputList inputs;
  for (const std::string& in : ins) inputs.emplace_back("IN", in);
  check_outputs({{"-o", out}});
  check_outputs_not_inputs({{"-o", out}}, inputs);
  use_memory_limit(args);
  if (args.flag("--fuse")) {
    if (ins.size() < 2) throw UsageError("--fuse needs two or more maps");
    return fuse(args, out);
  }
  if (ins.size() > 1)
    throw UsageError(
        "merging maps of different runs is not exact (clamping applies after every update, so "
        "the order of all updates matters); knnocc merge joins the tiles of one run. --fuse adds "
        "the maps' log-odds instead (docs/tiles.md), which does not equal mapping the runs "
        "together");
  if (!is_tile_set_path(ins[0]))
    throw io::Error(ins[0], is_tree_file(ins[0])
                                ? "is one map file already (knnocc convert rewrites it)"
                                : "not a tile set folder (no index.txt of a tile set)");
  const auto t0 = std::chrono::steady_clock::now();
  const tiles::TileSetIndex ix = tiles::read_index(ins[0]);
  Progress progress("merge", ix.tiles.size());
  const tiles::MergeStats st = reading(ins[0], [&] {
    return tiles::merge_tile_set(ins[0], out, binary_output(out),
                                 map_memory_share(memory_limit_bytes()),
                                 [&](std::size_t done) { progress.update(done); });
  });
  progress.finish();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("merged %zu tiles nodes %llu bytes %llu seconds %.3f\nwrote %s\n", st.tiles,
              static_cast<unsigned long long>(st.nodes), static_cast<unsigned long long>(st.bytes),
              seconds, io::printable(out).c_str());
  return 0;
}

int run_tile(const Args& args) {
  if (args.positional().size() != 1) throw UsageError("needs one MAP (.bt or .ot)");
  const std::string in = args.positional()[0], dir = args.str("--out-tiles");
  if (!is_tree_file(in)) throw UsageError(in + ": knnocc tile cuts a .bt or .ot map");
  if (args.has("--tile-depth") && args.has("--tile-size"))
    throw UsageError("give --tile-depth or --tile-size, not both");
  check_outputs_not_inputs({{"--out-tiles", dir}}, {{"MAP", in}});
  io::StagingDir::check_target(dir, tiles::is_tile_set);
  use_memory_limit(args);
  const OccupancyMap<OcKey> map = read_tree_checked(in, {}, nullptr);
  if (io::inspect_octree(in).id == "ColorOcTree")  // without expanding every voxel's colour
    note_colors_not_kept("tile", in, "ColorOcTree", {dir}, "a tile set keeps none");
  const int depth = args.has("--tile-size")
                        ? depth_for_tile_size(args.number("--tile-size"), map.resolution(), 16)
                        : static_cast<int>(args.integer("--tile-depth"));
  io::StagingDir staging(dir, tiles::is_tile_set);
  tiles::TileSetIndex ix;
  ix.resolution = map.resolution();
  ix.key_bits = 16;
  ix.tile_depth = depth;
  ix.params.occupancy = map.params();
  ix.model = "cut from a map file";
  ix.source = in;
  Progress progress("tile", 1);
  ix.tiles = tiles::write_tiles_of(map, staging.path(), TileGrid<OcKey>(depth),
                                   [&](std::size_t done, std::size_t of) {
                                     progress.retotal(of);
                                     progress.update(done);
                                   });
  progress.finish();
  tiles::write_index(staging.path(), ix);
  staging.commit();
  std::printf("tiles %zu depth %d edge_m %g occupied %llu free %llu\nwrote %s\n", ix.tiles.size(),
              depth, std::ldexp(map.resolution(), 16 - depth),
              static_cast<unsigned long long>(ix.occupied()),
              static_cast<unsigned long long>(ix.free()), io::printable(dir).c_str());
  return 0;
}

}  // namespace knnocc::cli
