// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internals of octomap_tree.hpp: the text header of OctoMap's .bt/.ot files and a validating
// walk over their node streams (see ../shared/docs/octomap-facts.md for the layouts).
//
// The walk never allocates from what a file claims: it visits nodes as it reads them, with a
// recursion depth bounded by the tree depth (16), and reports every leaf as (depth, lowest key,
// value). Every inconsistency (truncation, a finest voxel with children, non-finite values,
// a size line that disagrees with the node count, trailing bytes) is an io::Error.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <type_traits>

#include "../../core/grid.hpp"
#include "../error.hpp"
#include "bytes.hpp"
#include "file_text.hpp"

namespace knnocc::io::detail {

inline constexpr int kOctreeDepth = 16;
inline constexpr const char* kBtFirstLine = "# Octomap OcTree binary file";
inline constexpr const char* kOtFirstLine = "# Octomap OcTree file";
inline constexpr const char* kOctreeComment =
    "# (feel free to add / change comments, but leave the first line as it is!)\n#\n";

struct OctreeHeader {
  bool binary = false;          // .bt (true) or .ot (false), from the first line
  std::string id;               // tree type, e.g. OcTree
  std::uint64_t size = 0;       // node count claimed by the header
  double resolution = 0.0;      // voxel edge
  std::size_t data_offset = 0;  // first byte of the node stream
  std::string note;             // the text after "# knnocc " of such a comment line, or empty
};

/// The comment line a knnocc note is written as (OctoMap's readers skip comment lines).
inline constexpr const char* kNotePrefix = "# knnocc ";

inline OctreeHeader parse_octree_header(const std::string& path, const char* data,
                                        std::size_t size) {
  OctreeHeader h;
  const char* p = data;
  const char* const end = data + size;
  auto next_line = [&](const char*& b, const char*& e) {
    if (p == end) return false;
    const void* nl = std::memchr(p, '\n', static_cast<std::size_t>(end - p));
    b = p;
    e = nl ? static_cast<const char*>(nl) : end;
    p = nl ? e + 1 : end;
    if (e != b && e[-1] == '\r') --e;
    return true;
  };
  const char* b = nullptr;
  const char* e = nullptr;
  auto starts_with = [&](const char* prefix) {
    const std::size_t n = std::strlen(prefix);
    return static_cast<std::size_t>(e - b) >= n && std::memcmp(b, prefix, n) == 0;
  };
  if (!next_line(b, e) || !(starts_with(kBtFirstLine) || starts_with(kOtFirstLine))) {
    throw Error(path, "not an OctoMap file (the first line is not '" + std::string(kBtFirstLine) +
                          "' or '" + kOtFirstLine + "')");
  }
  h.binary = starts_with(kBtFirstLine);
  bool have_size = false, have_res = false, have_id = false;
  std::size_t line = 1;
  while (true) {
    if (!next_line(b, e)) throw Error(path, "OctoMap header has no 'data' line");
    check_header_length(path, "OctoMap", static_cast<std::size_t>(e - data));
    ++line;
    while (b != e && is_blank(*b)) ++b;
    const std::size_t prefix = std::strlen(kNotePrefix);
    if (static_cast<std::size_t>(e - b) > prefix && std::memcmp(b, kNotePrefix, prefix) == 0)
      h.note.assign(b + prefix, e);
    if (b == e || *b == '#') continue;
    const char* k = b;
    while (b != e && !is_blank(*b)) ++b;
    const std::string key(k, b);
    while (b != e && is_blank(*b)) ++b;
    const char* ve = e;
    while (ve != b && is_blank(ve[-1])) --ve;
    const std::string value(b, ve);
    const std::string at = "header line " + std::to_string(line) + ": ";
    if (key == "data") break;
    if (key == "id") {
      if (value.empty()) throw Error(path, at + "'id' names no tree type");
      h.id = value;
      have_id = true;
    } else if (key == "size") {
      if (!parse_int_token(b, ve, h.size)) {
        throw Error(path, at + "invalid node count " + quote_token(b, ve));
      }
      have_size = true;
    } else if (key == "res") {
      if (!parse_real_token(b, ve, h.resolution) || !(h.resolution > 0.0) ||
          !std::isfinite(h.resolution) || !std::isfinite(1.0 / h.resolution)) {
        throw Error(path, at + "invalid resolution " + quote_token(b, ve));
      }
      if (h.resolution < Grid<OcKey>::min_resolution ||
          h.resolution > Grid<OcKey>::max_resolution) {
        const bool small = h.resolution < Grid<OcKey>::min_resolution;
        char text[160];
        std::snprintf(text, sizeof text,
                      small ? "resolution %g is below %g m, the finest a map takes"
                            : "resolution %g is above %g m: the key range (+-32768 voxels) "
                              "would not fit a float",
                      h.resolution,
                      small ? Grid<OcKey>::min_resolution : Grid<OcKey>::max_resolution);
        throw Error(path, at + text);
      }
      have_res = true;
    } else {
      throw Error(path, at + "unknown header keyword '" + key + "'");
    }
  }
  if (!have_id) throw Error(path, "OctoMap header has no 'id' line");
  if (!have_size) throw Error(path, "OctoMap header has no 'size' line");
  if (!have_res) throw Error(path, "OctoMap header has no 'res' line");
  h.data_offset = static_cast<std::size_t>(p - data);
  return h;
}

// Lowest finest-level key corner of a node; children of a depth-d node are 2^(15-d) apart.
struct NodeCorner {
  std::uint32_t k[3];
  NodeCorner child(int i, int d) const {
    const std::uint32_t half = std::uint32_t{1} << (kOctreeDepth - 1 - d);
    return NodeCorner{
        {k[0] + ((i & 1) ? half : 0), k[1] + ((i & 2) ? half : 0), k[2] + ((i & 4) ? half : 0)}};
  }
};

// Walks a node stream. leaf(depth, corner, value, occupied_code): for .bt the value is unused
// and occupied_code tells the class; for .ot the value is the stored log-odds. A .ot leaf
// callable with a fifth argument gets the node's extra bytes there (a ColorOcTree's r, g, b).
class OctreeWalker {
 public:
  OctreeWalker(const std::string& path, const OctreeHeader& h, const unsigned char* data,
               std::size_t size, std::size_t node_extra_bytes)
      : path_(path), h_(h), p_(data), end_(data + size), extra_(node_extra_bytes) {}

  template <class Leaf>
  std::uint64_t run(Leaf&& leaf) {
    nodes_ = 0;
    const unsigned char* const begin = p_;
    if (h_.size != 0) {
      if (h_.binary) {
        count_node();
        bt_node(0, NodeCorner{{0, 0, 0}}, leaf);
      } else {
        ot_node(0, NodeCorner{{0, 0, 0}}, leaf);
      }
    }
    if (nodes_ != h_.size) {
      throw Error(path_, "header says size " + std::to_string(h_.size) + " but the tree has " +
                             std::to_string(nodes_) + " nodes");
    }
    if (p_ != end_) {
      throw Error(path_, std::to_string(end_ - p_) +
                             " unexpected bytes after the tree (which ends " +
                             std::to_string(p_ - begin) + " bytes into the data)");
    }
    return nodes_;
  }

 private:
  [[noreturn]] void truncated() const {
    throw Error(path_, "file truncated: the tree data ends inside node " + std::to_string(nodes_) +
                           " (header says " + std::to_string(h_.size) + " nodes)");
  }
  void count_node() {
    ++nodes_;
    // A lying size line must not let a crafted file walk on for long: stop at the claim.
    if (nodes_ > h_.size) {
      throw Error(path_,
                  "the tree has more nodes than the header's size " + std::to_string(h_.size));
    }
  }

  // A leaf callable with a fifth argument also gets the node's extra bytes (none in a .bt).
  template <class Leaf>
  static void call_leaf(Leaf& leaf, int d, const NodeCorner& c, float v, bool occupied_code,
                        const unsigned char* extra) {
    if constexpr (std::is_invocable_v<Leaf&, int, NodeCorner, float, bool, const unsigned char*>)
      leaf(d, c, v, occupied_code, extra);
    else
      leaf(d, c, v, occupied_code);
  }

  template <class Leaf>
  void bt_node(int d, NodeCorner c, Leaf& leaf) {
    if (end_ - p_ < 2) truncated();
    const unsigned codes = static_cast<unsigned>(p_[0]) | (static_cast<unsigned>(p_[1]) << 8);
    p_ += 2;
    for (int i = 0; i < 8; ++i) {
      const unsigned code = (codes >> (2 * i)) & 3u;
      if (code == 0 || code == 3) continue;
      count_node();
      call_leaf(leaf, d + 1, c.child(i, d), 0.0f, code == 2, nullptr);
    }
    for (int i = 0; i < 8; ++i) {
      if (((codes >> (2 * i)) & 3u) != 3u) continue;
      count_node();
      if (d + 1 == kOctreeDepth) {
        throw Error(path_, "node " + std::to_string(nodes_) +
                               ": a finest-level voxel (depth 16) is marked as having children");
      }
      bt_node(d + 1, c.child(i, d), leaf);
    }
  }

  template <class Leaf>
  void ot_node(int d, NodeCorner c, Leaf& leaf) {
    count_node();
    if (static_cast<std::size_t>(end_ - p_) < 5 + extra_) truncated();
    const float v = load_le<float>(p_);
    const unsigned mask = p_[4 + extra_];
    p_ += 5 + extra_;
    if (!std::isfinite(v)) {
      throw Error(path_, "node " + std::to_string(nodes_) + " has a non-finite log-odds value");
    }
    if (mask == 0) {
      call_leaf(leaf, d, c, v, false, p_ - 1 - extra_);
      return;
    }
    if (d == kOctreeDepth) {
      throw Error(path_, "node " + std::to_string(nodes_) +
                             ": a finest-level voxel (depth 16) is marked as having children");
    }
    for (int i = 0; i < 8; ++i) {
      if ((mask >> i) & 1u) ot_node(d + 1, c.child(i, d), leaf);
    }
  }

  const std::string& path_;
  const OctreeHeader& h_;
  const unsigned char* p_;
  const unsigned char* end_;
  std::size_t extra_;
  std::uint64_t nodes_ = 0;
};

}  // namespace knnocc::io::detail
