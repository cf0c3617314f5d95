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
// ColorOcTree and OcTreeStamped .ot files are read too (colours ignored).
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

inline std::string format_resolution(double res) {  // std::ostream's default, as OctoMap writes
  char text[64];
  std::snprintf(text, sizeof text, "%g", res);
  return text;
}

/// A node of an OctoMap tree as its parent sees it.
struct OctreeNodeSummary {
  bool leaf = false;         ///< the subtree collapsed into one leaf
  float value = 0.0f;        ///< the leaf's value, or the max of the children
  Rgb color{255, 255, 255};  ///< ColorOcTree: the leaf's colour, or the mean of the children's
};

/// One node of an OctoMap tree encoded apart (OctreeEncoder::encode_node): its bytes in the
/// file's pre-order, as the whole file has them, and what its parent needs.
struct OctreeNode {
  bool present = false;     ///< false: the node holds no known voxel (no bytes, no node)
  std::string data;         ///< the node's subtree, pre-order (.bt: empty for a leaf)
  std::uint64_t nodes = 0;  ///< nodes of the subtree, the node itself included
  OctreeNodeSummary summary;
};

// Builds OctoMap's node stream for a map (Full: .ot, else .bt; Color: ColorOcTree .ot); see the
// file comment. A map of keys wider than OctoMap's (WideKey) is written with `shift`: its key
// k + shift is OctoMap's key k (each a multiple of 8, so bricks stay whole); its voxels must then
// all lie within OctoMap's key range (check_fits_octree).
template <bool Full, bool Color = false, class Key = OcKey>
class OctreeEncoder {
  static_assert(Full || !Color, "ColorOcTree files are full (.ot) trees");

 public:
  using Map = OccupancyMap<Key>;
  using Brick = typename Map::Brick;
  using Shift = std::array<std::int64_t, 3>;
  static constexpr std::size_t kNodeBytes = Full ? (Color ? 8 : 5) : 2;

  /// `note`: the text of a "# knnocc <note>" header comment (made printable), or empty;
  /// `color_of`: the voxels' colours (ColorOcTree files only).
  OctreeEncoder(const Map& map, const std::string& note, VoxelColorOf<Key> color_of = {},
                Shift shift = {0, 0, 0})
      : map_(map), note_(note), color_of_(std::move(color_of)), shift_(shift) {}

  /// The whole file: header and node stream.
  std::string encode() {
    gather(0, {0, 0, 0});
    data_.clear();
    nodes_ = 0;
    OctreeNodeSummary root;
    if (!order_.empty()) tree_node(0, 0, order_.size(), root);
    std::string out = header(nodes_);
    out += data_;
    return out;
  }

  /// The header of a file of `nodes` nodes (what encode() writes before the node stream).
  std::string header(std::uint64_t nodes) const {
    return std::string(Full ? kOtFirstLine : kBtFirstLine) + "\n" + kOctreeComment +
           (note_.empty() ? "" : kNotePrefix + printable(note_) + "\n") + "id " +
           (Color ? "ColorOcTree" : "OcTree") + "\nsize " + std::to_string(nodes) + "\nres " +
           format_resolution(map_.resolution()) + "\ndata\n";
  }

  /// The node of depth d (<= 13) whose lowest OctoMap key is `corner`, as the whole file holds it
  /// (the voxels of the map outside the node are not looked at). `bytes` false: its summary and
  /// node count only (OctreeNode::data stays empty).
  OctreeNode encode_node(int d, const std::array<std::uint32_t, 3>& corner, bool bytes = true) {
    OctreeNode out;
    gather(d, corner);
    data_.clear();
    nodes_ = 0;
    count_only_ = !bytes;
    if (!order_.empty()) out.present = tree_node(d, 0, order_.size(), out.summary);
    count_only_ = false;
    out.data = std::move(data_);
    data_.clear();
    out.nodes = nodes_;
    return out;
  }

  /// OctoMap's writers' rule for an inner node of depth d whose present children (bit i of
  /// `present`) are `kids`: the node collapses into a leaf (true, `out` the leaf) when it is not
  /// the root and its 8 children are leaves of one value (.ot; one colour too in a ColorOcTree)
  /// or of one class (.bt); else (false) `out` is its summary and `head` receives its
  /// kNodeBytes bytes.
  bool combine(int d, const OctreeNodeSummary (&kids)[8], unsigned present, OctreeNodeSummary& out,
               char* head) const {
    bool collapse = d > 0 && present == 0xffu;
    for (int i = 0; collapse && i < 8; ++i) collapse = kids[i].leaf && same(kids[i], kids[0]);
    if (collapse) {
      out = kids[0];
      out.leaf = true;
      return true;
    }
    float max = -std::numeric_limits<float>::infinity();
    unsigned codes = 0;
    for (int i = 0; i < 8; ++i) {
      if (!((present >> i) & 1u)) continue;
      max = std::max(max, kids[i].value);
      const unsigned code = !kids[i].leaf ? 3u : occupied(kids[i].value) ? 2u : 1u;
      codes |= code << (2 * i);
    }
    out.leaf = false;
    out.value = Full ? max : 0.0f;  // a .bt holds no values: its inner nodes' are unused
    if (Color) out.color = mean_color(kids, present);
    if constexpr (Full) {
      node_data(head, out, present);
    } else {
      head[0] = static_cast<char>(codes & 0xffu);
      head[1] = static_cast<char>(codes >> 8);
    }
    return false;
  }

  /// The bytes a leaf writes (.ot: its value and an empty child mask; .bt: none, its parent's
  /// code tells it).
  static std::string leaf_bytes(const OctreeNodeSummary& s) {
    if constexpr (!Full) {
      (void)s;
      return {};
    } else {
      char bytes[kNodeBytes];
      node_data(bytes, s, 0);
      return std::string(bytes, kNodeBytes);
    }
  }

 private:
  static constexpr int kBrickDepth = kOctreeDepth - kBrickBits;  // 13: a brick is one node

  struct Entry {
    std::uint64_t morton;
    std::size_t index;
  };
  static constexpr Rgb kNoColor{255, 255, 255};  // ColorOcTreeNode's default: "not set"

  // The known bricks inside the depth-d node at OctoMap key `corner`, in Morton order.
  void gather(int d, const std::array<std::uint32_t, 3>& corner) {
    const auto& bricks = knnocc::detail::brick_reader(map_).bricks();
    const std::int64_t span = std::int64_t{1} << (kOctreeDepth - d);
    order_.clear();
    order_.reserve(bricks.size());
    for (std::size_t i = 0; i < bricks.size(); ++i) {
      if (!bricks[i].known.any()) continue;
      const auto o = BrickLayout<Key>::origin_of(bricks[i].coord);
      std::int64_t k[3];
      bool inside = true;
      for (int a = 0; a < 3; ++a) {
        k[a] = static_cast<std::int64_t>(o[a]) - shift_[a];
        inside = inside && k[a] >= corner[a] && k[a] < corner[a] + span;
      }
      if (!inside) continue;
      order_.push_back({morton(static_cast<std::uint32_t>(k[0] >> kBrickBits),
                               static_cast<std::uint32_t>(k[1] >> kBrickBits),
                               static_cast<std::uint32_t>(k[2] >> kBrickBits)),
                        i});
    }
    std::sort(order_.begin(), order_.end(),
              [](const Entry& a, const Entry& b) { return a.morton < b.morton; });
  }

  // Child index bits x -> 1, y -> 2, z -> 4 at every level: a pre-order walk visits bricks in
  // increasing Morton order.
  static std::uint64_t morton(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    std::uint64_t m = 0;
    for (int j = 0; j < kBrickDepth; ++j) {
      m |= static_cast<std::uint64_t>(((x >> j) & 1u) | (((y >> j) & 1u) << 1) |
                                      (((z >> j) & 1u) << 2))
           << (3 * j);
    }
    return m;
  }

  bool occupied(float v) const { return map_.is_occupied(v); }
  bool same(const OctreeNodeSummary& a, const OctreeNodeSummary& b) const {
    if (!Full) return occupied(a.value) == occupied(b.value);
    return a.value == b.value && (!Color || a.color == b.color);
  }

  // Voxel i of brick b as a leaf: its value and, in a ColorOcTree, its colour when occupied.
  OctreeNodeSummary voxel(const Brick& b, int i) const {
    OctreeNodeSummary s;
    s.leaf = true;
    s.value = b.get(i);
    if constexpr (Color) {
      if (occupied(s.value))
        s.color = color_of_(BrickLayout<Key>::key_of(b.coord, i)).value_or(kNoColor);
    }
    return s;
  }

  // Writes a node's data with an empty child mask: a leaf.
  void leaf(const OctreeNodeSummary& s, OctreeNodeSummary& out) {
    ++nodes_;
    if constexpr (Full) {
      if (!count_only_) {
        char bytes[kNodeBytes];
        node_data(bytes, s, 0);
        data_.append(bytes, kNodeBytes);
      }
    }
    out = s;
    out.leaf = true;
  }

  static void node_data(char* at, const OctreeNodeSummary& s, unsigned mask) {
    store_le(at, s.value);
    if constexpr (Color) {
      at[4] = static_cast<char>(s.color.r);
      at[5] = static_cast<char>(s.color.g);
      at[6] = static_cast<char>(s.color.b);
    }
    at[kNodeBytes - 1] = static_cast<char>(mask);
  }

  // ColorOcTreeNode::getAverageChildColor: the integer mean of the children's colours other than
  // white; white when there are none.
  static Rgb mean_color(const OctreeNodeSummary (&kids)[8], unsigned present) {
    unsigned sum[3] = {0, 0, 0}, n = 0;
    for (int i = 0; i < 8; ++i) {
      if (!((present >> i) & 1u) || kids[i].color == kNoColor) continue;
      sum[0] += kids[i].color.r;
      sum[1] += kids[i].color.g;
      sum[2] += kids[i].color.b;
      ++n;
    }
    if (n == 0) return kNoColor;
    return Rgb{static_cast<std::uint8_t>(sum[0] / n), static_cast<std::uint8_t>(sum[1] / n),
               static_cast<std::uint8_t>(sum[2] / n)};
  }

  // A node whose children child(i, summary) -> present emit themselves in order 0..7. With no
  // child present nothing is emitted; with 8 equal leaves (OctoMap's pruning) the children's
  // bytes are dropped and the node becomes a leaf.
  template <class Child>
  bool node(int d, Child&& child, OctreeNodeSummary& out) {
    const std::size_t start = data_.size();
    const std::uint64_t nodes_before = nodes_;
    ++nodes_;
    if (!count_only_) data_.append(kNodeBytes, '\0');  // the node's bytes, written below
    OctreeNodeSummary kids[8];
    unsigned present = 0;
    for (int i = 0; i < 8; ++i) {
      if (child(i, kids[i])) present |= 1u << i;
    }
    if (present == 0) {
      data_.resize(start);
      nodes_ = nodes_before;
      return false;
    }
    OctreeNodeSummary combined;
    char head[kNodeBytes];
    if (combine(d, kids, present, combined, head)) {
      data_.resize(start);
      nodes_ = nodes_before;
      leaf(combined, out);
      return true;
    }
    if (!count_only_) std::memcpy(&data_[start], head, kNodeBytes);
    out = combined;
    return true;
  }

  // Depth d < 13 over the bricks order_[lo, hi), which all lie in this node.
  bool tree_node(int d, std::size_t lo, std::size_t hi, OctreeNodeSummary& out) {
    if (d == kBrickDepth)
      return brick_node(knnocc::detail::brick_reader(map_).bricks()[order_[lo].index], out);
    const int shift = 3 * (kBrickDepth - 1 - d);
    std::size_t cur = lo;
    return node(
        d,
        [&](int i, OctreeNodeSummary& s) {
          std::size_t end = cur;
          while (end < hi && static_cast<int>((order_[end].morton >> shift) & 7u) == i) ++end;
          if (end == cur) return false;
          const std::size_t begin = cur;
          cur = end;
          return tree_node(d + 1, begin, end, s);
        },
        out);
  }

  bool brick_node(const Brick& b, OctreeNodeSummary& out) {
    if constexpr (!Full) {
      if (count_only_) return brick_bt_count(b, out);
    }
    if (b.known.count() == kBrickVoxels) {  // a whole known brick may be a single leaf
      const OctreeNodeSummary first = voxel(b, 0);
      bool uniform = true;
      for (int i = 1; uniform && i < kBrickVoxels; ++i) uniform = same(voxel(b, i), first);
      if (uniform) {
        leaf(first, out);
        return true;
      }
    }
    return brick_sub(b, kBrickDepth, 0, 0, 0, out);
  }

  // .bt, counting only: what brick_sub would give for the brick (its summary, its nodes added to
  // nodes_), from its known and occupied voxels' masks, a level at a time: a node is absent
  // without known voxels, a leaf when its 8 children are leaves of one class (its value that of
  // child 0), else an inner node (its value unused in a .bt).
  bool brick_bt_count(const Brick& b, OctreeNodeSummary& out) {
    if (!b.known.any()) return false;
    VoxelMask occ;
    b.known.for_each([&](int i) {
      if (occupied(b.get(i))) occ.set(i);
    });
    struct Node {
      int state = 0;  // 0 absent, 1 free leaf, 2 occupied leaf, 3 inner
      std::uint64_t nodes = 0;
      float value = 0.0f;
    };
    Node level[64];  // the current level's nodes, x fastest: n^3 of them
    // Depth 15: blocks of 2x2x2 voxels (voxel index x + 8 y + 64 z).
    for (int bz = 0; bz < 4; ++bz)
      for (int by = 0; by < 4; ++by)
        for (int bx = 0; bx < 4; ++bx) {
          int known = 0, full = 0;
          for (int c = 0; c < 8; ++c) {
            const int i =
                (2 * bx + (c & 1)) + 8 * (2 * by + ((c >> 1) & 1)) + 64 * (2 * bz + ((c >> 2) & 1));
            known += b.known.test(i);
            full += occ.test(i);
          }
          Node& n = level[bx + 4 * by + 16 * bz];
          const int first = 2 * bx + 16 * by + 128 * bz;
          if (known == 0) {
            n = Node{};
          } else if (known == 8 && (full == 0 || full == 8)) {
            n = Node{full ? 2 : 1, 1, b.get(first)};
          } else {
            n = Node{3, std::uint64_t(1 + known), 0.0f};
          }
        }
    // Depths 14 and 13: 8 children each, from the level below.
    for (int edge = 2; edge >= 1; edge /= 2) {
      Node up[8];
      for (int z = 0; z < edge; ++z)
        for (int y = 0; y < edge; ++y)
          for (int x = 0; x < edge; ++x) {
            Node n;
            int present = 0, leaves[3] = {0, 0, 0};
            float first = 0.0f;
            std::uint64_t below = 0;
            for (int c = 0; c < 8; ++c) {
              const int cx = 2 * x + (c & 1), cy = 2 * y + ((c >> 1) & 1), cz = 2 * z + (c >> 2);
              const Node& k = level[cx + 2 * edge * cy + 4 * edge * edge * cz];
              if (k.state == 0) continue;
              ++present;
              below += k.nodes;
              if (k.state < 3) ++leaves[k.state];
              if (c == 0) first = k.value;
            }
            if (present == 0) {
              n = Node{};
            } else if (present == 8 && (leaves[1] == 8 || leaves[2] == 8)) {
              n = Node{leaves[2] == 8 ? 2 : 1, 1, first};
            } else {
              n = Node{3, 1 + below, 0.0f};
            }
            up[x + edge * y + edge * edge * z] = n;
          }
      for (int i = 0; i < edge * edge * edge; ++i) level[i] = up[i];
    }
    const Node& brick = level[0];
    nodes_ += brick.nodes;
    out.leaf = brick.state < 3;
    out.value = brick.value;
    return true;
  }

  bool brick_sub(const Brick& b, int d, int x, int y, int z, OctreeNodeSummary& out) {
    if (d == kOctreeDepth) {
      const int i = x | (y << kBrickBits) | (z << (2 * kBrickBits));
      if (!b.known.test(i)) return false;
      leaf(voxel(b, i), out);
      return true;
    }
    const int half = 1 << (kOctreeDepth - 1 - d);
    return node(
        d,
        [&](int i, OctreeNodeSummary& s) {
          return brick_sub(b, d + 1, x + ((i & 1) ? half : 0), y + ((i & 2) ? half : 0),
                           z + ((i & 4) ? half : 0), s);
        },
        out);
  }

  const Map& map_;
  std::string note_;
  VoxelColorOf<Key> color_of_;
  Shift shift_;
  std::vector<Entry> order_;
  std::string data_;
  std::uint64_t nodes_ = 0;
  bool count_only_ = false;  // encode_node(..., bytes = false)
};

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
