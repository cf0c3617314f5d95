// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Brick geometry: the map stores voxels in 8x8x8 bricks, hashed by brick coordinate.
//
// A brick is the bottom three levels of the octree in one block: leaf index bits 0-2 of each axis
// address the voxel inside the brick (x -> bits 0-2, y -> 3-5, z -> 6-8 of the local index), the
// remaining high bits address the brick. VoxelMask is one bit per voxel of a brick.

#include <array>
#include <cstdint>

#include "../core/key.hpp"

namespace knnocc {

namespace detail {

/// Bits set in x. __builtin_popcountll is a library call unless the target has POPCNT (baseline
/// x86-64 does not), so portable SWAR code is used there.
inline int popcount64(std::uint64_t x) {
#if defined(__POPCNT__) || defined(__aarch64__)
  return __builtin_popcountll(x);
#else
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  return static_cast<int>((x * 0x0101010101010101ULL) >> 56);
#endif
}

}  // namespace detail

inline constexpr int kBrickBits = 3;                ///< log2 of the brick edge
inline constexpr int kBrickEdge = 1 << kBrickBits;  ///< voxels per brick edge (8)
inline constexpr int kBrickVoxels = kBrickEdge * kBrickEdge * kBrickEdge;  ///< 512

/// One bit per voxel of a brick.
struct VoxelMask {
  std::array<std::uint64_t, kBrickVoxels / 64> w{};

  bool test(int i) const { return (w[static_cast<unsigned>(i) >> 6] >> (i & 63)) & 1u; }
  void set(int i) { w[static_cast<unsigned>(i) >> 6] |= std::uint64_t{1} << (i & 63); }
  void reset(int i) { w[static_cast<unsigned>(i) >> 6] &= ~(std::uint64_t{1} << (i & 63)); }
  void clear() { w.fill(0); }
  bool any() const {
    for (auto x : w)
      if (x) return true;
    return false;
  }
  int count() const {
    int n = 0;
    for (auto x : w) n += detail::popcount64(x);
    return n;
  }
  /// Calls f(local_index) for every set bit, in increasing order.
  template <class F>
  void for_each(F&& f) const {
    for (int j = 0; j < static_cast<int>(w.size()); ++j)
      for (std::uint64_t x = w[static_cast<std::size_t>(j)]; x; x &= x - 1)
        f(j * 64 + __builtin_ctzll(x));
  }
};

/// Brick coordinate and voxel position of keys of type Key.
template <class Key>
struct BrickLayout {
  static constexpr int coord_bits = Key::depth - kBrickBits;
  static constexpr std::uint64_t coord_mask = (std::uint64_t{1} << coord_bits) - 1;

  /// Packed brick coordinate of the brick holding `key` (never FlatIndex::kEmpty).
  static std::uint64_t brick_of(const Key& key) {
    return (std::uint64_t{key[0]} >> kBrickBits << (2 * coord_bits)) |
           (std::uint64_t{key[1]} >> kBrickBits << coord_bits) |
           (std::uint64_t{key[2]} >> kBrickBits);
  }
  static int local_of(const Key& key) {
    constexpr unsigned m = kBrickEdge - 1;
    return static_cast<int>((key[0] & m) | ((key[1] & m) << kBrickBits) |
                            ((key[2] & m) << (2 * kBrickBits)));
  }
  /// Inverse of (brick_of, local_of).
  static Key key_of(std::uint64_t brick, int local) {
    using I = typename Key::index_type;
    const auto l = static_cast<unsigned>(local);
    constexpr unsigned m = kBrickEdge - 1;
    return Key(
        static_cast<I>((((brick >> (2 * coord_bits)) & coord_mask) << kBrickBits) | (l & m)),
        static_cast<I>((((brick >> coord_bits) & coord_mask) << kBrickBits) |
                       ((l >> kBrickBits) & m)),
        static_cast<I>(((brick & coord_mask) << kBrickBits) | ((l >> (2 * kBrickBits)) & m)));
  }
  /// First leaf key (lowest corner) of a brick, per axis.
  static std::array<std::int64_t, 3> origin_of(std::uint64_t brick) {
    return {static_cast<std::int64_t>(((brick >> (2 * coord_bits)) & coord_mask) << kBrickBits),
            static_cast<std::int64_t>(((brick >> coord_bits) & coord_mask) << kBrickBits),
            static_cast<std::int64_t>((brick & coord_mask) << kBrickBits)};
  }
  static std::uint64_t pack_brick(std::int64_t bx, std::int64_t by, std::int64_t bz) {
    return (static_cast<std::uint64_t>(bx) << (2 * coord_bits)) |
           (static_cast<std::uint64_t>(by) << coord_bits) | static_cast<std::uint64_t>(bz);
  }
};

}  // namespace knnocc
