// bench_tiles: maps larger than one process (docs/tiles.md), measured on the knnocc tool as a
// user runs it, each command a child process (wall time, peak resident memory):
//   1. identical: every model mapped into tiles and merged against the one-process .bt/.ot, on
//      TUM and the stereo ORB-SLAM2 keyframes (when ../shared/data has them) and the drive;
//   2. cost: the OctoMap model on TUM and the simulated drive, in one process (`map -o x.ot`)
//      and into tiles (`map --out-tiles`), then `merge`; time and peak memory, and their ratios;
//   3. one tile alone (what one task of a cluster maps): the largest tile of the drive mapped
//      from the kept rated keyframes in a forked child, its peak memory against the direct map's;
//   4. beyond memory: the drive's first scans at a finer resolution under --memory-limit into
//      tiles, then `info` and `view` of the tile set;
//   5. wide keys: the drive's first scans (inside OctoMap's key range) in 16-bit and 21-bit keys,
//      the same file; the whole drive into tiles, the points it could not map.
// The drive is `knnocc sim --scene drive` (default 2,100 scans, 8.4 km); its direct map at 0.1 m
// needs more memory than many machines have, so the one-process comparisons run at --res 0.2
// (--drive-res). Goals (issue: tiles): identical; tiles <= 1.2x the direct time; merge <= 2 tiles'
// size + 64 MB and <= 25 % of the direct peak; one tile <= 10 % of the direct peak.
//
// usage: bench_tiles --drive DIR [--data DIR] [--out DIR] [--drive-res R] [--depth D]
//                    [--fine-res R] [--fine-scans N] [--wide-scans N] [--skip SECTION]...
//        (build/bin/knnocc sim --scene drive --out DIR writes the drive; run from the root)

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include "bench_common.hpp"

#include <knnocc/tiles/rated_store.hpp>
#include <knnocc/tiles/tile_mapping.hpp>
#include <knnocc/tiles/tile_set.hpp>

namespace fs = std::filesystem;
using knnocc::bench::Child;
using knnocc::bench::run_process;

namespace {

struct Options {
  std::string tool = KNNOCC_TOOL_PATH, data = "../shared/data", drive, out = "build/bench_tiles";
  double drive_res = 0.2, fine_res = 0.05;
  int depth = 5;
  std::size_t fine_scans = 400, wide_scans = 300;
  std::set<std::string> skip;
};

Child tool(const Options& o, std::vector<std::string> args) {
  args.insert(args.begin(), o.tool);
  Child c = run_process(args);
  if (c.status != 0) {
    std::string line;
    for (const auto& a : args) line += a + " ";
    std::printf("  FAILED (status %d): %s\n", c.status, line.c_str());
  }
  return c;
}

bool same_file(const std::string& a, const std::string& b) {
  std::ifstream fa(a, std::ios::binary), fb(b, std::ios::binary);
  if (!fa || !fb) return false;
  return std::equal(std::istreambuf_iterator<char>(fa), std::istreambuf_iterator<char>(),
                    std::istreambuf_iterator<char>(fb), std::istreambuf_iterator<char>());
}

std::string last_line(const std::string& s, const char* prefix) {
  std::string out;
  std::size_t at = 0;
  while ((at = s.find(prefix, at)) != std::string::npos) {
    const std::size_t end = s.find('\n', at);
    out = s.substr(at, end == std::string::npos ? std::string::npos : end - at);
    at = end == std::string::npos ? s.size() : end;
  }
  return out;
}

// 1. Every model into tiles and merged, against the one-process files.
void identical(const Options& o) {
  std::printf("\n1. identical: merged tile sets against the one-process .bt and .ot\n");
  struct Set {
    std::string name, path;
    double res;
    std::vector<std::string> models;
  };
  std::vector<Set> sets;
  if (fs::exists(o.data + "/tum_fr2_pioneer_slam2"))
    sets.push_back(
        {"TUM", o.data + "/tum_fr2_pioneer_slam2", 0.05, {"octomap", "knn", "knn2022", "robust"}});
  if (fs::exists(o.data + "/orbslam2_stereo_keyframes"))
    sets.push_back({"stereo",
                    o.data + "/orbslam2_stereo_keyframes",
                    0.05,
                    {"octomap", "knn", "knn2022", "robust"}});
  sets.push_back({"drive", o.drive, o.drive_res, {"octomap"}});
  std::size_t checked = 0, differ = 0;
  for (const Set& s : sets)
    for (const std::string& m : s.models) {
      const std::string base = o.out + "/id_" + s.name + "_" + m, res = std::to_string(s.res);
      tool(o, {"map", "-i", s.path, "--res", res, "--model", m, "-o", base + ".bt", "-o",
               base + ".ot"});
      for (const int depth : {1, o.depth, 9}) {
        const std::string dir = base + "_tiles";
        fs::remove_all(dir);
        tool(o,
             {"map", "-i", s.path, "--res", res, "--model", m, "--out-tiles", dir, "--tile-depth",
              std::to_string(depth), "-o", base + "_t.bt", "-o", base + "_t.ot"});
        const bool same =
            same_file(base + ".bt", base + "_t.bt") && same_file(base + ".ot", base + "_t.ot");
        std::printf("  %-7s %-8s depth %2d: %s\n", s.name.c_str(), m.c_str(), depth,
                    same ? "identical" : "DIFFERENT");
        ++checked;
        differ += !same;
        fs::remove_all(dir);
      }
    }
  std::printf("  %zu tile sets, %zu differ (goal: 0)\n", checked, differ);
}

// 2. Time and memory of the OctoMap model, one process against tiles, and merging.
struct Cost {
  Child direct, tiled, merge;
  std::size_t tiles = 0;
};

Cost cost(const Options& o, const std::string& name, const std::string& input, double res,
          int depth) {
  const std::string base = o.out + "/cost_" + name, dir = base + "_tiles", r = std::to_string(res);
  fs::remove_all(dir);
  Cost c;
  c.direct = tool(o, {"map", "-i", input, "--res", r, "-o", base + ".ot"});
  c.tiled = tool(o, {"map", "-i", input, "--res", r, "--out-tiles", dir, "--tile-depth",
                     std::to_string(depth), "--keep-rated"});
  c.merge = tool(o, {"merge", dir, "-o", base + "_m.ot"});
  if (c.tiled.status == 0) c.tiles = knnocc::tiles::read_index(dir).tiles.size();
  std::printf("  %-6s res %g depth %d, %zu tiles:\n", name.c_str(), res, depth, c.tiles);
  std::printf("    one process  %8.2f s  peak %8.1f MB   (%s)\n", c.direct.seconds,
              c.direct.peak_mb, last_line(c.direct.output, "clouds ").c_str());
  std::printf("    into tiles   %8.2f s  peak %8.1f MB   time x%.2f (goal <= 1.2), memory x%.2f\n",
              c.tiled.seconds, c.tiled.peak_mb, c.tiled.seconds / c.direct.seconds,
              c.tiled.peak_mb / c.direct.peak_mb);
  std::printf(
      "    merge        %8.2f s  peak %8.1f MB   memory x%.2f of one process (goal <= "
      "0.25); the merged file %s\n",
      c.merge.seconds, c.merge.peak_mb, c.merge.peak_mb / c.direct.peak_mb,
      same_file(base + ".ot", base + "_m.ot") ? "is identical" : "DIFFERS");
  return c;
}

// 3. The largest tile of a tile set mapped alone from its rated keyframes, in a forked child.
void one_tile(const Options& o, const std::string& name, const Cost& c) {
  const std::string dir = o.out + "/cost_" + name + "_tiles";
  const knnocc::tiles::TileSetIndex ix = knnocc::tiles::read_index(dir);
  if (ix.tiles.empty()) return;
  const auto largest = *std::max_element(
      ix.tiles.begin(), ix.tiles.end(),
      [](const auto& a, const auto& b) { return a.occupied + a.free < b.occupied + b.free; });
  struct Result {
    double map_mb;
  };
  const auto [r, peak] = knnocc::bench::in_child([&] {
    const knnocc::tiles::RatedStore store = knnocc::tiles::RatedStore::open(dir + "/rated");
    const auto map_mb = [&](auto key) {  // the tile set's own key width
      const knnocc::TileGrid<decltype(key)> grid(ix.tile_depth);
      const auto tile = knnocc::tiles::map_tile(store, grid, largest.coord);
      return double(tile.map().memory_usage()) / 1e6;
    };
    return Result{ix.key_bits == 16 ? map_mb(knnocc::OcKey{}) : map_mb(knnocc::WideKey{})};
  });
  std::printf(
      "  %-6s largest tile of %zu alone: peak %.1f MB (its map %.1f MB), x%.3f of the "
      "one-process peak (goal <= 0.10)\n",
      name.c_str(), ix.tiles.size(), peak, r.map_mb, peak / c.direct.peak_mb);
  std::printf("         merge peak %.1f MB against 2 such tiles + 64 MB = %.1f MB\n",
              c.merge.peak_mb, 2 * r.map_mb + 64);
}

// 4. Finer than memory allows in one process: tiles under --memory-limit 1G.
void beyond_memory(const Options& o) {
  const std::string dir = o.out + "/fine_tiles";
  fs::remove_all(dir);
  std::printf("\n4. beyond memory: the drive's first %zu scans at %g m, --memory-limit 1G\n",
              o.fine_scans, o.fine_res);
  const Child t = tool(o, {"map", "-i", o.drive, "--res", std::to_string(o.fine_res), "--count",
                           std::to_string(o.fine_scans), "--out-tiles", dir, "--tile-depth", "7",
                           "--memory-limit", "1G"});
  std::printf("  into tiles: status %d, %.1f s, peak %.1f MB\n  %s\n", t.status, t.seconds,
              t.peak_mb, last_line(t.output, "clouds ").c_str());
  if (t.status != 0) return;
  const knnocc::tiles::TileSetIndex ix = knnocc::tiles::read_index(dir);
  std::uint64_t bytes = 0;
  for (const auto& e : ix.tiles) bytes += e.bytes;
  std::printf(
      "  %zu tiles, %.1f GB of tile files, %llu voxels (a one-process map of them needs "
      "at least %.1f GB: 4 bytes each)\n",
      ix.tiles.size(), double(bytes) / 1e9,
      static_cast<unsigned long long>(ix.occupied() + ix.free()),
      double(ix.occupied() + ix.free()) * 4 / 1e9);
  const Child info = tool(o, {"info", dir, "--memory-limit", "1G"});
  const Child view = tool(o, {"view", dir, "--out", o.out + "/fine.html", "--memory-limit", "1G"});
  std::printf("  info: status %d, %.1f s, peak %.1f MB; view: status %d, %.1f s, peak %.1f MB\n",
              info.status, info.seconds, info.peak_mb, view.status, view.seconds, view.peak_mb);
  fs::remove_all(dir);
}

// 5. Wide keys.
void wide_keys(const Options& o) {
  std::printf("\n5. wide keys\n");
  const std::string a = o.out + "/wide16.ot", b = o.out + "/wide21.ot";
  const std::string n = std::to_string(o.wide_scans);
  tool(o, {"map", "-i", o.drive, "--res", "0.1", "--count", n, "-o", a});
  tool(o, {"map", "-i", o.drive, "--res", "0.1", "--count", n, "--key-bits", "21", "-o", b});
  std::printf("  the first %zu scans at 0.1 m, 16-bit and 21-bit keys: %s\n", o.wide_scans,
              same_file(a, b) ? "the same .ot, byte for byte" : "DIFFERENT");
  const std::string dir = o.out + "/wide_tiles";
  fs::remove_all(dir);
  const Child t = tool(o, {"map", "-i", o.drive, "--res", "0.1", "--out-tiles", dir, "--tile-depth",
                           "4", "--memory-limit", "4G"});
  if (t.status == 0) {
    const knnocc::tiles::TileSetIndex ix = knnocc::tiles::read_index(dir);
    std::printf(
        "  the whole drive at 0.1 m into %zu tiles (%d-bit keys, --memory-limit 4G): %.1f s, "
        "peak %.1f MB, "
        "%llu of %llu points out of range (goal: 0)\n",
        ix.tiles.size(), ix.key_bits, t.seconds, t.peak_mb,
        static_cast<unsigned long long>(ix.totals.out_of_range),
        static_cast<unsigned long long>(ix.totals.points));
  }
  fs::remove_all(dir);
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_tiles: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--drive")
      o.drive = value();
    else if (a == "--data")
      o.data = value();
    else if (a == "--out")
      o.out = value();
    else if (a == "--drive-res")
      o.drive_res = std::atof(value().c_str());
    else if (a == "--fine-res")
      o.fine_res = std::atof(value().c_str());
    else if (a == "--depth")
      o.depth = std::atoi(value().c_str());
    else if (a == "--fine-scans")
      o.fine_scans = std::strtoul(value().c_str(), nullptr, 10);
    else if (a == "--wide-scans")
      o.wide_scans = std::strtoul(value().c_str(), nullptr, 10);
    else if (a == "--skip")
      o.skip.insert(value());
    else {
      std::printf(
          "usage: bench_tiles --drive DIR [--data DIR] [--out DIR] [--drive-res R] [--depth D]\n"
          "                   [--fine-res R] [--fine-scans N] [--wide-scans N]\n"
          "                   [--skip identical|cost|beyond|wide]...\n");
      return a == "--help" ? 0 : 2;
    }
  }
  if (o.drive.empty() || !fs::exists(o.drive + "/poses.txt")) {
    std::fprintf(stderr, "bench_tiles: --drive DIR (knnocc sim --scene drive --out DIR) needed\n");
    return 2;
  }
  fs::create_directories(o.out);
  std::printf("bench_tiles (%s build); tool %s; drive %s\n", KNNOCC_BENCH_BUILD_TYPE,
              o.tool.c_str(), o.drive.c_str());
  if (!o.skip.count("identical")) identical(o);
  if (!o.skip.count("cost")) {
    std::printf("\n2. cost (OctoMap model): one process against tiles and merge\n");
    if (fs::exists(o.data + "/tum_fr2_pioneer_slam2")) {
      const Cost tum = cost(o, "TUM", o.data + "/tum_fr2_pioneer_slam2", 0.05, 9);
      std::printf("\n3. one tile alone\n");
      one_tile(o, "TUM", tum);
    }
    const Cost drive = cost(o, "drive", o.drive, o.drive_res, o.depth);
    one_tile(o, "drive", drive);
  }
  if (!o.skip.count("beyond")) beyond_memory(o);
  if (!o.skip.count("wide")) wide_keys(o);
  return 0;
}
