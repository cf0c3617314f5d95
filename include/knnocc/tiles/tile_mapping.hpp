// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Mapping tiles from a folder of rated keyframes (tiles/rated_store.hpp): the tiles a run
// reaches, one tile mapped from the keyframes that can reach it (each clipped to the tile: only
// the part of a ray that can touch the tile is walked, with the keys of the whole walk), and a
// whole tile set written tile by tile, so that a process holds one tile's map at a time. Another
// process, or another machine sharing the folder, can map any tile alone (knnocc.dask does).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

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

/// Tile `c` of the run in `store`: the keyframes that can reach it, in order, each clipped to
/// it. `memory_limit` bounds the tile's map (0: none; a tile that cannot fit is a
/// MemoryLimitError); progress(keyframes done, of) after each keyframe.
template <class Key>
TileIntegrator<Key> map_tile(const RatedStore& store, const TileGrid<Key>& grid, const TileCoord& c,
                             unsigned threads = 1, std::size_t memory_limit = 0,
                             const std::function<void(std::size_t, std::size_t)>& progress = {}) {
  if (store.key_bits() != Key::depth)
    throw io::Error(store.dir(), "rated keyframes of " + std::to_string(store.key_bits()) +
                                     "-bit keys, not " + std::to_string(Key::depth));
  const KeyBounds<Key> b = grid.bounds(c);
  TileIntegrator<Key> tile(store.resolution(), store.params(), b, threads);
  tile.map().set_memory_limit(memory_limit);
  const std::vector<std::size_t> which =
      store.reaching({b.lo[0], b.lo[1], b.lo[2], b.hi[0], b.hi[1], b.hi[2]});
  RatedKeyframe rk;
  for (std::size_t j = 0; j < which.size(); ++j) {
    store.load(which[j], rk);
    tile.integrate(rk);
    if (progress) progress(j + 1, which.size());
  }
  return tile;
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

/// Maps every tile `store`'s run reaches at `depth` into `dir`, one tile at a time, and writes
/// the index (tiles that end up empty are left out). progress(tiles done, of).
template <class Key>
TileSetIndex write_tile_set(const RatedStore& store, const std::string& dir, int depth,
                            const RunDescription& run, unsigned threads = 1,
                            std::size_t memory_limit = 0,
                            const std::function<void(std::size_t, std::size_t)>& progress = {}) {
  const TileGrid<Key> grid(depth);
  TileSetIndex ix = start_index<Key>(store, depth, run);
  const std::vector<TileCoord> tiles = tiles_reached(store, grid);
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    const TileIntegrator<Key> tile = map_tile(store, grid, tiles[i], threads, memory_limit);
    if (!tile.map().empty()) ix.tiles.push_back(write_tile(dir, grid, tiles[i], tile.map()));
    if (progress) progress(i + 1, tiles.size());
  }
  write_index(dir, ix);
  return ix;
}

}  // namespace knnocc::tiles
