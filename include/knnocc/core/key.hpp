// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Voxel keys: one unsigned index per axis at the finest level of a tree of depth Bits.
//
// OcKey (16 bits) is OctoMap's OcTreeKey: index = floor(c / r) + 32768, so a map spans
// [-32768 r, 32768 r) per axis (±3.2 km at 0.1 m). WideKey (21 bits) spans ±104 km at 0.1 m.
// Any Bits in [4, 21] works; three indices pack into one 64-bit word (see pack()).

#include <array>
#include <cstdint>
#include <functional>
#include <type_traits>

namespace knnocc {

template <int Bits>
struct BasicKey {
  static_assert(Bits >= 4 && Bits <= 21, "knnocc::BasicKey: Bits must be in [4, 21]");
  using index_type = std::conditional_t<(Bits <= 16), std::uint16_t, std::uint32_t>;

  static constexpr int depth = Bits;  ///< tree depth (leaves at depth Bits)
  static constexpr std::int64_t center = std::int64_t{1} << (Bits - 1);  ///< index of coordinate 0
  static constexpr std::int64_t extent = std::int64_t{1} << Bits;        ///< indices per axis

  std::array<index_type, 3> k{};

  constexpr BasicKey() = default;
  constexpr BasicKey(index_type x, index_type y, index_type z) : k{x, y, z} {}

  constexpr index_type& operator[](int i) { return k[static_cast<std::size_t>(i)]; }
  constexpr index_type operator[](int i) const { return k[static_cast<std::size_t>(i)]; }

  /// The three indices in one word: x in the high bits, then y, then z. Unique per key.
  constexpr std::uint64_t pack() const {
    return (std::uint64_t{k[0]} << (2 * Bits)) | (std::uint64_t{k[1]} << Bits) |
           std::uint64_t{k[2]};
  }
  static constexpr BasicKey unpack(std::uint64_t w) {
    constexpr std::uint64_t mask = (std::uint64_t{1} << Bits) - 1;
    return BasicKey(static_cast<index_type>((w >> (2 * Bits)) & mask),
                    static_cast<index_type>((w >> Bits) & mask), static_cast<index_type>(w & mask));
  }

  friend constexpr bool operator==(const BasicKey& a, const BasicKey& b) { return a.k == b.k; }
  friend constexpr bool operator!=(const BasicKey& a, const BasicKey& b) { return a.k != b.k; }
  /// Lexicographic x, y, z: the order of --out-voxels files.
  friend constexpr bool operator<(const BasicKey& a, const BasicKey& b) { return a.k < b.k; }
};

/// `k` moved by (dx, dy, dz) voxels, into `out`; false (`out` unspecified) when that leaves the
/// key range (a neighbour across the map's edge).
template <int Bits>
constexpr bool shifted_key(const BasicKey<Bits>& k, int dx, int dy, int dz, BasicKey<Bits>& out) {
  const int d[3] = {dx, dy, dz};
  for (int a = 0; a < 3; ++a) {
    const std::int64_t c = std::int64_t{k[a]} + d[a];
    if (c < 0 || c >= BasicKey<Bits>::extent) return false;
    out[a] = static_cast<typename BasicKey<Bits>::index_type>(c);
  }
  return true;
}

using OcKey = BasicKey<16>;    ///< OctoMap-compatible key (OcTreeKey)
using WideKey = BasicKey<21>;  ///< wide key for maps beyond ±3.2 km at 0.1 m

/// The keys with lo[a] <= k[a] <= hi[a] on every axis: a box of voxels, e.g. one tile of a map
/// (tiles/tile_grid.hpp) to which an integrator restricts its updates.
template <class Key>
struct KeyBounds {
  Key lo, hi;

  constexpr bool contains(const Key& k) const {
    return k[0] >= lo[0] && k[0] <= hi[0] && k[1] >= lo[1] && k[1] <= hi[1] && k[2] >= lo[2] &&
           k[2] <= hi[2];
  }
  friend constexpr bool operator==(const KeyBounds& a, const KeyBounds& b) {
    return a.lo == b.lo && a.hi == b.hi;
  }
};

template <class T>
struct is_key : std::false_type {};
template <int Bits>
struct is_key<BasicKey<Bits>> : std::true_type {};
template <class T>
inline constexpr bool is_key_v = is_key<T>::value;

/// Hash for std containers; a 64-bit finaliser so neighbouring keys spread over buckets.
struct KeyHash {
  template <int Bits>
  std::size_t operator()(const BasicKey<Bits>& key) const noexcept {
    std::uint64_t h = key.pack();
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    return static_cast<std::size_t>(h);
  }
};

}  // namespace knnocc
