// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Rgb: an 8-bit colour, as point files (PLY red/green/blue, PCD rgb/rgba) and OctoMap's
// ColorOcTree store it.

#include <cstdint>
#include <functional>
#include <optional>

#include "key.hpp"

namespace knnocc {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;

  friend bool operator==(const Rgb& a, const Rgb& c) {
    return a.r == c.r && a.g == c.g && a.b == c.b;
  }
  friend bool operator!=(const Rgb& a, const Rgb& c) { return !(a == c); }
};

/// The colour of a voxel, or nullopt when it has none: what writers of coloured maps take (e.g.
/// [&](const OcKey& k) { return colors.mean(k); } for a VoxelColors).
template <class Key = OcKey>
using VoxelColorOf = std::function<std::optional<Rgb>(const Key&)>;

}  // namespace knnocc
