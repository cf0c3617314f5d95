// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// OctoMap's tree files, read into and written from an OccupancyMap<OcKey>, without liboctomap.
//
//   .bt  "binary" tree: 2 bits per child (unknown / free / occupied / has children); what
//        octovis, octomap_server and OctoMap's tools exchange.
//   .ot  full tree: float log-odds per node plus an 8-bit child mask.
//
// Writing builds OctoMap's octree on the fly from the map's finest voxels (bricks in Morton
// order, the bottom three levels inside each brick) with exactly the nodes OctoMap's own writer
// would emit:
//   .bt  writeBinary(): every voxel reduced to occupied/free (toMaxLikelihood), then pruned, so
//        a node whose 8 children are leaves of one class becomes a leaf (the root never does).
//   .ot  write() of a tree built by insertion: pruned where 8 children are leaves with exactly
//        equal log-odds; an inner node stores the max of its children.
// The bytes equal liboctomap's for the same map (tests/test_octomap_tree.cpp compares them).
//
// Reading expands each leaf into finest voxels: .bt free leaves get clamp_min, occupied leaves
// clamp_max (as liboctomap's reader); .ot leaves keep their log-odds, clamped into the map's
// [clamp_min, clamp_max]; inner values of .ot files are not needed (the map recomputes them as
// the max of the leaves). Leaves at coarse depths (pruned space) become whole bricks stored
// compacted, and OctreeReadOptions::max_voxels bounds how many finest voxels a file may claim,
// so a 20-byte file with a leaf the size of the world is an error, not an allocation.
// ColorOcTree and OcTreeStamped .ot files are read too; read_octree_colors() also returns a
// ColorOcTree's colours: those of its occupied leaves, every finest voxel of a leaf taking the
// leaf's colour, but not ColorOcTree's "no colour" white, nor the colours of free leaves (knnocc
// colours occupied voxels only; OctreeColors counts them so a caller can say they were dropped).
//
// ColorOcTree .ot (write_color_ot): OctoMap's ColorOcTree::write, a float log-odds then r, g, b
// bytes per node (ColorOcTreeNode::writeData), for a map plus a colour per voxel. Occupied
// voxels get their colour; free voxels and occupied ones without a colour get ColorOcTree's
// "no colour" white (255, 255, 255). Inner nodes get the integer mean of their children's
// colours other than white (getAverageChildColor). ColorOcTree prunes 8 equal leaves whatever
// their colours and gives the parent their mean; here they are pruned only when their colours
// are equal too, so that every voxel's colour reads back exactly.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "../core/key.hpp"
#include "../core/rgb.hpp"
#include "../map/detail/brick_access.hpp"
#include "../map/occupancy_map.hpp"
#include "atomic_file.hpp"
#include "detail/bytes.hpp"
#include "detail/file_text.hpp"
#include "detail/octree_encoder.hpp"
#include "detail/octree_format.hpp"
#include "error.hpp"

namespace knnocc::io {

struct OctreeReadOptions {
  OccupancyParams params{};  ///< clamping and threshold of the map that is built
  /// Largest number of finest-level voxels the file's leaves may cover (pruned leaves at
  /// coarse depths cover up to 8^15 each); more is an io::Error.
  std::uint64_t max_voxels = std::uint64_t{1} << 31;
  /// Memory limit of the map that is built (OccupancyMap::set_memory_limit; 0: none). A file
  /// whose leaves surely need more (every 512 voxels take at least a brick record and an index
  /// slot) is an io::Error before the map is made.
  std::size_t memory_limit = 0;
};

/// What a .bt/.ot file holds, from one validating pass (no map is built).
struct OctreeInfo {
  bool binary = false;  ///< .bt (true) or .ot
  std::string id;       ///< tree type from the header, e.g. OcTree
  double resolution = 0.0;
  std::uint64_t nodes = 0;
  std::uint64_t occupied_leaves = 0, free_leaves = 0;
  std::uint64_t occupied_voxels = 0, free_voxels = 0;  ///< finest-level voxels the leaves cover
  int min_leaf_depth = 0, max_leaf_depth = 0;          ///< 0 when there are no leaves
  double min[3] = {0, 0, 0}, max[3] = {0, 0, 0};       ///< box of the leaves (metres)
  std::string note;  ///< a "# knnocc <note>" header comment's note (see encode_bt), or empty
};

namespace detail {

// Bytes each .ot node carries between its float and its child mask, by tree type.
inline std::size_t octree_node_extra(const std::string& path, const OctreeHeader& h) {
  if (h.id == "OcTree") return 0;
  if (h.id == "OcTreeStamped") return 0;  // its time stamps are not written
  if (h.id == "ColorOcTree") return 3;    // r, g, b
  throw Error(path, "unsupported OctoMap tree type '" + h.id +
                        "' (supported: OcTree, ColorOcTree, OcTreeStamped)");
}

inline std::uint64_t voxels_in_node(int depth) {
  return std::uint64_t{1} << (3 * (kOctreeDepth - depth));
}

// Runs the walker over a whole file; leaf(depth, corner, value, occupied_code).
template <class Leaf>
void walk_octree_file(const std::string& path, const FileBuffer& buf, const OctreeHeader& h,
                      Leaf&& leaf) {
  const std::size_t extra = octree_node_extra(path, h);
  OctreeWalker walker(path, h, reinterpret_cast<const unsigned char*>(buf.data()) + h.data_offset,
                      buf.size() - h.data_offset, extra);
  walker.run(leaf);
}

// Writes one leaf of a read tree into the map: whole bricks (compacted) for leaves at depth 13
// or coarser, single voxels below. The map's key of OctoMap key k is k + shift.
template <class Key>
void put_octree_leaf(OccupancyMap<Key>& map, int d, const NodeCorner& c, float value,
                     const std::array<std::int64_t, 3>& shift) {
  using layout = BrickLayout<Key>;
  using I = typename Key::index_type;
  const OccupancyParams& p = map.params();
  const float v = std::min(std::max(value, p.clamp_min), p.clamp_max);
  const std::uint32_t span = std::uint32_t{1} << (kOctreeDepth - d);
  std::int64_t k0[3];
  for (int a = 0; a < 3; ++a) k0[a] = std::int64_t{c.k[a]} + shift[a];
  if (span >= static_cast<std::uint32_t>(kBrickEdge)) {
    const std::int64_t bricks = span >> kBrickBits;
    const std::int64_t b0[3] = {k0[0] >> kBrickBits, k0[1] >> kBrickBits, k0[2] >> kBrickBits};
    knnocc::detail::BrickWriter<Key> w(map);
    for (std::int64_t x = 0; x < bricks; ++x)
      for (std::int64_t y = 0; y < bricks; ++y)
        for (std::int64_t z = 0; z < bricks; ++z) {
          auto& b = w.brick_at(w.brick_slot(layout::pack_brick(b0[0] + x, b0[1] + y, b0[2] + z)));
          w.fill_brick(b, v);
        }
    return;
  }
  for (std::uint32_t x = 0; x < span; ++x)
    for (std::uint32_t y = 0; y < span; ++y)
      for (std::uint32_t z = 0; z < span; ++z)
        map.set(
            Key(static_cast<I>(k0[0] + x), static_cast<I>(k0[1] + y), static_cast<I>(k0[2] + z)),
            v);
}

}  // namespace detail

/// Header and leaf statistics of a .bt/.ot file; throws io::Error when the file is malformed.
/// `params` decides which .ot leaves count as occupied.
inline OctreeInfo inspect_octree(const std::string& path, const OccupancyParams& params = {}) {
  const detail::FileBuffer buf = detail::read_file(path);
  const detail::OctreeHeader h = detail::parse_octree_header(path, buf.data(), buf.size());
  OctreeInfo info;
  info.min_leaf_depth = detail::kOctreeDepth + 1;
  std::uint32_t lo[3] = {~0u, ~0u, ~0u}, hi[3] = {0, 0, 0};  // key box, hi exclusive
  detail::walk_octree_file(
      path, buf, h, [&](int d, const detail::NodeCorner& c, float v, bool occupied_code) {
        for (int a = 0; a < 3; ++a) {
          lo[a] = std::min(lo[a], c.k[a]);
          hi[a] = std::max(hi[a], c.k[a] + (std::uint32_t{1} << (detail::kOctreeDepth - d)));
        }
        const bool occ = h.binary ? occupied_code : v >= params.occupancy_threshold;
        (occ ? info.occupied_leaves : info.free_leaves) += 1;
        (occ ? info.occupied_voxels : info.free_voxels) += detail::voxels_in_node(d);
        info.min_leaf_depth = std::min(info.min_leaf_depth, d);
        info.max_leaf_depth = std::max(info.max_leaf_depth, d);
      });
  info.binary = h.binary;
  info.id = h.id;
  info.note = h.note;
  info.resolution = h.resolution;
  info.nodes = h.size;
  if (info.occupied_leaves + info.free_leaves == 0) {
    info.min_leaf_depth = 0;
    return info;
  }
  for (int a = 0; a < 3; ++a) {
    info.min[a] = (static_cast<double>(lo[a]) - 32768.0) * h.resolution;
    info.max[a] = (static_cast<double>(hi[a]) - 32768.0) * h.resolution;
  }
  return info;
}

template <class Key>
OccupancyMap<Key> read_octree_bytes(const std::string& path, const detail::FileBuffer& buf,
                                    const OctreeReadOptions& options,
                                    const std::array<std::int64_t, 3>& shift);

/// Reads a .bt or .ot file (told apart by its first line) into a new map of keys `Key`, the
/// file's OctoMap key k becoming the map's key k + shift (a tile of a wide map,
/// tiles/tile_files.hpp; shift 0 for OcKey). The file's leaves must land in the key range.
template <class Key>
OccupancyMap<Key> read_octree_shifted(const std::string& path, const OctreeReadOptions& options,
                                      const std::array<std::int64_t, 3>& shift) {
  return read_octree_bytes<Key>(path, detail::read_file(path), options, shift);
}

/// The same from the file's bytes, read already (`path` names it in errors).
template <class Key>
OccupancyMap<Key> read_octree_bytes(const std::string& path, const detail::FileBuffer& buf,
                                    const OctreeReadOptions& options,
                                    const std::array<std::int64_t, 3>& shift) {
  // Pass 1 validates everything and sizes the expansion before anything is allocated.
  const detail::OctreeHeader h = detail::parse_octree_header(path, buf.data(), buf.size());
  std::uint64_t voxels = 0;
  detail::walk_octree_file(path, buf, h, [&](int d, const detail::NodeCorner& c, float, bool) {
    voxels += detail::voxels_in_node(d);
    if (voxels > options.max_voxels) {
      throw Error(path, "the tree's leaves cover more than " + std::to_string(options.max_voxels) +
                            " finest-level voxels (OctreeReadOptions::max_voxels); a leaf at "
                            "depth " +
                            std::to_string(d) + " alone covers " +
                            std::to_string(detail::voxels_in_node(d)));
    }
    for (int a = 0; a < 3; ++a) {
      const std::int64_t k = std::int64_t{c.k[a]} + shift[a];
      if (k < 0 || k + (std::int64_t{1} << (detail::kOctreeDepth - d)) > Key::extent)
        throw Error(path, "a leaf lies outside the key range of a " + std::to_string(Key::depth) +
                              "-bit map at this file's offset");
    }
  });
  using Brick = typename OccupancyMap<Key>::Brick;
  const std::uint64_t bricks = (voxels + kBrickVoxels - 1) / kBrickVoxels;
  const double at_least = static_cast<double>(bricks) * (sizeof(Brick) + 24);
  if (options.memory_limit && at_least > static_cast<double>(options.memory_limit)) {
    throw Error(path, "the tree's " + std::to_string(voxels) + " voxels need at least " +
                          std::to_string(static_cast<std::uint64_t>(at_least / 1e6)) +
                          " MB as a map, more than its memory limit of " +
                          std::to_string(options.memory_limit / 1000000) + " MB");
  }
  OccupancyMap<Key> map(h.resolution, options.params);
  map.set_memory_limit(options.memory_limit);
  const OccupancyParams& p = map.params();
  detail::walk_octree_file(path, buf, h,
                           [&](int d, const detail::NodeCorner& c, float v, bool occupied_code) {
                             if (h.binary) v = occupied_code ? p.clamp_max : p.clamp_min;
                             detail::put_octree_leaf(map, d, c, v, shift);
                           });
  return map;
}

/// Reads a .bt or .ot file (told apart by its first line) into a new map.
inline OccupancyMap<OcKey> read_octree(const std::string& path,
                                       const OctreeReadOptions& options = {}) {
  return read_octree_shifted<OcKey>(path, options, {0, 0, 0});
}

/// The colours of a ColorOcTree file (see the file comment), read by read_octree_colors().
struct OctreeColors {
  bool color_tree = false;                    ///< the file is a ColorOcTree
  std::vector<std::pair<OcKey, Rgb>> voxels;  ///< occupied finest voxels that have a colour
  std::uint64_t free_colored_voxels = 0;      ///< free finest voxels with a colour (not kept)
};

/// Reads a .bt or .ot file as read_octree() does, and a ColorOcTree's colours into `colors`
/// (cleared first; an OcTree, OcTreeStamped or .bt file has none).
inline OccupancyMap<OcKey> read_octree_colors(const std::string& path,
                                              const OctreeReadOptions& options,
                                              OctreeColors& colors) {
  const detail::FileBuffer buf = detail::read_file(path);
  OccupancyMap<OcKey> map = read_octree_bytes<OcKey>(path, buf, options, {0, 0, 0});
  colors = OctreeColors{};
  const detail::OctreeHeader h = detail::parse_octree_header(path, buf.data(), buf.size());
  colors.color_tree = !h.binary && h.id == "ColorOcTree";
  if (!colors.color_tree) return map;
  const OccupancyParams& p = map.params();
  detail::walk_octree_file(
      path, buf, h,
      [&](int d, const detail::NodeCorner& c, float v, bool, const unsigned char* rgb) {
        const Rgb color{rgb[0], rgb[1], rgb[2]};
        if (color == Rgb{255, 255, 255}) return;  // ColorOcTree: no colour
        const bool occupied = map.is_occupied(std::min(std::max(v, p.clamp_min), p.clamp_max));
        const std::uint32_t span = std::uint32_t{1} << (detail::kOctreeDepth - d);
        if (!occupied) {
          colors.free_colored_voxels += std::uint64_t{span} * span * span;
          return;
        }
        for (std::uint32_t x = 0; x < span; ++x)
          for (std::uint32_t y = 0; y < span; ++y)
            for (std::uint32_t z = 0; z < span; ++z)
              colors.voxels.push_back({OcKey(static_cast<OcKey::index_type>(c.k[0] + x),
                                             static_cast<OcKey::index_type>(c.k[1] + y),
                                             static_cast<OcKey::index_type>(c.k[2] + z)),
                                       color});
      });
  return map;
}

/// The bytes of `map` as liboctomap's OcTree::writeBinary would write them (.bt). A `note` adds
/// the header comment "# knnocc <note>" (what wrote the file; OctoMap's readers skip comments,
/// inspect_octree() returns it as OctreeInfo::note); without one the bytes are liboctomap's.
inline std::string encode_bt(const OccupancyMap<OcKey>& map, const std::string& note = {}) {
  return detail::OctreeEncoder<false>(map, note).encode();
}
/// The bytes of `map` as liboctomap's OcTree::write would write them (.ot); `note` as encode_bt.
inline std::string encode_ot(const OccupancyMap<OcKey>& map, const std::string& note = {}) {
  return detail::OctreeEncoder<true>(map, note).encode();
}

inline void write_bt(const std::string& path, const OccupancyMap<OcKey>& map,
                     const std::string& note = {}) {
  AtomicFile out(path);
  out.write(encode_bt(map, note));
  out.commit();
}
inline void write_ot(const std::string& path, const OccupancyMap<OcKey>& map,
                     const std::string& note = {}) {
  AtomicFile out(path);
  out.write(encode_ot(map, note));
  out.commit();
}

/// The bytes of `map` as a ColorOcTree .ot file, with color_of(key) for each occupied voxel
/// (see the file comment); liboctomap reads it as a ColorOcTree. `note` as encode_bt.
inline std::string encode_color_ot(const OccupancyMap<OcKey>& map, VoxelColorOf<OcKey> color_of,
                                   const std::string& note = {}) {
  return detail::OctreeEncoder<true, true>(map, note, std::move(color_of)).encode();
}
inline void write_color_ot(const std::string& path, const OccupancyMap<OcKey>& map,
                           VoxelColorOf<OcKey> color_of, const std::string& note = {}) {
  AtomicFile out(path);
  out.write(encode_color_ot(map, std::move(color_of), note));
  out.commit();
}

}  // namespace knnocc::io
