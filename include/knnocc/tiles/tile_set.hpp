// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A tile set on disk: a map cut into octree-aligned tiles (tiles/tile_grid.hpp), one OctoMap .ot
// file per tile that octovis opens as it is, and an index. docs/tiles.md describes the layout:
//
//   DIR/index.txt        the index (below)
//   DIR/tile_X_Y_Z.ot    one tile: a full OctoMap tree (log-odds kept) holding only that tile's
//                        voxels, where OctoMap's keys put them; for a map of wide keys a tile
//                        beyond OctoMap's key range sits at its position modulo that range (its
//                        `shift`, in the index and in the file's "# knnocc" header line)
//
// index.txt, one record per line:
//   knnocc tile set 1
//   resolution R / key_bits 16|21 / tile_depth D / tile_edge_voxels 2^(16-D)
//   integration ... / occupancy ...        the run's constants (tiles/detail/index_text.hpp)
//   model NAME / model_options TEXT / source PATH / clouds FIRST COUNT
//   totals clouds N points N nonfinite N out_of_range N rated N rays N
//   tiles N, then one line per tile in the order of OctoMap's files (TileGrid::morton_order):
//     tile X Y Z FILE shift SX SY SZ keys X0 Y0 Z0 X1 Y1 Z1 occupied N free N
//          bt NODES leaf|inner VALUE ot NODES leaf|inner VALUE bytes N sha256 HEX
//   end
// `shift`: the map's key of the file's OctoMap key k is k + shift. `keys`: the tile's keys (first
// and last, per axis). bt/ot: the node count of the tile's subtree in a .bt / .ot file of the
// whole map, whether it is one leaf, and its value (the leaf's, or the max of its voxels): what
// merging needs to write the tree above the tiles before streaming them (tiles/tile_merge.hpp).
// `sha256` is the file's, as sha256sum prints it.
//
// Everything read is checked against everything else it implies (tile keys against coordinates
// and depth, shifts, file names, counts); a tile file is checked against its entry when it is
// read (size, checksum, resolution, that its voxels lie inside its tile). Any mismatch is an
// io::Error naming the file and what is wrong.

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "../core/key.hpp"
#include "../io/atomic_file.hpp"
#include "../io/detail/file_text.hpp"
#include "../io/detail/sha256.hpp"
#include "../io/error.hpp"
#include "../io/octomap_tree.hpp"
#include "../map/brick.hpp"
#include "../map/detail/brick_access.hpp"
#include "../map/occupancy_map.hpp"
#include "detail/index_text.hpp"
#include "rated_store.hpp"
#include "tile_grid.hpp"

namespace knnocc::tiles {

/// A tile's subtree in a .bt or .ot file of the whole map.
struct TileNodeInfo {
  std::uint64_t nodes = 0;
  bool leaf = false;
  float value = 0.0f;
};

/// One tile of the index.
struct TileEntry {
  TileCoord coord;
  std::string file;
  std::array<std::int64_t, 3> shift{};   ///< map key = the file's OctoMap key + shift
  std::array<std::int64_t, 6> keys{};    ///< first and last key per axis (x0 y0 z0 x1 y1 z1)
  std::uint64_t occupied = 0, free = 0;  ///< finest-level voxels
  TileNodeInfo bt, ot;
  std::uint64_t bytes = 0;
  std::string sha256;
};

/// A tile set's index.
struct TileSetIndex {
  double resolution = 0.0;
  int key_bits = 16;
  int tile_depth = 0;
  IntegrationParams params;
  std::string model, model_options, source;
  std::uint64_t first = 0, count = 0;  ///< the clouds the tiles hold
  RatingTotals totals;
  std::vector<TileEntry> tiles;  ///< in the order of OctoMap's files

  std::int64_t tile_edge() const { return std::int64_t{1} << (16 - tile_depth); }
  std::uint64_t occupied() const {
    std::uint64_t n = 0;
    for (const TileEntry& t : tiles) n += t.occupied;
    return n;
  }
  std::uint64_t free() const {
    std::uint64_t n = 0;
    for (const TileEntry& t : tiles) n += t.free;
    return n;
  }
};

inline constexpr const char* kIndexName = "index.txt";

/// Whether `dir` holds a tile set (its index's first line says so).
inline bool is_tile_set(const std::string& dir) {
  std::error_code ec;
  const std::filesystem::path index = std::filesystem::path(dir) / kIndexName;
  if (!std::filesystem::is_regular_file(index, ec)) return false;
  std::FILE* f = std::fopen(index.string().c_str(), "rb");
  if (!f) return false;
  char line[32] = {};
  const std::size_t n = std::fread(line, 1, sizeof line - 1, f);
  std::fclose(f);
  return std::string(line, n).rfind("knnocc tile set ", 0) == 0;
}

namespace detail {

inline std::string node_text(const TileNodeInfo& n) {
  return number_text(n.nodes) + (n.leaf ? " leaf " : " inner ") + number_text(n.value);
}

inline TileNodeInfo read_node(const IndexLines& in, const std::vector<std::string>& w,
                              std::size_t at, const char* name) {
  in.expect_word(w[at], name);
  TileNodeInfo n;
  n.nodes = in.integer<std::uint64_t>(w[at + 1], "node count");
  if (w[at + 2] != "leaf" && w[at + 2] != "inner") in.fail("expected 'leaf' or 'inner'");
  n.leaf = w[at + 2] == "leaf";
  n.value = in.real_float(w[at + 3], "node value");
  if (!std::isfinite(n.value)) in.fail("a node value is not finite");
  return n;
}

// Where tile `c` sits in an OctoMap file (see the file comment): OctoMap's key k of the file is
// the map's key k + shift. Tiles inside OctoMap's key range keep their place (shift 2^20 - 2^15 in
// a wide map, 0 in a 16-bit one); others move by a multiple of 2^16 (still node-aligned).
template <class Key>
std::array<std::int64_t, 3> tile_shift(const TileGrid<Key>& grid, const TileCoord& c) {
  constexpr std::int64_t natural = Key::center - 32768;
  std::array<std::int64_t, 3> s{};
  for (int a = 0; a < 3; ++a) {
    const std::int64_t first = grid.first_index(c.t[a]);
    const std::int64_t k16 = (((first - natural) % 65536) + 65536) % 65536;
    s[static_cast<std::size_t>(a)] = first - k16;
  }
  return s;
}

// The first OctoMap key of entry `e`'s node in its file.
inline std::array<std::uint32_t, 3> tile_corner(const TileEntry& e) {
  std::array<std::uint32_t, 3> corner{};
  for (std::size_t a = 0; a < 3; ++a)
    corner[a] = static_cast<std::uint32_t>(e.keys[a] - e.shift[a]);
  return corner;
}

// Checks entry `t` against everything the index implies of it.
template <class Key>
void check_entry(const IndexLines& in, const TileGrid<Key>& grid, const TileEntry& t) {
  if (!grid.valid(t.coord)) in.fail("tile outside the key range");
  const KeyBounds<Key> b = grid.bounds(t.coord);
  for (int a = 0; a < 3; ++a)
    if (t.keys[static_cast<std::size_t>(a)] != b.lo[a] ||
        t.keys[static_cast<std::size_t>(a + 3)] != b.hi[a])
      in.fail("the tile's keys do not match its coordinates and the tile depth");
  if (t.shift != tile_shift(grid, t.coord))
    in.fail("the tile's shift is not where its file places it");
  if (t.file != TileGrid<Key>::file_name(t.coord))
    in.fail("tile file '" + t.file + "' is not named after its coordinates");
  if (t.sha256.size() != 64 || t.sha256.find_first_not_of("0123456789abcdef") != std::string::npos)
    in.fail("sha256 must be 64 lowercase hex digits");
}

template <class Key>
void check_entries(IndexLines& in, const TileSetIndex& ix) {
  const TileGrid<Key> grid(ix.tile_depth);
  for (std::size_t i = 0; i < ix.tiles.size(); ++i) {
    check_entry(in, grid, ix.tiles[i]);
    if (i > 0 && grid.morton(ix.tiles[i - 1].coord) >= grid.morton(ix.tiles[i].coord))
      in.fail("tiles out of order or repeated (tile " + std::to_string(i) + ")");
  }
}

inline TileEntry read_entry(IndexLines& in) {
  const std::vector<std::string>& w = in.take("tile", 31);
  TileEntry t;
  for (int a = 0; a < 3; ++a)
    t.coord.t[a] = in.integer<std::int64_t>(w[static_cast<std::size_t>(1 + a)], "tile coordinate");
  t.file = w[4];
  in.expect_word(w[5], "shift");
  for (std::size_t a = 0; a < 3; ++a) t.shift[a] = in.integer<std::int64_t>(w[6 + a], "shift");
  in.expect_word(w[9], "keys");
  for (std::size_t a = 0; a < 6; ++a) t.keys[a] = in.integer<std::int64_t>(w[10 + a], "keys");
  in.expect_word(w[16], "occupied");
  t.occupied = in.integer<std::uint64_t>(w[17], "occupied");
  in.expect_word(w[18], "free");
  t.free = in.integer<std::uint64_t>(w[19], "free");
  t.bt = read_node(in, w, 20, "bt");
  t.ot = read_node(in, w, 24, "ot");
  in.expect_word(w[28], "bytes");
  t.bytes = in.integer<std::uint64_t>(w[29], "bytes");
  in.expect_word(w[30], "sha256");
  t.sha256 = w[31];
  return t;
}

}  // namespace detail

/// The text of index.txt.
inline std::string index_text(const TileSetIndex& ix) {
  using detail::number_text;
  std::string s = "knnocc tile set 1\nresolution " + number_text(ix.resolution) + "\nkey_bits " +
                  std::to_string(ix.key_bits) + "\ntile_depth " + std::to_string(ix.tile_depth) +
                  "\ntile_edge_voxels " + std::to_string(ix.tile_edge()) + "\n" +
                  detail::integration_lines(ix.params);
  s += "model " + detail::escape_word(ix.model) + "\nmodel_options " +
       detail::escape_word(ix.model_options) + "\nsource " + detail::escape_word(ix.source) +
       "\nclouds " + number_text(ix.first) + " " + number_text(ix.count) + "\n";
  const RatingTotals& t = ix.totals;
  s += "totals clouds " + number_text(t.clouds) + " points " + number_text(t.points) +
       " nonfinite " + number_text(t.nonfinite) + " out_of_range " + number_text(t.out_of_range) +
       " rated " + number_text(t.rated) + " rays " + number_text(t.rays) + "\n";
  s += "tiles " + std::to_string(ix.tiles.size()) + "\n";
  for (const TileEntry& e : ix.tiles) {
    s += "tile " + std::to_string(e.coord.t[0]) + " " + std::to_string(e.coord.t[1]) + " " +
         std::to_string(e.coord.t[2]) + " " + e.file + " shift";
    for (const std::int64_t v : e.shift) s += " " + std::to_string(v);
    s += " keys";
    for (const std::int64_t v : e.keys) s += " " + std::to_string(v);
    s += " occupied " + number_text(e.occupied) + " free " + number_text(e.free) + " bt " +
         detail::node_text(e.bt) + " ot " + detail::node_text(e.ot) + " bytes " +
         number_text(e.bytes) + " sha256 " + e.sha256 + "\n";
  }
  s += "end\n";
  return s;
}

/// Reads and checks DIR/index.txt (io::Error naming it, and the line, for anything wrong).
inline TileSetIndex read_index(const std::string& dir) {
  const std::string path = (std::filesystem::path(dir) / kIndexName).string();
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw io::Error(dir, "tile set folder does not exist");
  if (!std::filesystem::is_regular_file(path, ec))
    throw io::Error(path, "missing: not a tile set (knnocc map --out-tiles writes one)");
  detail::IndexLines in(path);
  TileSetIndex ix;
  const auto& head = in.take("knnocc", 3);
  if (head[1] != "tile" || head[2] != "set" || head[3] != "1")
    in.fail("not a knnocc tile set index (version 1)");
  ix.resolution = in.real(in.take("resolution", 1)[1], "resolution");
  if (!(ix.resolution >= Grid<OcKey>::min_resolution && ix.resolution <= 1e6))
    in.fail("resolution out of range");
  ix.key_bits = in.integer<int>(in.take("key_bits", 1)[1], "key_bits");
  if (ix.key_bits != 16 && ix.key_bits != 21) in.fail("key_bits must be 16 or 21");
  ix.tile_depth = in.integer<int>(in.take("tile_depth", 1)[1], "tile_depth");
  if (ix.tile_depth < (ix.key_bits == 16 ? 0 : 1) || ix.tile_depth > 13)
    in.fail("tile_depth out of range for " + std::to_string(ix.key_bits) + "-bit keys");
  if (in.integer<std::int64_t>(in.take("tile_edge_voxels", 1)[1], "tile_edge_voxels") !=
      ix.tile_edge())
    in.fail("tile_edge_voxels does not match tile_depth");
  ix.params = detail::read_integration(in);
  ix.model = detail::unescape_word(in.take("model", 1)[1]);
  ix.model_options = detail::unescape_word(in.take("model_options", 1)[1]);
  ix.source = detail::unescape_word(in.take("source", 1)[1]);
  const auto& clouds = in.take("clouds", 2);
  ix.first = in.integer<std::uint64_t>(clouds[1], "first cloud");
  ix.count = in.integer<std::uint64_t>(clouds[2], "cloud count");
  const auto& t = in.take("totals", 12);
  const char* names[] = {"clouds", "points", "nonfinite", "out_of_range", "rated", "rays"};
  std::uint64_t* fields[] = {&ix.totals.clouds,       &ix.totals.points, &ix.totals.nonfinite,
                             &ix.totals.out_of_range, &ix.totals.rated,  &ix.totals.rays};
  for (std::size_t i = 0; i < 6; ++i) {
    in.expect_word(t[1 + 2 * i], names[i]);
    *fields[i] = in.integer<std::uint64_t>(t[2 + 2 * i], names[i]);
  }
  const auto count = in.integer<std::uint64_t>(in.take("tiles", 1)[1], "tiles");
  if (count > (std::uint64_t{1} << 30)) in.fail("too many tiles");
  for (std::uint64_t i = 0; i < count; ++i) {
    if (in.peek() != "tile")
      in.fail("the index lists " + std::to_string(i) + " tiles, not the " + std::to_string(count) +
              " its 'tiles' line says");
    ix.tiles.push_back(detail::read_entry(in));
  }
  if (ix.key_bits == 16)
    detail::check_entries<OcKey>(in, ix);
  else
    detail::check_entries<WideKey>(in, ix);
  in.take("end", 0);
  if (!in.done()) in.fail("lines after 'end'");
  return ix;
}

/// Writes index.txt into `dir` (atomically).
inline void write_index(const std::string& dir, const TileSetIndex& ix) {
  io::AtomicFile f((std::filesystem::path(dir) / kIndexName).string());
  f.write(index_text(ix));
  f.commit();
}

/// Writes tile `c` of `map` (its voxels outside the tile are not looked at) into `dir` as its
/// .ot file, and returns its index entry. `note` goes into the file's "# knnocc" header line.
template <class Key>
TileEntry write_tile(const std::string& dir, const TileGrid<Key>& grid, const TileCoord& c,
                     const OccupancyMap<Key>& map, const std::string& note = {}) {
  TileEntry e;
  e.coord = c;
  e.file = TileGrid<Key>::file_name(c);
  e.shift = detail::tile_shift(grid, c);
  const KeyBounds<Key> b = grid.bounds(c);
  for (int a = 0; a < 3; ++a) {
    e.keys[static_cast<std::size_t>(a)] = b.lo[a];
    e.keys[static_cast<std::size_t>(a + 3)] = b.hi[a];
  }
  map.for_each_voxel_in_bbox(
      b.lo, b.hi, [&](const Key&, float v) { (map.is_occupied(v) ? e.occupied : e.free) += 1; });
  const std::array<std::uint32_t, 3> corner = detail::tile_corner(e);
  const io::detail::OctreeNode bt =
      io::detail::OctreeEncoder<false, false, Key>(map, "", {}, e.shift)
          .encode_node(grid.depth(), corner, false);
  io::detail::OctreeEncoder<true, false, Key> ot_encoder(map, note, {}, e.shift);
  const io::detail::OctreeNode ot = ot_encoder.encode_node(grid.depth(), corner);
  e.bt = TileNodeInfo{bt.nodes, bt.summary.leaf, bt.summary.value};
  e.ot = TileNodeInfo{ot.nodes, ot.summary.leaf, ot.summary.value};
  // The tile's file: the path from the root to the tile's node (one child each, the tile's value),
  // then the node.
  std::string head = ot_encoder.header(ot.present ? grid.depth() + ot.nodes : 0);
  for (int d = 0; ot.present && d < grid.depth(); ++d) {
    const int bit = 15 - d;
    const unsigned child = ((corner[0] >> bit) & 1u) | (((corner[1] >> bit) & 1u) << 1) |
                           (((corner[2] >> bit) & 1u) << 2);
    char node[5];
    io::detail::store_le(node, ot.summary.value);
    node[4] = static_cast<char>(1u << child);
    head.append(node, 5);
  }
  io::detail::Sha256 h;
  h.update(head);
  h.update(ot.data);
  e.sha256 = h.hex();
  e.bytes = head.size() + ot.data.size();
  io::AtomicFile f((std::filesystem::path(dir) / e.file).string());
  f.write(head);
  f.write(ot.data);
  f.commit();
  return e;
}

/// Cuts `map` into the tiles of `grid` that hold known voxels and writes each into `dir` (one tile
/// copied out of the map at a time); returns their entries in the order of OctoMap's files.
template <class Key>
std::vector<TileEntry> write_tiles_of(
    const OccupancyMap<Key>& map, const std::string& dir, const TileGrid<Key>& grid,
    const std::function<void(std::size_t, std::size_t)>& progress = {}) {
  using layout = BrickLayout<Key>;
  std::map<TileCoord, std::vector<std::uint64_t>> bricks;  // a brick lies in one tile
  for (const auto& b : knnocc::detail::brick_reader(map).bricks()) {
    if (!b.known.any()) continue;
    const auto o = layout::origin_of(b.coord);
    using I = typename Key::index_type;
    bricks[grid.tile_of(Key(static_cast<I>(o[0]), static_cast<I>(o[1]), static_cast<I>(o[2])))]
        .push_back(b.coord);
  }
  std::vector<TileCoord> order;
  for (const auto& kv : bricks) order.push_back(kv.first);
  grid.morton_order(order);
  std::vector<TileEntry> out;
  for (std::size_t i = 0; i < order.size(); ++i) {
    OccupancyMap<Key> tile(map.resolution(), map.params());
    knnocc::detail::BrickWriter<Key> w(tile);
    for (const std::uint64_t c : bricks[order[i]]) w.copy_brick_from(map, c);
    out.push_back(write_tile(dir, grid, order[i], tile));
    if (progress) progress(i + 1, order.size());
  }
  return out;
}

/// Reads tile `e` of the tile set in `dir` (index `ix`) into a map of the run's key width,
/// checking its size, checksum, resolution and that its voxels lie inside the tile.
/// `as_octomap_keys`: the tile's voxels at the OctoMap keys of its file (shift 0, a 16-bit map:
/// merging into one OctoMap file), rather than at the run's keys.
template <class Key>
OccupancyMap<Key> read_tile(const std::string& dir, const TileSetIndex& ix, const TileEntry& e,
                            std::size_t memory_limit = 0, bool as_octomap_keys = false) {
  const std::string path = (std::filesystem::path(dir) / e.file).string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw io::Error(path, "missing: the tile set's index lists it");
  const io::detail::FileBuffer buf = io::detail::read_file(path);
  if (buf.size() != e.bytes)
    throw io::Error(path, "is " + std::to_string(buf.size()) + " bytes, the index says " +
                              std::to_string(e.bytes) + ": the tile set is damaged");
  io::detail::Sha256 h;
  h.update(buf.data(), buf.size());
  if (h.hex() != e.sha256)
    throw io::Error(path, "sha256 does not match the index: the tile set is damaged");
  const io::detail::OctreeHeader head =
      io::detail::parse_octree_header(path, buf.data(), buf.size());
  if (head.binary || head.id != "OcTree")
    throw io::Error(path, "a tile must be an OcTree .ot file");
  // OctoMap's header holds the resolution as std::ostream prints it (6 digits).
  const std::string res_text = io::detail::format_resolution(ix.resolution);
  if (head.resolution != std::strtod(res_text.c_str(), nullptr))
    throw io::Error(path, "resolution " + io::detail::round_trip_text(head.resolution) +
                              " differs from the tile set's " + res_text);
  io::OctreeReadOptions options;
  options.params = ix.params.occupancy;
  options.memory_limit = memory_limit;
  options.max_voxels = static_cast<std::uint64_t>(ix.tile_edge()) *
                       static_cast<std::uint64_t>(ix.tile_edge()) *
                       static_cast<std::uint64_t>(ix.tile_edge());
  const std::array<std::int64_t, 3> shift =
      as_octomap_keys ? std::array<std::int64_t, 3>{0, 0, 0} : e.shift;
  OccupancyMap<Key> map = io::read_octree_bytes<Key>(path, buf, options, shift);
  KeyBounds<Key> b;
  for (std::size_t a = 0; a < 3; ++a) {
    using I = typename Key::index_type;
    b.lo[static_cast<int>(a)] = static_cast<I>(e.keys[a] - e.shift[a] + shift[a]);
    b.hi[static_cast<int>(a)] = static_cast<I>(e.keys[a + 3] - e.shift[a] + shift[a]);
  }
  std::uint64_t outside = 0, occupied = 0, free = 0;
  map.for_each_voxel([&](const Key& k, float v) {
    outside += !b.contains(k);
    (map.is_occupied(v) ? occupied : free) += 1;
  });
  if (outside > 0)
    throw io::Error(path, std::to_string(outside) + " voxels lie outside the tile's keys");
  if (occupied != e.occupied || free != e.free)
    throw io::Error(path, "holds " + std::to_string(occupied) + " occupied and " +
                              std::to_string(free) + " free voxels, the index says " +
                              std::to_string(e.occupied) + " and " + std::to_string(e.free));
  return map;
}

/// Throws io::Error naming the tile's file unless `map` (tile `e` as read_tile reads it, at the
/// run's keys) encodes to the .bt and .ot node counts and summaries the index holds for it: what
/// merging relies on besides the checks of read_tile.
template <class Key>
void check_tile_nodes(const std::string& dir, const TileSetIndex& ix, const TileEntry& e,
                      const OccupancyMap<Key>& map) {
  const std::array<std::uint32_t, 3> corner = detail::tile_corner(e);
  const io::detail::OctreeNode bt =
      io::detail::OctreeEncoder<false, false, Key>(map, "", {}, e.shift)
          .encode_node(ix.tile_depth, corner, false);
  const io::detail::OctreeNode ot =
      io::detail::OctreeEncoder<true, false, Key>(map, "", {}, e.shift)
          .encode_node(ix.tile_depth, corner, false);
  const auto same = [](const io::detail::OctreeNode& n, const TileNodeInfo& i) {
    return n.nodes == i.nodes && n.summary.leaf == i.leaf &&
           std::memcmp(&n.summary.value, &i.value, sizeof(float)) == 0;
  };
  if (!same(bt, e.bt) || !same(ot, e.ot))
    throw io::Error((std::filesystem::path(dir) / e.file).string(),
                    "its tree does not match the index's summary of it: the tile set is damaged");
}

}  // namespace knnocc::tiles
