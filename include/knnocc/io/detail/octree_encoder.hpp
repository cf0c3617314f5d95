// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// OctreeEncoder: OctoMap's node stream for a map, .bt, .ot or ColorOcTree .ot, as OctoMap's own
// writer emits it (the rules are in io/octomap_tree.hpp's file comment), for a whole file or for
// one node encoded apart (the tiles of a tile set, merged as a stream).

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "../../core/key.hpp"
#include "../../core/rgb.hpp"
#include "../../map/detail/brick_access.hpp"
#include "../../map/occupancy_map.hpp"
#include "../error.hpp"
#include "bytes.hpp"
#include "file_text.hpp"
#include "octree_format.hpp"

namespace knnocc::io::detail {

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

}  // namespace knnocc::io::detail
