// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ValuePool: the 512-float value arrays of a map's bricks, carved from a few large slabs.
//
// One allocation per brick made a fresh map pay malloc's bookkeeping and a 4 KB page fault per two
// bricks. The pool hands out arrays in creation order from slabs that grow geometrically (64 KB
// to 512 KB, then 2 MB each), so small maps stay small and large maps are mapped 2 MB at a time
// (detail/huge_pages.hpp). Arrays given back (bricks the .bt reader fills whole) are reused
// first; compaction builds a new, exactly sized pool instead (OccupancyMap::compact). The pool owns
// the memory: arrays stay valid until clear() or the pool's destruction, and a moved pool keeps
// them at the same addresses.

#include <cstddef>
#include <memory>
#include <new>
#include <vector>

#include "../core/config.hpp"
#include "../core/detail/huge_pages.hpp"
#include "brick.hpp"

namespace knnocc {

class ValuePool {
 public:
  static constexpr std::size_t kArrayBytes = kBrickVoxels * sizeof(float);

  ValuePool() = default;
  ValuePool(ValuePool&&) noexcept = default;
  ValuePool& operator=(ValuePool&&) noexcept = default;

  /// An array of kBrickVoxels floats, uninitialised.
  float* allocate() {
    if (!free_.empty()) {
      float* p = free_.back();
      free_.pop_back();
      return p;
    }
    if (slabs_.empty() || used_ == slabs_.back().arrays) add_slab(next_slab_arrays());
    return slabs_.back().data + kBrickVoxels * used_++;
  }

  /// Gives an array back for reuse (it must come from this pool).
  void release(float* p) {
    if (p) free_.push_back(p);
  }

  /// On a pool without slabs: the first slab holds exactly n arrays (compaction packs into one).
  /// Does nothing on a pool that has slabs already.
  void reserve(std::size_t n) {
    if (n > 0 && slabs_.empty()) add_slab(n);
  }

  /// Releases every array and slab.
  void clear() {
    std::vector<Slab>().swap(slabs_);
    std::vector<float*>().swap(free_);
    used_ = 0;
    slab_bytes_ = 0;
  }

  /// Bytes reserved by the slabs (arrays in use, given back, and not yet handed out).
  std::size_t memory_usage() const {
    return free_.capacity() * sizeof(float*) + slabs_.capacity() * sizeof(Slab) + slab_bytes_;
  }
  /// How much memory_usage() grows when the next array is allocated (0 when one is at hand).
  std::size_t growth_bytes() const {
    if (!free_.empty() || (!slabs_.empty() && used_ < slabs_.back().arrays)) return 0;
    return detail::big_size(next_slab_arrays() * kArrayBytes) + sizeof(Slab);
  }

 private:
  static constexpr std::size_t kFirstSlabArrays = (std::size_t{64} << 10) / kArrayBytes;  // 32
  static constexpr std::size_t kMaxSlabArrays = detail::kHugePage / kArrayBytes;          // 1024

  struct Slab {
    std::unique_ptr<float[], detail::BigFree> owner;
    float* data;
    std::size_t arrays;
  };

  std::size_t next_slab_arrays() const {
    std::size_t arrays = kFirstSlabArrays;
    for (std::size_t i = 0; i < slabs_.size() && arrays < kMaxSlabArrays; ++i) arrays *= 2;
    // A slab that would take huge pages takes a whole one.
    return arrays * kArrayBytes >= detail::kHugeMin ? kMaxSlabArrays : arrays;
  }

  void add_slab(std::size_t arrays) {
    const std::size_t bytes = arrays * kArrayBytes;
    auto* data = static_cast<float*>(detail::big_alloc(bytes));
    if (!data) detail::out_of_memory();
    slabs_.push_back(Slab{std::unique_ptr<float[], detail::BigFree>(data, detail::BigFree{bytes}),
                          data, arrays});
    used_ = 0;
    slab_bytes_ += detail::big_size(bytes);
  }

  std::vector<Slab> slabs_;
  std::size_t used_ = 0;        // arrays handed out from the last slab
  std::vector<float*> free_;    // arrays given back
  std::size_t slab_bytes_ = 0;  // big_size() of every slab
};

}  // namespace knnocc
