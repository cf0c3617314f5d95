#pragma once
// Tile sets where the tool's commands take maps (info, view, convert): a tile set read tile by
// tile into one map for pictures, pages and voxel files, without merging it into one file first.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include <knnocc/io/error.hpp>
#include <knnocc/map/occupancy_map.hpp>
#include <knnocc/tiles/tile_set.hpp>

#include "progress.hpp"
#include "resource_limits.hpp"

namespace knnocc::cli {

/// Whether `path` is a tile set folder (index.txt says so).
inline bool is_tile_set_path(const std::string& path) { return tiles::is_tile_set(path); }

/// A tile set as one map for what shows or lists voxels (`command` names the caller in notes):
///   - every voxel when `free_too` and they fit the map's share of --memory-limit (the index
///     counts them), else the occupied voxels only (a note says so);
///   - a map of 21-bit keys beyond OctoMap's key range at the finest coarser resolution (a power
///     of two times the tile set's) that holds it: a cell is occupied when a voxel in it is, with
///     the largest log-odds of them (a note says so).
inline OccupancyMap<OcKey> read_tile_set_map(const std::string& dir, bool free_too,
                                             const char* command) {
  const tiles::TileSetIndex ix = tiles::read_index(dir);
  const double share = double(map_memory_share(memory_limit_bytes()));
  const double bytes = double(ix.occupied() + ix.free()) * 5.0;  // a voxel's float and bits
  const bool with_free = free_too && (share <= 0 || bytes < share);
  if (free_too && !with_free)
    std::fprintf(stderr,
                 "knnocc %s: %s: its %llu voxels need about %s, more than the map's share of "
                 "--memory-limit: occupied voxels only\n",
                 command, dir.c_str(), static_cast<unsigned long long>(ix.occupied() + ix.free()),
                 format_bytes(bytes).c_str());
  // How far the tiles reach from coordinate 0, in voxels: the coarsening that fits 16-bit keys.
  const std::int64_t center = ix.key_bits == 16 ? OcKey::center : WideKey::center;
  std::int64_t reach = 0;
  for (const tiles::TileEntry& t : ix.tiles)
    for (std::size_t a = 0; a < 3; ++a)
      reach = std::max({reach, center - t.keys[a], t.keys[a + 3] + 1 - center});
  int shift = 0;
  while ((reach >> shift) > 32768) ++shift;
  const double res = std::ldexp(ix.resolution, shift);
  if (shift > 0)
    std::fprintf(stderr,
                 "knnocc %s: %s: the map reaches %.1f m from its origin, beyond OctoMap's key "
                 "range at %g m: shown at %g m (a cell occupied where a voxel in it is)\n",
                 command, dir.c_str(), double(reach) * ix.resolution, ix.resolution, res);
  OccupancyMap<OcKey> out(res, ix.params.occupancy);
  Progress progress(command, ix.tiles.size());
  auto add = [&](const auto& key, float v, bool occupied) {
    if (!occupied && (!with_free || shift > 0)) return;
    OcKey k;
    for (int a = 0; a < 3; ++a)
      k[a] = static_cast<std::uint16_t>(((std::int64_t(key[a]) - center) >> shift) + 32768);
    const std::optional<float> old = out.logodds(k);
    if (!old || v > *old) out.set(k, v);
  };
  for (std::size_t i = 0; i < ix.tiles.size(); ++i) {
    reading(dir, [&] {
      if (ix.key_bits == 16) {
        const OccupancyMap<OcKey> t = tiles::read_tile<OcKey>(dir, ix, ix.tiles[i]);
        t.for_each_voxel([&](const OcKey& k, float v) { add(k, v, t.is_occupied(v)); });
      } else {
        const OccupancyMap<WideKey> t = tiles::read_tile<WideKey>(dir, ix, ix.tiles[i]);
        t.for_each_voxel([&](const WideKey& k, float v) { add(k, v, t.is_occupied(v)); });
      }
      return 0;
    });
    progress.update(i + 1);
  }
  progress.finish();
  return out;
}

}  // namespace knnocc::cli
