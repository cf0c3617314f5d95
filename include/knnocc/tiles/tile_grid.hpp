// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// TileGrid: a map cut into tiles, each one node of the octree at a fixed depth.
//
// The depth counts in OctoMap's 16-level tree whatever the key type: a tile at depth D holds
// 2^(16 - D) voxels per axis (depth 0: one tile, the whole range of OctoMap's keys; depth 13: one
// brick of 8^3 voxels). Tiles are numbered by signed coordinates around the map's centre: from
// depth 1 on, tile (tx, ty, tz) holds the voxels whose indices from coordinate 0, floor(c / r),
// lie in [t 2^(16 - D), (t + 1) 2^(16 - D)) on each axis (the one tile of depth 0 is tile 0). So a
// tile is the same region of space, with the same number, in a map of OctoMap's 16-bit keys and
// in a map of wide keys (WideKey: 21 bits; a tile there is a node at depth D + 5 of its 21-level
// tree). Wide maps need depth >= 1: a tile of at most 2^15 voxels per axis, so that each tile
// fits one OctoMap file (tiles/tile_files.hpp).
//
// A tile's node sits in OctoMap's tree where its keys do; the tiles of a map in the pre-order of
// OctoMap's files are the tiles in Morton order of their nodes (child index bits x 1, y 2, z 4 at
// every level, the root's child first): morton_order() sorts them so, which is how a tile set is
// merged into one file as a stream (tiles/tile_merge.hpp).
//
// Thread safety: immutable after construction.

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "../core/config.hpp"
#include "../core/key.hpp"

namespace knnocc {

/// A tile's signed coordinates (see TileGrid).
struct TileCoord {
  std::int64_t t[3] = {0, 0, 0};

  friend bool operator==(const TileCoord& a, const TileCoord& b) {
    return a.t[0] == b.t[0] && a.t[1] == b.t[1] && a.t[2] == b.t[2];
  }
  friend bool operator!=(const TileCoord& a, const TileCoord& b) { return !(a == b); }
  /// x, then y, then z: an order for lookups (not the file order; see TileGrid::morton_order).
  friend bool operator<(const TileCoord& a, const TileCoord& b) {
    return a.t[0] != b.t[0]   ? a.t[0] < b.t[0]
           : a.t[1] != b.t[1] ? a.t[1] < b.t[1]
                              : a.t[2] < b.t[2];
  }
};

template <class Key = OcKey>
class TileGrid {
 public:
  using key_type = Key;
  static constexpr int kOctreeDepth = 16;  ///< OctoMap's tree, in which depths count
  static constexpr int kMaxDepth = 13;     ///< a tile of one brick

  /// Tiles at `depth` (0..13; 1..13 with wide keys); else std::invalid_argument.
  explicit TileGrid(int depth) : depth_(depth) {
    const int min_depth = Key::depth > kOctreeDepth ? 1 : 0;
    if (depth < min_depth || depth > kMaxDepth)
      detail::invalid_argument("tile depth must be in [" + std::to_string(min_depth) + ", " +
                               std::to_string(kMaxDepth) + "] for " + std::to_string(Key::depth) +
                               "-bit keys, got " + std::to_string(depth));
    static_assert(Key::depth >= kOctreeDepth, "TileGrid: keys of at least 16 bits");
  }

  int depth() const { return depth_; }
  /// log2 of a tile's edge in voxels.
  int edge_bits() const { return kOctreeDepth - depth_; }
  std::int64_t edge() const { return std::int64_t{1} << edge_bits(); }

  /// The tile holding `key`.
  TileCoord tile_of(const Key& key) const {
    TileCoord c;
    for (int a = 0; a < 3; ++a) c.t[a] = tile_index(key[a]);
    return c;
  }
  /// Along one axis: the tile holding index k (a key's index).
  std::int64_t tile_index(std::int64_t k) const {
    return (k >> edge_bits()) - (Key::center >> edge_bits());  // k >= 0: the node's index
  }

  /// Whether tile `c` lies inside the key range.
  bool valid(const TileCoord& c) const {
    for (int a = 0; a < 3; ++a) {
      const std::int64_t lo = first_index(c.t[a]);
      if (lo < 0 || lo + edge() > Key::extent) return false;
    }
    return true;
  }

  /// Along one axis: the first key index of tile t.
  std::int64_t first_index(std::int64_t t) const {
    return (t + (Key::center >> edge_bits())) * edge();
  }

  /// The keys of tile `c` (valid(c) required).
  KeyBounds<Key> bounds(const TileCoord& c) const {
    using I = typename Key::index_type;
    KeyBounds<Key> b;
    for (int a = 0; a < 3; ++a) {
      const std::int64_t lo = first_index(c.t[a]);
      b.lo[a] = static_cast<I>(lo);
      b.hi[a] = static_cast<I>(lo + edge() - 1);
    }
    return b;
  }

  /// Calls f(TileCoord) for every tile that holds a key of `keys`, x fastest.
  template <class F>
  void for_each_tile(const KeyBounds<Key>& keys, F&& f) const {
    const TileCoord lo = tile_of(keys.lo), hi = tile_of(keys.hi);
    TileCoord c;
    for (c.t[2] = lo.t[2]; c.t[2] <= hi.t[2]; ++c.t[2])
      for (c.t[1] = lo.t[1]; c.t[1] <= hi.t[1]; ++c.t[1])
        for (c.t[0] = lo.t[0]; c.t[0] <= hi.t[0]; ++c.t[0]) f(static_cast<const TileCoord&>(c));
  }

  /// The tiles' nodes in the pre-order of an OctoMap tree of this key width (sorted in place).
  void morton_order(std::vector<TileCoord>& tiles) const {
    std::sort(tiles.begin(), tiles.end(),
              [this](const TileCoord& a, const TileCoord& b) { return morton(a) < morton(b); });
  }

  /// A tile's node index in the pre-order's Morton code (higher levels in higher bits).
  std::uint64_t morton(const TileCoord& c) const {
    const int levels = Key::depth - edge_bits();  // node depth in the key's own tree
    std::uint64_t m = 0;
    std::uint64_t u[3];
    for (int a = 0; a < 3; ++a)
      u[a] = static_cast<std::uint64_t>(c.t[a] + (Key::center >> edge_bits()));
    for (int j = 0; j < levels; ++j)
      m |= (((u[0] >> j) & 1u) | (((u[1] >> j) & 1u) << 1) | (((u[2] >> j) & 1u) << 2)) << (3 * j);
    return m;
  }

  /// The file name of a tile: tile_X_Y_Z.ot with its signed coordinates.
  static std::string file_name(const TileCoord& c) {
    return "tile_" + std::to_string(c.t[0]) + "_" + std::to_string(c.t[1]) + "_" +
           std::to_string(c.t[2]) + ".ot";
  }

 private:
  int depth_;
};

}  // namespace knnocc
