// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Mapping tiles from a folder of rated keyframes (tiles/rated_store.hpp): the tiles a run
// reaches; a box of tiles mapped from the keyframes that can reach it (each clipped to the box:
// a scan from inside is walked whole, a ray from outside from its first voxel inside, with the
// keys of the whole walk); and a whole tile set written, its tiles mapped together as far as a
// memory limit allows. Another process, or another machine sharing the folder, can map any tile
// alone (map_tile; knnocc.dask does).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <new>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "../core/memory_limit.hpp"
#include "rated_store.hpp"
#include "tile_grid.hpp"
#include "tile_integrator.hpp"
#include "tile_set.hpp"

namespace knnocc::tiles {

/// The tiles that the keyframes of `store` can reach, in the order of OctoMap's files.
template <class Key>
std::vector<TileCoord> tiles_reached(const RatedStore& store, const TileGrid<Key>& grid) {
  std::set<TileCoord> seen;
  for (std::size_t i = 0; i < store.size(); ++i) {
    const auto& r = store.entry(i).reach;
    if (!r) continue;
    using I = typename Key::index_type;
    const KeyBounds<Key> b{
        Key(static_cast<I>((*r)[0]), static_cast<I>((*r)[1]), static_cast<I>((*r)[2])),
        Key(static_cast<I>((*r)[3]), static_cast<I>((*r)[4]), static_cast<I>((*r)[5]))};
    grid.for_each_tile(b, [&](const TileCoord& c) { seen.insert(c); });
  }
  std::vector<TileCoord> out(seen.begin(), seen.end());
  grid.morton_order(out);
  return out;
}

/// A box of tiles, first and last per axis.
struct TileBox {
  TileCoord lo, hi;
  std::int64_t count() const {
    return (hi.t[0] - lo.t[0] + 1) * (hi.t[1] - lo.t[1] + 1) * (hi.t[2] - lo.t[2] + 1);
  }
};

/// The tiles of `box` of the run in `store`, mapped together: the keyframes that can reach the box,
/// in order, each clipped to it. `memory_limit` bounds the map (0: none; more is a
/// MemoryLimitError); progress(keyframes done, of) after each keyframe.
template <class Key>
TileIntegrator<Key> map_tiles(const RatedStore& store, const TileGrid<Key>& grid,
                              const TileBox& box, unsigned threads = 1,
                              std::size_t memory_limit = 0,
                              const std::function<void(std::size_t, std::size_t)>& progress = {}) {
  if (store.key_bits() != Key::depth)
    throw io::Error(store.dir(), "rated keyframes of " + std::to_string(store.key_bits()) +
                                     "-bit keys, not " + std::to_string(Key::depth));
  const KeyBounds<Key> b{grid.bounds(box.lo).lo, grid.bounds(box.hi).hi};
  TileIntegrator<Key> tiles(store.resolution(), store.params(), b, threads);
  tiles.map().set_memory_limit(memory_limit);
  const std::vector<std::size_t> which =
      store.reaching({b.lo[0], b.lo[1], b.lo[2], b.hi[0], b.hi[1], b.hi[2]});
  RatedKeyframe rk;
  for (std::size_t j = 0; j < which.size(); ++j) {
    store.load(which[j], rk);
    tiles.integrate(rk);
    if (progress) progress(j + 1, which.size());
  }
  return tiles;
}

/// Tile `c` of the run in `store` alone (what one process of a cluster maps): map_tiles of it.
template <class Key>
TileIntegrator<Key> map_tile(const RatedStore& store, const TileGrid<Key>& grid, const TileCoord& c,
                             unsigned threads = 1, std::size_t memory_limit = 0,
                             const std::function<void(std::size_t, std::size_t)>& progress = {}) {
  return map_tiles(store, grid, TileBox{c, c}, threads, memory_limit, progress);
}

/// What describes a run in its tile set's index besides its tiles.
struct RunDescription {
  std::string model, model_options, source;
  std::uint64_t first = 0, count = 0;
};

/// The index of a tile set of `store`'s run at `depth`, before its tiles.
template <class Key>
TileSetIndex start_index(const RatedStore& store, int depth, const RunDescription& run) {
  TileSetIndex ix;
  ix.resolution = store.resolution();
  ix.key_bits = Key::depth;
  ix.tile_depth = depth;
  ix.params = store.params();
  ix.model = run.model;
  ix.model_options = run.model_options;
  ix.source = run.source;
  ix.first = run.first;
  ix.count = run.count;
  ix.totals = store.totals();
  return ix;
}

namespace detail {

// Maps the tiles `coords` (inside `box`) together and writes them; when they do not fit
// `memory_limit` together, the box is halved along its longest side and each half done alone.
template <class Key>
void write_tile_group(const RatedStore& store, const std::string& dir, const TileGrid<Key>& grid,
                      std::vector<TileCoord> coords, unsigned threads, std::size_t memory_limit,
                      std::vector<TileEntry>& out, std::size_t& done,
                      const std::function<void(std::size_t)>& tiles_done) {
  if (coords.empty()) return;
  TileBox box{coords[0], coords[0]};
  for (const TileCoord& c : coords)
    for (int a = 0; a < 3; ++a) {
      box.lo.t[a] = std::min(box.lo.t[a], c.t[a]);
      box.hi.t[a] = std::max(box.hi.t[a], c.t[a]);
    }
  std::vector<TileEntry> written;
  try {
    const TileIntegrator<Key> group = map_tiles(store, grid, box, threads, memory_limit);
    written = write_tiles_of(group.map(), dir, grid);
  } catch (const std::bad_alloc&) {  // MemoryLimitError too
    if (coords.size() == 1)
      throw io::Error((std::filesystem::path(dir) / TileGrid<Key>::file_name(coords[0])).string(),
                      "the tile's map needs more than its memory limit of " +
                          std::to_string(memory_limit / 1000000) +
                          " MB; cut the map into smaller tiles (a deeper tile depth)");
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (box.hi.t[a] - box.lo.t[a] > box.hi.t[axis] - box.lo.t[axis]) axis = a;
    const std::int64_t mid = box.lo.t[axis] + (box.hi.t[axis] - box.lo.t[axis] + 1) / 2;
    std::vector<TileCoord> low, high;
    // Distinct tiles span at least two on the longest side: both halves hold some.
    for (const TileCoord& c : coords) (c.t[axis] < mid ? low : high).push_back(c);
    write_tile_group(store, dir, grid, std::move(low), threads, memory_limit, out, done,
                     tiles_done);
    write_tile_group(store, dir, grid, std::move(high), threads, memory_limit, out, done,
                     tiles_done);
    return;
  }
  out.insert(out.end(), written.begin(), written.end());
  done += coords.size();
  if (tiles_done) tiles_done(done);
}

}  // namespace detail

/// Maps every tile `store`'s run reaches at `depth` into `dir` and writes the index (tiles that
/// end up empty are left out). The tiles are mapped together as far as `memory_limit` allows (0:
/// all at once): a group of tiles is one clipped map, its scans from inside it walked whole; a
/// group whose map passes the limit is halved and each half mapped alone, down to single tiles
/// (one tile that does not fit is an io::Error naming it). progress(tiles done, of).
template <class Key>
TileSetIndex write_tile_set(const RatedStore& store, const std::string& dir, int depth,
                            const RunDescription& run, unsigned threads = 1,
                            std::size_t memory_limit = 0,
                            const std::function<void(std::size_t, std::size_t)>& progress = {}) {
  const TileGrid<Key> grid(depth);
  TileSetIndex ix = start_index<Key>(store, depth, run);
  const std::vector<TileCoord> tiles = tiles_reached(store, grid);
  std::size_t done = 0;
  detail::write_tile_group(store, dir, grid, tiles, threads, memory_limit, ix.tiles, done,
                           [&](std::size_t n) {
                             if (progress) progress(n, tiles.size());
                           });
  std::sort(ix.tiles.begin(), ix.tiles.end(), [&](const TileEntry& a, const TileEntry& b) {
    return grid.morton(a.coord) < grid.morton(b.coord);
  });
  write_index(dir, ix);
  return ix;
}

}  // namespace knnocc::tiles
