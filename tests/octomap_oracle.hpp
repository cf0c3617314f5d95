#pragma once
// liboctomap as the oracle (tests built with KNNOCC_HAVE_OCTOMAP only): its tree's leaves,
// pruned ones included, visited as the finest-level voxels they cover.

#include <cstdint>

#include <knnocc/core/key.hpp>

#include <octomap/OcTree.h>

namespace knnocc::test {

/// Calls f(key, leaf) for every finest-level voxel under every leaf of `tree` (an OcTree or
/// another liboctomap tree, e.g. a ColorOcTree).
template <class Tree, class F>
void for_each_octomap_voxel(const Tree& tree, F&& f) {
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const int span = 1 << (16 - static_cast<int>(it.getDepth()));
    const octomap::OcTreeKey base = it.getIndexKey();
    for (int dx = 0; dx < span; ++dx)
      for (int dy = 0; dy < span; ++dy)
        for (int dz = 0; dz < span; ++dz)
          f(OcKey(static_cast<std::uint16_t>(base[0] + dx),
                  static_cast<std::uint16_t>(base[1] + dy),
                  static_cast<std::uint16_t>(base[2] + dz)),
            *it);
  }
}

}  // namespace knnocc::test
