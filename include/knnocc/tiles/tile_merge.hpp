// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// merge_tile_set: a tile set (tiles/tile_set.hpp) as one OctoMap .bt or .ot file, written as a
// stream, so the file may be larger than memory. The bytes are those of the one-process map's
// file (io/octomap_tree.hpp), because an OctoMap file is its tree in pre-order:
//   1. the tree above the tiles (depths 0 .. D-1) is planned from the index alone: each tile's
//      subtree summary (one leaf or not, its value, its node count) gives its parents' bytes, the
//      pruning of parents whose 8 children are equal leaves, and the header's node count;
//   2. the header and the nodes above the tiles are written, and each tile in turn is read (its
//      size, checksum and contents checked), its subtree encoded exactly as the whole map's writer
//      encodes that node, checked against the index's summary, and appended: about one tile in
//      memory at a time.
// A tile set of wide keys merges only if every tile lies inside OctoMap's key range; otherwise
// the refusal names the extent and the finest resolution that would hold it. Any error leaves the
// output as it was (io/atomic_file.hpp).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "../io/atomic_file.hpp"
#include "../io/octomap_tree.hpp"
#include "tile_grid.hpp"
#include "tile_set.hpp"

namespace knnocc::tiles {

/// What merge_tile_set wrote.
struct MergeStats {
  std::uint64_t nodes = 0;  ///< the file's node count
  std::size_t tiles = 0;    ///< tiles streamed
  std::uint64_t bytes = 0;  ///< the file's size
};

namespace detail {

// Refuses a tile set whose tiles leave OctoMap's key range (a wide map beyond +-2^15 voxels).
inline void check_fits_octomap(const std::string& dir, const TileSetIndex& ix) {
  if (ix.key_bits == 16) return;
  constexpr std::int64_t natural = WideKey::center - 32768;
  double reach = 0.0;  // farthest tile corner from coordinate 0, in voxels
  bool fits = true;
  for (const TileEntry& t : ix.tiles) {
    for (std::size_t a = 0; a < 3; ++a) {
      fits = fits && t.shift[a] == natural;
      reach = std::max({reach, std::fabs(double(t.keys[a] - WideKey::center)),
                        std::fabs(double(t.keys[a + 3] + 1 - WideKey::center))});
    }
  }
  if (fits) return;
  char text[400];
  std::snprintf(text, sizeof text,
                "the map spans up to %.1f m from its origin, beyond the +-%.1f m an OctoMap "
                ".bt/.ot holds at resolution %g (the finest resolution that would hold it is "
                "%.4g m): keep it as a tile set (knnocc view and info read it), or map it again "
                "at a coarser --res",
                reach * ix.resolution, 32768.0 * ix.resolution, ix.resolution,
                ix.resolution * reach / 32768.0);
  throw io::Error(dir, text);
}

// Streams a tile set into one OctoMap file (Full: .ot, else .bt); see the file comment.
template <bool Full>
class TileMerger {
 public:
  using Encoder = io::detail::OctreeEncoder<Full>;

  TileMerger(const std::string& dir, const TileSetIndex& ix, std::size_t memory_limit)
      : dir_(dir),
        ix_(ix),
        memory_limit_(memory_limit),
        empty_(ix.resolution, ix.params.occupancy) {
    check_fits_octomap(dir, ix);
    const TileGrid<OcKey> grid(ix.tile_depth);  // OctoMap's tree: tile numbers are the same
    order_.resize(ix.tiles.size());
    for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = {grid.morton(ix.tiles[i].coord), i};
    std::sort(order_.begin(), order_.end());
  }

  /// Writes the file to `out`; progress(tiles done) after each tile.
  MergeStats write(const std::string& out, const std::function<void(std::size_t)>& progress) {
    plan_.clear();
    std::uint64_t nodes = 0;
    if (!order_.empty()) nodes = plan(0, 0, order_.size()).nodes;
    const Encoder rules(empty_, "");
    io::AtomicFile file(out);
    const std::string header = rules.header(nodes);
    file.write(header);
    stats_ = MergeStats{};
    stats_.nodes = nodes;
    stats_.bytes = header.size();
    progress_ = &progress;
    cursor_ = 0;
    if (!order_.empty()) emit(0, 0, order_.size(), file);
    file.commit();
    return stats_;
  }

 private:
  struct Planned {  // a node above the tiles
    io::detail::OctreeNodeSummary summary;
    std::uint64_t nodes = 0;      // its subtree's nodes in the file
    bool collapsed = false;       // pruned into one leaf
    std::string head;             // its bytes when not collapsed
    std::size_t descendants = 0;  // planned nodes below it
  };
  struct Sub {
    io::detail::OctreeNodeSummary summary;
    std::uint64_t nodes = 0;
  };

  const TileEntry& tile(std::size_t i) const { return ix_.tiles[order_[i].second]; }
  const TileNodeInfo& info(const TileEntry& t) const { return Full ? t.ot : t.bt; }

  // Child digit (0..7) of sorted tile i at depth d.
  unsigned digit(std::size_t i, int d) const {
    return static_cast<unsigned>((order_[i].first >> (3 * (ix_.tile_depth - 1 - d))) & 7u);
  }

  // The children of the depth-d node over tiles [lo, hi): f(child, lo, hi) for each present one.
  template <class F>
  void for_each_child(int d, std::size_t lo, std::size_t hi, F&& f) const {
    for (std::size_t b = lo; b < hi;) {
      std::size_t e = b;
      while (e < hi && digit(e, d) == digit(b, d)) ++e;
      f(digit(b, d), b, e);
      b = e;
    }
  }

  Sub plan(int d, std::size_t lo, std::size_t hi) {
    if (d == ix_.tile_depth) {
      const TileNodeInfo& n = info(tile(lo));
      Sub s;
      s.summary.leaf = n.leaf;
      s.summary.value = n.value;
      s.nodes = n.nodes;
      return s;
    }
    const std::size_t slot = plan_.size();
    plan_.emplace_back();
    io::detail::OctreeNodeSummary kids[8];
    unsigned present = 0;
    std::uint64_t below = 0;
    for_each_child(d, lo, hi, [&](unsigned c, std::size_t b, std::size_t e) {
      const Sub s = plan(d + 1, b, e);
      kids[c] = s.summary;
      present |= 1u << c;
      below += s.nodes;
    });
    Planned& p = plan_[slot];
    char head[Encoder::kNodeBytes];
    p.collapsed = Encoder(empty_, "").combine(d, kids, present, p.summary, head);
    p.head.assign(head, Encoder::kNodeBytes);
    p.nodes = p.collapsed ? 1 : 1 + below;
    p.descendants = plan_.size() - slot - 1;
    return Sub{p.summary, p.nodes};
  }

  void emit(int d, std::size_t lo, std::size_t hi, io::AtomicFile& file) {
    if (d == ix_.tile_depth) {
      emit_tile(lo, file);
      return;
    }
    const Planned& p = plan_[cursor_++];
    if (p.collapsed) {  // 8 tiles of one leaf each, pruned: checked, not written
      for (std::size_t i = lo; i < hi; ++i) emit_tile(i, file, false);
      put(Encoder::leaf_bytes(p.summary), file);
      cursor_ += p.descendants;
      return;
    }
    put(p.head, file);
    for_each_child(d, lo, hi,
                   [&](unsigned, std::size_t b, std::size_t e) { emit(d + 1, b, e, file); });
  }

  void emit_tile(std::size_t i, io::AtomicFile& file, bool write = true) {
    const TileEntry& t = tile(i);
    const OccupancyMap<OcKey> map = read_tile<OcKey>(dir_, ix_, t, memory_limit_, true);
    std::array<std::uint32_t, 3> corner{};
    for (std::size_t a = 0; a < 3; ++a)
      corner[a] = static_cast<std::uint32_t>(t.keys[a] - t.shift[a]);
    io::detail::OctreeNode node = Encoder(map, "").encode_node(ix_.tile_depth, corner);
    const TileNodeInfo& n = info(t);
    if (!node.present || node.nodes != n.nodes || node.summary.leaf != n.leaf ||
        std::memcmp(&node.summary.value, &n.value, sizeof(float)) != 0)
      throw io::Error((std::filesystem::path(dir_) / t.file).string(),
                      "its tree does not match the index's summary of it: the tile set is "
                      "damaged");
    if (write) put(node.data, file);
    ++stats_.tiles;
    (*progress_)(stats_.tiles);
  }

  void put(const std::string& bytes, io::AtomicFile& file) {
    file.write(bytes);
    stats_.bytes += bytes.size();
  }

  std::string dir_;
  const TileSetIndex& ix_;
  std::size_t memory_limit_;
  OccupancyMap<OcKey> empty_;  // the tile set's resolution and clamping: the writers' rules
  std::vector<std::pair<std::uint64_t, std::size_t>> order_;  // (Morton code, tile), sorted
  std::vector<Planned> plan_;                                 // nodes above the tiles, pre-order
  std::size_t cursor_ = 0;
  MergeStats stats_;
  const std::function<void(std::size_t)>* progress_ = nullptr;
};

}  // namespace detail

/// Writes the tile set in `dir` as one OctoMap file at `out`: .bt when `binary`, else .ot; see the
/// file comment. `memory_limit` bounds each tile's map (0: none); progress(tiles done) is called
/// after each tile.
inline MergeStats merge_tile_set(const std::string& dir, const std::string& out, bool binary,
                                 std::size_t memory_limit = 0,
                                 const std::function<void(std::size_t)>& progress = {}) {
  const TileSetIndex ix = read_index(dir);
  const std::function<void(std::size_t)> report = progress ? progress : [](std::size_t) {};
  if (binary) return detail::TileMerger<false>(dir, ix, memory_limit).write(out, report);
  return detail::TileMerger<true>(dir, ix, memory_limit).write(out, report);
}

}  // namespace knnocc::tiles
